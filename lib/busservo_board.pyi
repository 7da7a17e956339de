"""busservo_board: the bus and the robot, found the same way by every example.

import busservo_board
bus = busservo_board.bus()               # board.py's UART, or the simulated controller
arm = busservo_board.robot(bus, JOINTS)  # the calibration you saved, or these joints
"""

from typing import Mapping

from busservo import BusServo
from busservo_motion import Joint, Robot

simulated: bool
"""True once bus() took the simulated controller (there was no board.py)."""

def bus() -> BusServo:
    """A BusServo on the uart() of board.py (your port's file from boards/, copied to the board
    as board.py), or where there is none, on the simulated controller, which it says. A
    board.py that fails to import raises its own error: only a missing one means the
    simulator. Prints what it talks to."""

def robot(bus: BusServo, joints: Mapping[str, Joint]) -> Robot:
    """The Robot saved to busservo_motion.CALIBRATION (robot.json, in the folder the program
    runs from: a board's root), so that every example moves your arm within the limits you
    found; without that file, Robot(bus, joints). A calibration that is no calibration raises
    ValueError naming the file."""

def joints(dps: float | None = None) -> dict[str, Joint]:
    """The examples' arm: a base, a shoulder (-90..90 degrees), an elbow (-90..90) and a claw
    (0..60) on servos 1..4, each turning at most dps degrees a second (None: as fast as
    asked)."""
