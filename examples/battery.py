# Read the controller's battery voltage, blocking, then without blocking.
#   mpremote run examples/battery.py
import time

import busservo

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

bus = busservo.BusServo(uart())
print("battery: %d mV" % bus.read_battery())

bus.request_battery()  # the answer comes through poll(): nothing waits for it
while bus.poll() != busservo.CMD_GET_BATTERY_VOLTAGE:
    time.sleep_ms(1)  # a control loop would do its work here
print("battery: %.2f V" % (bus.battery / 1000))
