# Moves nothing: reads the controller's battery voltage, without blocking, then blocking.
#   mpremote run examples/battery.py
import time

import busservo

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError as e:
    if "'board'" not in str(e):
        raise  # board.py is there but fails to import: its error, not the simulator
    from busservo_sim import uart

    print("no board.py found: using the simulated controller, nothing real moves")

port = uart()
print("talking to", port)
bus = busservo.BusServo(port)
bus.request_battery()  # the answer comes through poll(): nothing waits for it
for _ in range(100):  # about 100 ms at most
    if bus.poll() == busservo.CMD_GET_BATTERY_VOLTAGE:
        break
    time.sleep_ms(1)  # a control loop would do its work here
if bus.battery is None:  # None until an answer has come
    print("no answer within 100 ms: examples/check_wiring.py tells why")
else:
    print("battery: %.2f V" % (bus.battery / 1000))

print("battery: %d mV" % bus.read_battery())  # waits for the answer; OSError if none comes
