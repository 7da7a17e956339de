# Move six servos together: one command, one shared time.
#   mpremote run examples/move_many.py
import time

import busservo

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

bus = busservo.BusServo(uart())
bus.move_many([(1, 200), (2, 350), (3, 500), (4, 650), (5, 800), (6, 950)], 1200)
time.sleep_ms(1200)
print(bus.read_positions([1, 2, 3, 4, 5, 6]))
bus.move_many({1: 500, 2: 500, 3: 500, 4: 500, 5: 500, 6: 500}, 1200)  # a dict works too
