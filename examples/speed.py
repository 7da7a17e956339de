# Action group speed, in percent: group 1 at 50 %, then every group at 300 %.
# The controller forgets this at power-off.
#   mpremote run examples/speed.py
import busservo

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

bus = busservo.BusServo(uart())
bus.set_group_speed(1, 50)
bus.set_group_speed(busservo.ALL_GROUPS, 300)
print("all action groups at 300 %")
