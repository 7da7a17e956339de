# Lets servos 1..6 go limp (an arm falls!); real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# Unloaded servos lose their holding torque and turn freely by hand; the next move gives it back.
# Handy for posing a robot by hand, then reading the pose.
#   mpremote mip install package.json   # once: the driver
#   mpremote run examples/unload.py
import time

import busservo_board

# Set True once you hold your robot up (or it rests safely): limp servos hold up nothing.
I_HAVE_CHECKED_MY_ROBOT = False

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check

SERVOS = [1, 2, 3, 4, 5, 6]
print("servos 1..6 are at", sorted(bus.read_positions(SERVOS).items()))
print("this lets them go limp: whatever they hold up falls")
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit

bus.unload(SERVOS)
print("pose the servos by hand for 3 s...")
time.sleep_ms(3000)
print("posed at", sorted(bus.read_positions(SERVOS).items()))
