"""busservo_calibrate: calibrate an arm by hand, once, on the motion layer. Every joint goes
limp, and a person
1. holds the arm in its rest pose (every joint at its 0): each joint's trim;
2. moves each joint through the whole range it may safely use: its limits, MARGIN degrees
   inside what was seen;
3. puts the arm back in its rest pose and nudges each joint a little in its positive
   direction: its direction.

    import busservo_calibrate as bc, busservo_motion as bm
    cal = bc.Calibration(bus, {"base": 1, "shoulder": 2, "elbow": 3, "wrist": 4,
                               "gripper": 5}, kinds={"gripper": bm.PWM_180})
    cal.limp()
    cal.rest()                  # step 1
    cal.sample()                # step 2: again and again while the person sweeps
    cal.nudge()                 # step 3: the last call counts
    arm = cal.save("robot.json", links={"base_height": 70, "upper_arm": 105,
                                        "forearm": 98, "hand": 60})

Each step is one positions query (it blocks for a few tens of ms), or takes the positions a
query made elsewhere brought ({servo_id: position} of cal.ids, as BusServo.read_positions() and
AsyncBusServo.read_positions() give them), so a loop can drive it. A servo that does not answer
raises OSError(ENODEV) naming its joint, as the motion layer does. robot() and save() refuse,
naming each joint and why, what they cannot trust: a joint that did not move, a range under
RANGE_MIN degrees, a rest pose outside the range seen, a nudge too small to tell the direction.
Nothing here moves a servo.

Positive directions (docs/calibrate.md): x forward when base is 0, y to the left, z up. base
turns counter-clockwise seen from above; shoulder, elbow and wrist tilt forward and down
(shoulder 0: the upper arm vertical; elbow 0 and wrist 0: in line with the link before); roll
turns the hand clockwise seen from behind it; gripper opens.
"""

from typing import Mapping

from busservo import BusServo
from busservo_motion import Joint, Robot

MARGIN: int
"""Degrees the limits keep inside the range seen, at each end: 3."""
RANGE_MIN: int
"""Degrees a joint's range seen must span: 10."""
STILL: int
"""Degrees seen under which a joint did not move (a hand's tremor, a read's noise): 2."""
NUDGE_MIN: int
"""Degrees a nudge must go from the rest pose to tell the direction: 5."""

class Calibration:
    """One arm's calibration by hand, a step at a time."""

    bus: BusServo
    """The bus it reads and robot() drives."""
    names: list[str]
    """The joints' names, in servo id order."""
    ids: list[int]
    """Their servos' ids, in that order: what a positions query for the steps asks for."""
    samples: int
    """How many times sample() has read."""

    def __init__(
        self, bus: BusServo, ids: Mapping[str, int], kinds: Mapping[str, str] | None = None
    ) -> None:
        """ids: {joint name: servo_id}; kinds: {joint name: kind} of those that are not bus
        servos (busservo_motion.PWM_180, PWM_270). A PWM servo cannot tell the controller
        where a hand turned it: on a real controller such a joint does not move here."""
    def limp(self) -> None:
        """Let every joint go limp, to be moved by hand (hold the arm: it falls)."""
    def rest(self, positions: Mapping[int, int | None] | None = None) -> dict[str, float]:
        """Step 1: read the rest pose, each joint's 0. {name: degrees from its servo's
        centre}."""
    def sample(
        self, positions: Mapping[int, int | None] | None = None
    ) -> dict[str, tuple[float, float]]:
        """Step 2, again and again while the person sweeps each joint: widen each joint's
        range seen. {name: (least, most) degrees seen, from its servo's centre}."""
    def nudge(self, positions: Mapping[int, int | None] | None = None) -> dict[str, float]:
        """Step 3, after rest(): read how far each joint has been nudged from its rest pose
        (the last call counts). {name: degrees, positive in its servo's own direction}."""
    def unswept(self) -> dict[str, str]:
        """{name: why} of each joint whose range seen in step 2 is too small to calibrate
        (none: {}): the sweep is not done."""
    def problems(self) -> dict[str, str]:
        """{name: why} of each joint the steps so far cannot calibrate (none: {})."""
    def joints(self) -> dict[str, Joint]:
        """{name: Joint} calibrated, or ValueError naming each joint that cannot be and why."""
    def robot(self, bus: BusServo | None = None) -> Robot:
        """A Robot of the calibrated joints, on bus (default: this calibration's), or
        ValueError naming each joint that cannot be calibrated and why."""
    def save(
        self,
        path: str | None = None,
        links: Mapping[str, float] | None = None,
        dps: float | None = None,
    ) -> Robot:
        """Write the calibration to path (default busservo_motion.CALIBRATION, robot.json) as
        Robot.load() reads it, with links {name: mm} of busservo_arm.LINKS if given (measured
        with a ruler, for busservo_arm): {"joints": {name: Joint settings}, "links": {...}},
        keeping what else the file holds (links saved before, and a joint's dps a person set
        in it). Refuses as robot() does, and links that busservo_arm.check_links() refuses
        (TypeError or ValueError), before the file is touched. Returns the Robot, each joint
        at most dps degrees a second if given (a program's cap, as Robot.load() keeps it: not
        saved)."""
