# Servos 1..4 go limp and lead 7..10; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# A leader arm, limp, moved by hand, drives a follower arm live, both on board.py's bus: the
# leader is your calibration (robot.json) or the demo's arm on servos 1..4, the follower the
# one in follower.json (Robot.save() of the follower's calibration) or the demo's arm on
# servos 7..10. The follower first goes to the leader's pose at 30 degrees/s, then follows it
# at the wire's pace (about 26 cycles a second for 6 servos each); a joint that does not
# answer holds it, by name. It runs for SECONDS and says its rate each second. Two arms on two
# UARTs: give the follower a BusServo of its own, the rest is the same. RECORD = "leader.rec"
# records the leader too, from the same reads (play it back with examples/record.py's
# Recording.load(); it needs busservo_record: mpremote mip install lib/busservo_record.json).
#   mpremote mip install lib/busservo_teleop.json   # once: the driver, motion, teleop
#   mpremote run examples/teleop.py
#   sh boards/unix.sh examples/teleop.py            # unix port, simulated controller
import errno
import time

import busservo_board
import busservo_motion as bm
import busservo_teleop

# Set True once you hold the leader (limp, it falls) and the follower can turn freely.
I_HAVE_CHECKED_MY_ROBOT = False
DPS: int | None = 30  # on a real robot no follower joint turns faster (degrees a second)
SECONDS = 10  # how long it runs (mpremote run forwards no Ctrl-C: it ends by itself)
FOLLOWER = "follower.json"  # the follower's calibration, if you saved one
OFFSET = 6  # without it: the demo's arm on servos 1 + OFFSET.. (7..10)
RECORD: str | None = None  # a file ("leader.rec") to record the leader's reads into, too

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check
    DPS = None  # nor to hurt: full speed
    SECONDS = 2  # no hand moves the simulated leader: the follower holds its pose

leader = busservo_board.robot(bus, busservo_board.joints())
try:
    follower = bm.Robot.load(bus, FOLLOWER, DPS)  # DPS holds over the file's
    print("the follower: the calibration in %s" % FOLLOWER)
except OSError as e:
    if e.args[0] != errno.ENOENT:
        raise
    joints = {}
    for name, joint in busservo_board.joints(dps=DPS).items():
        config = joint.config()
        config["servo_id"] += OFFSET
        joints[name] = bm.Joint(**config)
    follower = bm.Robot(bus, joints)
lids = [leader.joints[n].servo_id for n in leader.names]
fids = [follower.joints[n].servo_id for n in follower.names]
print("the servos are at", bus.read_positions(lids + fids))
print(
    "this lets servos %s go limp and moves servos %s after them, for %d s" % (lids, fids, SECONDS)
)
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit

recorder = None
if RECORD:
    import busservo_record

    names = [n for n in leader.names if n in follower.joints]  # the joints the teleop reads
    recorder = busservo_record.Recorder(leader, names, RECORD, limp=False)
# It warns of calibrations that disagree; with a recorder, it gives it each read of the leader.
try:
    teleop = busservo_teleop.Teleop(leader, follower, dps=30, recorder=recorder)
except ValueError as e:  # the arms' calibrations do not fit together: say how, alone
    print(e)
    raise SystemExit(1)
print("the leader is limp: move it by hand")
start = time.ticks_ms()
second = reads = 0
while second < SECONDS:
    teleop.step()  # never waits for the wire: the loop is yours between steps
    if time.ticks_diff(time.ticks_ms(), start) >= (second + 1) * 1000:
        second += 1
        print(
            "  %d cycles a second, %s"
            % (teleop.reads - reads, "following" if teleop.engaged else "going to its pose")
        )
        reads = teleop.reads
    time.sleep_ms(1)
teleop.stop()
print(
    "done: %d reads of the leader, %d moves of the follower, %d reads timed out"
    % (teleop.reads, teleop.moves, teleop.timeouts)
)
if recorder:
    recording = recorder.stop()
    print("recorded %d samples of the leader into %s" % (len(recording), RECORD))
