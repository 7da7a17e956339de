# Teach by hand, then play back: the joints go limp, you pose the robot by hand and press
# Enter to capture each pose (q and Enter to end), the poses are saved to teach.json, and
# the robot plays them back. On the simulator no one can pose it, so the example poses it.
#   mpremote run examples/teach.py          (at the board's REPL: input() needs a console)
import time

import busservo
import busservo_motion as bm

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py

    SIMULATED = False
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

    SIMULATED = True

PATH = "teach.json"
MS = 1000  # to go from one pose to the next, in playback
bus = busservo.BusServo(uart())
arm = bm.Robot(
    bus,
    {
        "base": bm.Joint(1),
        "shoulder": bm.Joint(2, limits=(-90, 90)),
        "elbow": bm.Joint(3, limits=(-90, 90)),
        "claw": bm.Joint(4, limits=(0, 60)),
    },
)
# On the simulator, these stand for the hands that pose the robot.
HANDS = [
    {"base": 0, "shoulder": 0, "elbow": 0, "claw": 0},
    {"base": 45, "shoulder": 30, "elbow": -20, "claw": 40},
    {"base": -45, "shoulder": 60, "elbow": -60, "claw": 10},
]


def ask(n):
    """The line typed for pose n, or None to end (q, or no console)."""
    try:
        line = input("pose %d: move the robot, then Enter (q, Enter: done) " % n)
    except EOFError:  # no console: nothing more to capture
        return None
    return None if line.strip().lower() == "q" else line


sequence = bm.Sequence()
arm.limp()
print("the joints are limp: pose the robot by hand")
for n in range(1, 21):
    if SIMULATED:
        if n > len(HANDS):
            break
        arm.move(HANDS[n - 1], ms=0)  # the simulator's "hands"
        arm.limp()
    elif ask(n) is None:
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
    print("playing back (to the first pose at 60 degrees/s first)")
    time.sleep_ms(arm.home(sequence.steps[0][0], dps=60))
    player = sequence.play(arm)
    while not player.done:
        if player.step():
            print("  pose %d of %d" % (player.index + 1, len(sequence)))
        time.sleep_ms(10)
    print("played back", len(sequence), "poses")
