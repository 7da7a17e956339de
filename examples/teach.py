# Servos 1..4 go limp, then replay poses; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# Teach by hand, then play back: the joints go limp, you pose the robot by hand and press
# Enter (or board.py's button, if it has one) to capture each pose (q and Enter to end), the
# poses are saved to teach.json, and the robot plays them back. On the simulator no one can
# pose it, so the example poses it.
#
# On a board it runs at the board's REPL, where your Enter reaches it (`mpremote run`
# forwards no keys: input() would wait for ever, the arm limp). With board.py on the board:
#   mpremote mip install lib/busservo_motion.json   # once: the driver, the motion layer
#   mpremote cp examples/teach.py :teach.py
#   mpremote repl              then type: import teach      (Ctrl-] leaves mpremote)
# To teach again: Ctrl-D (a soft reset), then import teach. With a board.py that offers
# button() (boards/esp32.py: BOOT; boards/rp2.py: BOOTSEL) a press captures each pose and a
# 1 s press ends, with no keys at all: `mpremote run examples/teach.py` works then too.
#   sh boards/unix.sh examples/teach.py     # unix port, simulated controller
import time

import busservo_board
import busservo_motion as bm

# Set True once you hold the arm (limp, it falls) and servos 1..4 can turn freely.
I_HAVE_CHECKED_MY_ROBOT = False
DPS: int | None = 30  # on a real robot no joint turns faster (degrees a second)

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check
    DPS = None  # nor to hurt: full speed

PATH = "teach.json"
MS = 1000  # to go from one pose to the next, in playback
# Your calibration (robot.json, if you saved one), or these joints.
arm = busservo_board.robot(bus, busservo_board.joints(dps=DPS))
print("the servos are at", bus.read_positions([arm.joints[n].servo_id for n in arm.names]))
print("this lets them go limp, captures the poses you make by hand, then plays them back")
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit
# On the simulator, these stand for the hands that pose the robot.
HANDS = [
    {"base": 0, "shoulder": 0, "elbow": 0, "claw": 0},
    {"base": 45, "shoulder": 30, "elbow": -20, "claw": 40},
    {"base": -45, "shoulder": 60, "elbow": -60, "claw": 10},
]


try:  # a board.py may offer a button(): a machine.Pin that reads 0 while pressed
    import board

    button = getattr(board, "button", None)
except ImportError:
    button = None


def ask(n):
    """True once pose n is made: Enter at the console (q, Enter: done), or a press of
    board.py's button (a long press, 1 s: done). False to end (or with no console)."""
    if button:
        pin = button()
        print("pose %d: move the robot, then press the button (hold it 1 s: done)" % n)
        while pin.value():
            time.sleep_ms(10)
        pressed = time.ticks_ms()
        while not pin.value():
            time.sleep_ms(10)
        return time.ticks_diff(time.ticks_ms(), pressed) < 1000
    try:
        line = input("pose %d: move the robot, then Enter (q, Enter: done) " % n)
    except EOFError:  # no console: nothing more to capture
        return False
    return line.strip().lower() != "q"


sequence = bm.Sequence()
arm.limp()
print("the joints are limp: pose the robot by hand")
for n in range(1, 21):
    if busservo_board.simulated:
        if n > len(HANDS):
            break
        hands = {name: d for name, d in HANDS[n - 1].items() if name in arm.joints}
        arm.move(hands, ms=0)  # the simulator's "hands"
        arm.limp()
    elif not ask(n):
        break
    pose = arm.capture()
    sequence.append(pose, MS)
    print("captured pose %d: %s" % (n, pose))

if not len(sequence):
    print("no pose captured")
else:
    sequence.save(PATH)
    print("saved %d poses to %s" % (len(sequence), PATH))
    sequence = bm.Sequence.load(PATH)
    first = DPS or 60  # (the joints' own DPS would hold over a faster home)
    print("playing back (to the first pose at %d degrees/s first)" % first)
    time.sleep_ms(arm.home(sequence.steps[0][0], dps=first))
    player = sequence.play(arm)
    while not player.done:
        if player.step():
            print("  pose %d of %d" % (player.index + 1, len(sequence)))
        time.sleep_ms(10)
    print("played back", len(sequence), "poses")
