# Read servo positions: a dict {servo_id: position}.
#   mpremote run examples/positions.py
import busservo

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

bus = busservo.BusServo(uart())
positions = bus.read_positions([1, 2, 3, 4, 5, 6])
for servo_id, position in sorted(positions.items()):
    print("servo", servo_id, "at", position)
