# Unload servos 1 to 6: they lose holding torque and turn freely by hand. The
# next move gives it back. Handy for posing a robot by hand, then reading it.
#   mpremote run examples/unload.py
import time

import busservo

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

bus = busservo.BusServo(uart())
bus.unload([1, 2, 3, 4, 5, 6])
print("pose the servos by hand for 3 s...")
time.sleep_ms(3000)
print("posed at", bus.read_positions([1, 2, 3, 4, 5, 6]))
