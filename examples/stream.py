# Stream a sine wave to six joints at the wire's pace: the loop sets new targets every 10 ms
# with stream(), which only stores them; step() sends the latest in one frame whenever the wire
# is free, so the loop never waits and no stale target is queued. Prints the updates a second.
#   mpremote run examples/stream.py
import math
import time

import busservo
import busservo_motion as bm

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

SECONDS = 3
bus = busservo.BusServo(uart())
arm = bm.Robot(bus, {"j%d" % i: bm.Joint(i, limits=(-60, 60)) for i in range(1, 7)})
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
        print("%d updates/s (the wire's limit for 6 servos: 38.4)" % (arm.updates - counted))
        counted = arm.updates
        print("  ", {name: round(targets[name], 1) for name in arm.names})
    time.sleep_ms(10)
print("%d updates in %d s, each frame %d ms on the wire" % (arm.updates, SECONDS, arm.frame_ms))
