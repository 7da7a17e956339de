# Moves servo 1 to 800, then back to 500; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
#   mpremote mip install package.json   # once: the driver
#   mpremote run examples/move.py
import time

import busservo_board

# Set True once you have checked that servo 1 can turn freely, with nothing in its way.
I_HAVE_CHECKED_MY_ROBOT = False

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check

print("servo 1 is at", bus.read_positions([1])[1])
print("this moves it to 800 over 2 s, then back to 500 over 2 s")
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit

bus.move(1, 800, 2000)  # a first move of 2 s gives you time to see it coming
time.sleep_ms(2000)
print("servo 1 is at", bus.read_positions([1])[1])
bus.move(1, 500, 2000)
time.sleep_ms(2000)
print("and back at", bus.read_positions([1])[1])
