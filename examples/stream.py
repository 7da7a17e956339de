# Streams a sine wave to servos 1..6; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# A sine wave to six joints at the wire's pace: the loop sets new targets every 10 ms
# with stream(), which only stores them; step() sends the latest in one frame whenever the wire
# is free, so the loop never waits and no stale target is queued. Prints the updates a second.
#   mpremote mip install lib/busservo_motion.json   # once: the driver, the motion layer
#   mpremote run examples/stream.py
import math
import time

import busservo_board
import busservo_motion as bm

# Set True once you have checked that servos 1..6 can turn 60 degrees each way, freely.
I_HAVE_CHECKED_MY_ROBOT = False
DPS: int | None = 30  # on a real robot no joint turns faster (degrees a second)

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check
    DPS = None  # nor to hurt: full speed

SECONDS = 3
# Your calibration (robot.json, if you saved one), or six joints of servos 1..6.
arm = busservo_board.robot(
    bus, {"j%d" % i: bm.Joint(i, limits=(-60, 60), dps=DPS) for i in range(1, 7)}
)
print("the servos are at", bus.read_positions([arm.joints[n].servo_id for n in arm.names]))
print("this homes them to 0 degrees at 30 degrees/s, then streams a sine wave for 3 s")
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit
n = len(arm.names)
limit = 9600 / 10 / (3 * n + 7)  # a frame of n servos is 3n + 7 bytes of 10 bits
print("homing: to 0 degrees at 30 degrees/s")
time.sleep_ms(arm.home(dps=30))

targets = {name: 0.0 for name in arm.names}
start = time.ticks_ms()
second = start
counted = arm.updates
while time.ticks_diff(time.ticks_ms(), start) < SECONDS * 1000:
    t = time.ticks_diff(time.ticks_ms(), start) / 1000
    for k, name in enumerate(arm.names):
        targets[name] = 45 * math.sin(2 * math.pi * 0.5 * t + k)  # 0.5 Hz, a joint apart
    arm.stream(targets)
    arm.step()  # sends only when the wire is (nearly) free: never waits
    while bus.poll() is not None:  # frames from the controller, if any
        pass
    if time.ticks_diff(time.ticks_ms(), second) >= 1000:
        second = time.ticks_add(second, 1000)
        print(
            "%d updates/s (the wire's limit for %d servos: %.1f)"
            % (arm.updates - counted, n, limit)
        )
        counted = arm.updates
        print("  ", {name: round(targets[name], 1) for name in arm.names})
    time.sleep_ms(10)
print("%d updates in %d s, each frame %d ms on the wire" % (arm.updates, SECONDS, arm.frame_ms))
