# Moves servos 1..6 to 200..950 and back; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
#   mpremote mip install package.json   # once: the driver
#   mpremote run examples/move_many.py
import time

import busservo_board

# Set True once you have checked that servos 1..6 can turn freely, with nothing in their way.
I_HAVE_CHECKED_MY_ROBOT = False

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check

SERVOS = [1, 2, 3, 4, 5, 6]
here = bus.read_positions(SERVOS)
print("servos 1..6 are at", [here[i] for i in SERVOS])
print("this moves them to 200, 350, 500, 650, 800, 950 together over 2 s, then all to 500")
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit

# One command, one shared time: they all start and arrive together.
bus.move_many([(1, 200), (2, 350), (3, 500), (4, 650), (5, 800), (6, 950)], 2000)
time.sleep_ms(2000)
here = bus.read_positions(SERVOS)
print("now at", [here[i] for i in SERVOS])
bus.move_many({1: 500, 2: 500, 3: 500, 4: 500, 5: 500, 6: 500}, 2000)  # a dict works too
time.sleep_ms(2000)
here = bus.read_positions(SERVOS)
print("back at", [here[i] for i in SERVOS])
