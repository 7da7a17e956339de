# Plays a sequence on servos 1..4; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# Play a sequence back: from teach.json (written by examples/teach.py) if there is one, else
# a wave made here. Once with player.step() from a loop, then looping at twice the speed until
# stopped, then with asyncio (await player). estop() stops everything and lets the joints go.
#   mpremote mip install lib/busservo_motion.json   # once: the driver, the motion layer
#   mpremote run examples/playback.py
import asyncio
import time

import busservo_board
import busservo_motion as bm

# Set True once you have checked that servos 1..4 can turn freely, with nothing in their way.
I_HAVE_CHECKED_MY_ROBOT = False
DPS: int | None = 30  # on a real robot no joint turns faster (degrees a second)

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check
    DPS = None  # nor to hurt: full speed

# Your calibration (robot.json, if you saved one), or these joints.
arm = busservo_board.robot(bus, busservo_board.joints(dps=DPS))
print("the servos are at", bus.read_positions([arm.joints[n].servo_id for n in arm.names]))
print("this plays teach.json (or a wave) on them, at most 30 degrees/s on a real robot")
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit
try:
    sequence = bm.Sequence.load("teach.json")
    print("teach.json: %d poses" % len(sequence))
except OSError:  # no such file
    # Every joint to 20 degrees, to -20, then back to 0 (within its limits: clamped).
    sequence = bm.Sequence(
        [({name: degrees for name in arm.names}, 500) for degrees in (0, 20, -20, 0)]
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
