"""busservo_board: the bus and the robot, found the same way by every example.

import busservo_board
bus = busservo_board.bus()               # board.py's UART, or the simulated controller
arm = busservo_board.robot(bus, JOINTS)  # the calibration you saved, or these joints
"""

from typing import Final, Mapping

from busservo import BusServo
from busservo_motion import Joint, Robot

CALIBRATION: Final = "robot.json"
"""Where robot() looks for a saved calibration (Robot.save(CALIBRATION) writes it), in the
folder the program runs from: a board's root."""
simulated: bool
"""True once bus() took the simulated controller (there was no board.py)."""

def bus() -> BusServo:
    """A BusServo on the uart() of board.py (your port's file from boards/, copied to the board
    as board.py), or where there is none, on the simulated controller, which it says. A
    board.py that fails to import raises its own error: only a missing one means the
    simulator. Prints what it talks to."""

def robot(bus: BusServo, joints: Mapping[str, Joint]) -> Robot:
    """The Robot saved to CALIBRATION (Robot.load(bus, CALIBRATION)), so that every example
    moves your arm within the limits you found; without that file, Robot(bus, joints). A
    calibration that is no calibration raises ValueError naming the file."""
