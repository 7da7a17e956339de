# Moves nothing: reads where servos 1..6 are, as a dict {servo_id: position}.
#   mpremote run examples/positions.py
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
positions = bus.read_positions([1, 2, 3, 4, 5, 6])
for servo_id, position in sorted(positions.items()):
    print("servo", servo_id, "at", position)
