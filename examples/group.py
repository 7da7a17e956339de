# Run an action group (downloaded to the controller beforehand), wait for it to
# complete with poll(), then run one forever and stop it.
#   mpremote run examples/group.py
import time

import busservo

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

bus = busservo.BusServo(uart())


def wait_for(want, timeout_ms=10000):
    start = time.ticks_ms()
    while time.ticks_diff(time.ticks_ms(), start) < timeout_ms:
        cmd = bus.poll()  # never blocks: do the rest of your loop here
        if cmd is not None:
            print("frame", cmd, "running:", bus.running, "group:", bus.group, "times:", bus.times)
        if cmd == want:
            return
        time.sleep_ms(5)
    print("gave up waiting")


bus.run_group(1)
wait_for(busservo.CMD_ACTION_GROUP_COMPLETE)
bus.run_group(2, 0)  # 0: forever
wait_for(busservo.CMD_ACTION_GROUP_RUN)
time.sleep_ms(500)
bus.stop_group()
wait_for(busservo.CMD_ACTION_GROUP_STOP)
