# Servos 1..4 go limp, then replay; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# Record an arm moved by hand, then play it back: the joints go limp, every read of them is
# kept with the time it came (about 35 a second for 4 servos at 9600 baud) for SECONDS, the
# recording is saved to demo.rec (8 bytes a sample for 6 joints), and the arm plays it back:
# into its first pose at 30 degrees/s, then at the pace you moved it.
#   mpremote mip install lib/busservo_record.json   # once: the driver, motion, recording
#   mpremote run examples/record.py
#   sh boards/unix.sh examples/record.py            # unix port, simulated controller
import time

import busservo_board
import busservo_record as br

# Set True once you hold the arm (limp, it falls) and servos 1..4 can turn freely.
I_HAVE_CHECKED_MY_ROBOT = False
DPS: int | None = 30  # on a real robot no joint turns faster (degrees a second)
SECONDS = 5  # how long it records (mpremote run forwards no Ctrl-C: it ends by itself)
PATH = "demo.rec"  # "demo.jsonl": JSON lines, for a computer

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check
    DPS = None  # nor to hurt: full speed
    SECONDS = 2  # no hand moves the simulated arm: its samples are all alike

# Your calibration (robot.json, if you saved one), or these joints.
arm = busservo_board.robot(bus, busservo_board.joints(dps=DPS))
print("the servos are at", bus.read_positions([arm.joints[n].servo_id for n in arm.names]))
print("this lets them go limp, records them for %d s, then plays that back" % SECONDS)
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit

recorder = br.Recorder(arm, path=PATH)  # the joints go limp
print("the joints are limp: move the arm by hand for %d s" % SECONDS)
start = time.ticks_ms()
second = 0
while second < SECONDS:
    recorder.step()  # never waits for the wire: the loop is yours between steps
    if time.ticks_diff(time.ticks_ms(), start) >= (second + 1) * 1000:
        second += 1
        print("  %d s: %d samples" % (second, recorder.samples))  # each second, the last too
    time.sleep_ms(1)
recording = recorder.stop()
print(
    "saved %s: %d samples over %d ms, %d reads missed"
    % (PATH, len(recording), recording.duration_ms, recorder.missed)
)

recording = br.Recording.load(PATH)
print("playing it back (to its first pose at 30 degrees/s first)")
player = recording.play(arm, speed=1.0)
while not player.done:
    player.step()
    time.sleep_ms(2)
print(
    "played back %d samples (%d moves slowed by a joint's dps)" % (len(recording), player.slowed)
)
