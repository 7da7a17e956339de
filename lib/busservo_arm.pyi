"""busservo_arm: a desktop arm in millimetres, on busservo_motion.Robot. An optional module:
it needs busservo_motion (and busservo), nothing needs it.

    import busservo_arm
    arm = busservo_arm.Arm(robot, {"base_height": 70, "upper_arm": 105, "forearm": 98,
                                   "hand": 150})
    arm.move_to(150, 0, 40, ms=1000)           # the tool point to x, y, z mm, the hand down
    arm.move_to(120, 80, 30, mm_s=50)          # at 50 mm/s
    line = arm.line_to(120, -80, 30, mm_s=100)  # line.step() from a loop, or await line
    arm.where()                                # (x, y, z, pitch), read now
    arm.save(); arm = busservo_arm.Arm.load(bus)   # robot.json: the joints and the links

The geometry (docs/arm.md has the picture): a base that turns, then a shoulder, an elbow and a
wrist that tilt in one vertical plane (a roll and a gripper may follow: the arm leaves them to
you). x is forward when the base is at 0, y to the left, z up, the origin on the base's axis at
the table. base positive turns counter-clockwise seen from above. shoulder 0 holds the upper
arm vertical; shoulder, elbow and wrist positive tilt forward and down; elbow 0 and wrist 0 are
in line with the link before. pitch is the hand's angle from the horizontal: 0 straight out,
-90 straight down. Angles are the joints' degrees (busservo_motion's): calibrate each joint's
direction and trim so that they match the picture.

A point the arm cannot reach, or only past a joint's limits, raises ValueError naming the point,
the reach and the limiting joint, and nothing is sent.
"""

from typing import Any, Generator, Mapping

from busservo import BusServo
from busservo_motion import Robot

JOINTS: tuple[str, ...]
"""The joints an arm needs, by name: ("base", "shoulder", "elbow", "wrist")."""
LINKS: tuple[str, ...]
"""The links, in mm: ("base_height", "upper_arm", "forearm", "hand")."""

def check_links(links: Mapping[str, float]) -> dict[str, float]:
    """{name: mm} of the four LINKS, each a number in 0..10000 mm, upper_arm and forearm more
    than 0: the one check of an arm's links (Arm(), busservo_calibrate's save() and the
    panel's calibration page use it). Raises TypeError or ValueError naming what is wrong."""

class Arm:
    """A Robot's base, shoulder, elbow and wrist as an arm, in millimetres."""

    robot: Robot
    """The Robot it moves."""
    links: dict[str, float]
    """{name: mm}: base_height (the table to the shoulder's axis), upper_arm (the shoulder's
    axis to the elbow's), forearm (the elbow's axis to the wrist's), hand (the wrist's axis to
    the tool point)."""
    elbow_up: bool
    """Which of the two solutions: the elbow above the line from shoulder to wrist (True, the
    default: elbow positive), or below it."""

    def __init__(self, robot: Robot, links: dict[str, float], elbow_up: bool = True) -> None:
        """robot: a busservo_motion.Robot with joints named base, shoulder, elbow and wrist
        (others are left alone); links: {name: mm} of the four LINKS, as check_links() takes
        them. Raises ValueError or TypeError saying what is missing or wrong."""
    @staticmethod
    def load(
        bus_or_robot: BusServo | Robot, path: str | None = None, elbow_up: bool = True
    ) -> Arm:
        """The Arm with the links save() wrote to path, on a Robot of the joints saved there
        (given a BusServo), or on the Robot given. A file that is not valid JSON, or holds no
        "links", raises ValueError naming the file and why."""
    def save(self, path: str | None = None) -> None:
        """Write the joints' calibration and the links to path as JSON,
        {"joints": {...}, "links": {...}}, keeping whatever else the file holds. Robot.load()
        reads its joints, Arm.load() both."""
    def point(self, pose: dict[str, float]) -> tuple[float, float, float, float]:
        """(x, y, z, pitch) of the tool point at pose {name: degrees} of the four joints: the
        forward kinematics (others in pose are ignored)."""
    def reach(self, x: float, y: float, z: float, pitch: float) -> tuple[float, float, float]:
        """The tool point nearest x, y, z mm (with the hand at pitch degrees) that the wrist
        can reach: x, y, z itself if it can, else the one whose wrist is at the reach's edge
        (a hair inside), on the line from the shoulder's axis."""
    def pose(self, x: float, y: float, z: float, pitch: float | None = None) -> dict[str, float]:
        """{name: degrees} of the four joints that put the tool point at x, y, z mm with the
        hand at pitch (None: the reachable pitch nearest -90, within the limits): the inverse
        kinematics, checked. Nothing is sent: a pose for robot.move() or a Sequence."""
    def move_to(
        self,
        x: float,
        y: float,
        z: float,
        pitch: float | None = None,
        ms: int | None = None,
        mm_s: float | None = None,
    ) -> int:
        """Move the tool point to x, y, z mm, the hand at pitch (None: the reachable pitch
        nearest -90), in one CMD_SERVO_MOVE for the four joints: within ms (0..65535), or at
        mm_s (one of the two), timed so that neither the tool point nor the wrist goes faster
        in a straight line (nor the pitch faster than mm_s degrees/s) from where the arm last
        went (move_to(), a line, or where(); read first if none: a blocking query). A joint's
        own dps lengthens the move. Stops a line playing. Returns the move's ms."""
    def where(
        self, positions: Mapping[int, int | None] | None = None
    ) -> tuple[float, float, float, float]:
        """(x, y, z, pitch) of the tool point from the joints' positions read now (a blocking
        query), or from positions {servo_id: position} read before (not blocking), to 0.1 mm
        and 0.1 degree. A servo that does not answer raises OSError(ENODEV) naming its
        joint."""
    def line_to(
        self, x: float, y: float, z: float, pitch: float | None = None, mm_s: float = 50
    ) -> Line:
        """A Line: the tool point along a straight line from where the arm last went (read
        first if not known) to x, y, z mm at mm_s, the pitch turning evenly to pitch (None:
        the reachable pitch nearest -90 at the end). The whole line is checked first, and
        solved every 2 mm (8 bytes a point: 4 KB at most): a point on it the arm cannot reach
        raises ValueError naming it, and nothing is sent. A joint's dps slows the whole line.
        Nothing moves until its step()."""

class Line:
    """A straight line playing: call step() from a loop, or await it (await line, or await
    line.run()). It streams through the robot's stream() and step(), at the wire's pace; it is
    the robot's player, so robot.estop() stops it."""

    arm: Arm
    """The arm it moves."""
    robot: Robot
    """The arm's robot."""
    start: tuple[float, float, float, float]
    """(x, y, z, pitch) it starts from."""
    end: tuple[float, float, float, float]
    """(x, y, z, pitch) it ends at."""
    mm_s: float
    """The speed asked for, in mm/s."""
    ms: int
    """How long the line takes, in ms: its length at mm_s, or longer if a joint's dps needs
    it."""
    updates: int
    """Frames of the line sent."""
    done: bool
    """Its last point has been sent, or stop() was called."""

    def __init__(
        self,
        arm: Arm,
        x: float,
        y: float,
        z: float,
        pitch: float | None = None,
        mm_s: float = 50,
    ) -> None:
        """As arm.line_to(x, y, z, pitch, mm_s). A new line stops the robot's player."""
    def step(self) -> bool:
        """From the control loop: if the wire can take a frame (or will before the next
        step()), send the point the line has reached, with robot.stream() and robot.step():
        the joints straight between the two points around it, solved when the line was made.
        Never waits; allocates nothing when the wire is busy. True if it sent. A late loop
        slows the line rather than cutting across."""
    def stop(self) -> None:
        """End the line: the tool point stops at the last point sent (reached within that
        frame's time). Nothing is sent; targets streamed but not sent are dropped."""
    async def run(self, poll_ms: int = 5) -> None:
        """Step to the end of the line, sleeping between frames: other tasks run meanwhile."""
    def __await__(self) -> Generator[Any, None, None]: ...
