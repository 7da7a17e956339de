# Moves nothing: reads the controller's battery voltage, without blocking, then blocking.
#   mpremote mip install package.json   # once: the driver
#   mpremote run examples/battery.py
import time

import busservo
import busservo_board

bus = busservo_board.bus()  # board.py's UART, or the simulated controller

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
