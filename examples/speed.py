# Moves nothing: sets action group 1 to half speed, every other group to 100 %, until power-off.
# Nothing runs until examples/group.py (or your code) starts a group.
#   mpremote mip install package.json   # once: the driver
#   mpremote run examples/speed.py
import busservo
import busservo_board

bus = busservo_board.bus()  # board.py's UART, or the simulated controller

bus.set_group_speed(busservo.ALL_GROUPS, 100)  # every group at its own pace
bus.set_group_speed(1, 50)  # then group 1 at half of it: it takes twice as long
print("action group 1 at 50 %, the others at 100 %, until the controller is switched off")
