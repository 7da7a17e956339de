# Plays a sequence on servos 1..4; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# Play a sequence back: from teach.json (written by examples/teach.py) if there is one, else
# a wave made here. Once with player.step() from a loop, then looping at twice the speed until
# stopped, then with asyncio (await player). estop() stops everything and lets the joints go.
#   mpremote run examples/playback.py
import asyncio
import time

import busservo
import busservo_motion as bm

# Set True once you have checked that servos 1..4 can turn freely, with nothing in their way.
I_HAVE_CHECKED_MY_ROBOT = False
DPS: int | None = 30  # on a real robot no joint turns faster (degrees a second)

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError as e:
    if "'board'" not in str(e):
        raise  # board.py is there but fails to import: its error, not the simulator
    from busservo_sim import uart

    print("no board.py found: using the simulated controller, nothing real moves")
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check
    DPS = None  # nor to hurt: full speed

port = uart()
print("talking to", port)
bus = busservo.BusServo(port)
print("the servos are at", bus.read_positions([1, 2, 3, 4]))
print("this plays teach.json (or a wave) on them, at most 30 degrees/s on a real robot")
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit
arm = bm.Robot(
    bus,
    {
        "base": bm.Joint(1, dps=DPS),
        "shoulder": bm.Joint(2, limits=(-90, 90), dps=DPS),
        "elbow": bm.Joint(3, limits=(-90, 90), dps=DPS),
        "claw": bm.Joint(4, limits=(0, 60), dps=DPS),
    },
)
try:
    sequence = bm.Sequence.load("teach.json")
    print("teach.json: %d poses" % len(sequence))
except OSError:  # no such file
    sequence = bm.Sequence(
        [
            ({"base": 0, "shoulder": 20, "elbow": -20, "claw": 0}, 600),
            ({"base": 30, "shoulder": 40, "elbow": -50}, 400),
            ({"base": -30, "claw": 50}, 400),
            ({"base": 0, "shoulder": 20, "elbow": -20, "claw": 0}, 400),
        ]
    )
    print("a wave of %d poses (no teach.json)" % len(sequence))

time.sleep_ms(arm.home(sequence.steps[0][0], dps=30))  # a soft start

start = time.ticks_ms()
player = sequence.play(arm)
while not player.done:  # the loop is yours: do other work between steps
    if player.step():
        print("  pose %d at %d ms" % (player.index + 1, time.ticks_diff(time.ticks_ms(), start)))
    time.sleep_ms(5)
print("played once in %d ms" % time.ticks_diff(time.ticks_ms(), start))

player = sequence.play(arm, speed=2.0, loop=True)
start = time.ticks_ms()
while player.loops < 2:
    player.step()
    time.sleep_ms(5)
player.stop()
print("looped at twice the speed: stopped after %d rounds" % player.loops)


async def main():
    await sequence.play(arm, speed=1.5)  # other tasks run meanwhile
    print("played with asyncio")


asyncio.run(main())
arm.estop()
print("estop: group stopped, joints limp")
