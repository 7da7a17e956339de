# Play a sequence back: from teach.json (written by examples/teach.py) if there is one, else
# a wave made here. Once with player.step() from a loop, then looping at twice the speed until
# stopped, then with asyncio (await player). estop() stops everything and lets the joints go.
#   mpremote run examples/playback.py
import asyncio
import time

import busservo
import busservo_motion as bm

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

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
