# Move one servo: servo 1 to position 800 within 1000 ms, then back to 500.
#   mpremote run examples/move.py
import time

import busservo

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

bus = busservo.BusServo(uart())
bus.move(1, 800, 1000)
time.sleep_ms(1000)
print("servo 1 is at", bus.read_positions([1])[1])
bus.move(1, 500, 1000)
