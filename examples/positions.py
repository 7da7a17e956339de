# Moves nothing: reads where servos 1..6 are, as a dict {servo_id: position}.
#   mpremote mip install package.json   # once: the driver
#   mpremote run examples/positions.py
import busservo_board

bus = busservo_board.bus()  # board.py's UART, or the simulated controller

positions = bus.read_positions([1, 2, 3, 4, 5, 6])
for servo_id, position in sorted(positions.items()):
    print("servo", servo_id, "at", position)
