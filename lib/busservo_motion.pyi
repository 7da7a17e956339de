"""busservo_motion: joints in degrees, poses taught by hand, and motion at the wire's limit, on
top of busservo.BusServo. An optional module: busservo alone does not need it.

    import busservo, busservo_motion as bm
    arm = bm.Robot(busservo.BusServo(uart), {
        "base": bm.Joint(1),                                   # a bus servo
        "shoulder": bm.Joint(2, direction=-1, trim=3.5, limits=(-90, 90)),
        "claw": bm.Joint(6, kind=bm.PWM_180, limits=(0, 60)),  # a PWM servo on an LSC board
    })
    arm.move({"base": 30, "shoulder": -45}, ms=500)   # one CMD_SERVO_MOVE for all
    arm.move({"base": 0}, dps=60)                      # speed-limited
    arm.limp(); pose = arm.capture()                   # teach by hand
    player = bm.Sequence([(pose, 800)]).play(arm)      # player.step() from a loop, or await it
    arm.stream({"base": x}); arm.step()                # a control loop at the wire's pace
    arm.estop()                                        # stop the group, every joint limp

Degrees are the joint's: 0 at the servo's centre (position 500 of a bus servo, 1500 us of a
PWM servo), and the servo turns to direction * degrees + trim. Bad input raises ValueError or
TypeError naming the argument, what is allowed and what came, and nothing is sent.
"""

from typing import Any, Generator, Iterable, Mapping
from typing import Sequence as _Seq

from busservo import BusServo

BUS: str
"""A bus servo: positions 0..1000 over 240 degrees (-120..120), 500 at 0 degrees."""
PWM_180: str
"""A PWM servo on an LSC board: 500..2500 us over 180 degrees (-90..90), 1500 at 0."""
PWM_270: str
"""A PWM servo: 500..2500 us over 270 degrees (-135..135), 1500 at 0."""

CALIBRATION: str
"""Where a calibration is saved by default, "robot.json", in the folder the program runs from
(a board's root): Robot.save() writes the joints there, busservo_arm's Arm.save() the links
beside them, and busservo_board.robot(), the panel and busservo_calibrate use it."""

def aio() -> Any:
    """The asyncio module, imported when first asked for (on CPython, busservo_cpython's):
    many robots never need it."""

def load_json(path: str, key: str, saver: str) -> Any:
    """config[key] of the JSON file at path (saver wrote it), or ValueError naming the file
    and what is wrong with it (not JSON, or no key)."""

def number(name: str, value: Any, low: float = float("-inf"), high: float = float("inf")) -> float:
    """value, a finite int or float in low..high; else TypeError or ValueError naming it
    (name), the range and what came."""

def least_dps(joints: Mapping[str, Joint]) -> float | None:
    """The least dps of joints {name: Joint}, or None when none has one: the speed cap a
    program's joints ask for, which Robot.load(bus, path, dps) keeps over a file's."""

def toward(
    pair: list[int],
    goal: int,
    i: int,
    at: list[int],
    owed: list[int],
    way: list[int],
    pps: int,
    elapsed: int,
    last_ms: int,
    since: int,
) -> int:
    """One step of joint i of a stream towards goal (a position), at pps positions a second
    at most (Robot.step(), busservo_teleop): pair[1] becomes the position to send, from at[i]
    (the last sent) as far as elapsed ms allow (owed[i]: the part of a position carried, in
    1/1000ths). Returns the ms the move needs at pps from where the servo is (short of at[i]
    still while the last move, way[i]/1000 positions over last_ms sent `since` ms ago, is on
    its way); way[i] becomes this move's. Allocates nothing."""

_Pose = Mapping[str, float]

class Joint:
    """One servo of a robot, and its calibration."""

    servo_id: int
    """The servo's id on the bus (0..255)."""
    kind: str
    """BUS, PWM_180 or PWM_270."""
    direction: int
    """1, or -1 for a servo mounted the other way round."""
    trim: float
    """Degrees added to the servo's angle, so that the joint's 0 is the servo's centre plus
    trim."""
    limits: tuple[float, float]
    """(low, high) degrees: targets beyond them are clamped (and counted)."""
    lo: float
    """limits[0]."""
    hi: float
    """limits[1]."""
    dps: float | None
    """The joint's top speed in degrees per second, or None: no move of the module is
    faster."""
    per_degree: float
    """Positions per degree: 25/6 for BUS, 100/9 for PWM_180, 200/27 for PWM_270."""
    centre: int
    """The kind's centre position: 500 (BUS) or 1500 (PWM)."""

    def __init__(
        self,
        servo_id: int,
        kind: str = "BUS",
        direction: int = 1,
        trim: float = 0.0,
        limits: _Seq[float] | None = None,
        dps: float | None = None,
    ) -> None:
        """servo_id 0..255; kind BUS, PWM_180 or PWM_270; direction 1 or -1; trim in degrees
        within the kind's half range; limits (low, high) in degrees, which the servo must be
        able to reach with this direction and trim (None: all it can reach); dps > 0 or
        None. Raises ValueError or TypeError saying what is allowed and what came."""
    def position(self, degrees: float) -> int:
        """The position for degrees, clamped to the limits. Allocates nothing."""
    def degrees(self, position: int) -> float:
        """The joint's angle at position, in degrees (not clamped)."""
    def config(self) -> dict[str, Any]:
        """The joint's settings, as Robot.save() writes them: Joint(**config) makes it again."""

class Robot:
    """Joints by name on one bus. Moves take degrees; positions it last read or commanded are
    kept, for speed-limited moves."""

    bus: BusServo
    """The BusServo the robot drives."""
    joints: dict[str, Joint]
    """{name: Joint}, as given."""
    names: list[str]
    """The joints' names, in servo_id order."""
    clamped: int
    """How many targets were clamped to their joint's limits, ever: a clamp is never silent."""
    slowed: int
    """How many moves and stream frames were slowed to a joint's dps."""
    player: Player | None
    """The Player playing on this robot, if any (estop() stops it)."""
    frame_ms: int
    """A stream frame's time on the wire, in whole ms as measured (0 before the first)."""
    updates: int
    """Stream frames step() has sent."""

    def __init__(self, bus: BusServo, joints: dict[str, Joint]) -> None:
        """bus: a busservo.BusServo; joints: {name: Joint}, 1..83 of them, each servo_id
        once."""
    @staticmethod
    def load(bus: BusServo, path: str, dps: float | None = None) -> Robot:
        """A Robot on bus with the calibration save() wrote to path (JSON). A file that is not
        valid JSON, or holds no "joints", raises ValueError naming the file and why. dps: a
        cap in degrees a second that holds whatever the file says: each joint turns at most
        the least of its own dps (the file's) and dps."""
    def save(self, path: str, **more: object) -> None:
        """Write the joints' calibration to path as JSON, and the keys in more (links=...),
        keeping what else the file holds."""
    def move(self, targets: _Pose, ms: int | None = None, dps: float | None = None) -> int:
        """Move joints {name: degrees} together, in one CMD_SERVO_MOVE: within ms (0..65535),
        or at dps degrees per second for the joint that goes furthest (one of the two). A
        speed needs to know where the joints are: those not known are read first (a
        blocking query). A joint's own dps lengthens the move if need be (counted in slowed).
        Targets beyond the limits are clamped (counted in clamped). Returns the move's ms.
        Ends the stream."""
    def where(
        self, names: Iterable[str] | None = None, positions: Mapping[int, int | None] | None = None
    ) -> dict[str, float]:
        """{name: degrees} of these joints (all by default), read now (a blocking query), to
        0.1 degree; or, not blocking, from positions {servo_id: position} read before (after
        the driver's ask(), bus.positions). A servo that does not answer (unpowered, not on
        the bus: it reads 65535), or has no position in positions, raises OSError(ENODEV)
        naming its joint."""
    def capture(self) -> dict[str, float]:
        """The pose the robot is in, {name: degrees} of every joint, read now: after limp(),
        pose the robot by hand, then capture()."""
    def limp(self, names: Iterable[str] | None = None) -> None:
        """Unload these joints (all by default): they turn freely by hand until the next move.
        Ends the stream."""
    def home(self, pose: _Pose | None = None, dps: float = 30) -> int:
        """A soft start: read where every joint is, then go to pose (default: 0 degrees, or the
        nearest limit) at dps. Returns the move's ms."""
    def estop(self) -> None:
        """Stop everything: the player and the stream end, CMD_ACTION_GROUP_STOP, then every
        joint is unloaded (limp)."""
    def stream(self, targets: _Pose) -> int:
        """Store the latest targets {name: degrees} for step(): nothing is sent, and a later
        call's targets replace these. Allocates nothing once each joint has been streamed
        to. Returns how many targets were clamped. A joint with a dps must have a known
        position (home() or where() first)."""
    def step(self) -> bool:
        """From the control loop: if stream() gave new targets and the wire is free (or will
        be before the next step()), send them in one move_many(), timed to glide until the
        next update (the frame's wire time, or the pace of stream() if slower). Never waits
        for the UART; allocates nothing. True if it sent a frame."""
    def hold(self) -> None:
        """End the stream: targets stream() gave that step() has not sent are dropped, and
        each joint stops at the last target sent (reached within that frame's time).
        Nothing is sent; a later stream() starts afresh. For a dead-man: a control loop
        whose source of targets has gone quiet calls hold()."""

class Sequence:
    """Poses and the ms to reach each, to play back."""

    steps: list[tuple[dict[str, float], int]]
    """(pose, ms) pairs."""

    def __init__(self, steps: Iterable[tuple[_Pose, int]] = ...) -> None:
        """steps: (pose, ms) pairs: each pose {name: degrees}, ms 0..65535 to reach it."""
    def append(self, pose: _Pose, ms: int) -> None:
        """Add a pose, reached ms (0..65535) after the one before."""
    def __len__(self) -> int: ...
    def save(self, path: str) -> None:
        """Write the sequence to path as JSON."""
    @staticmethod
    def load(path: str) -> Sequence:
        """The sequence save() wrote to path. A file that is not valid JSON, or holds no
        "steps" of {"pose", "ms"}, raises ValueError naming the file and why."""
    def play(self, robot: Robot, speed: float = 1.0, loop: bool = False) -> Player:
        """A Player of this sequence on robot (every pose checked first). speed 2.0 plays
        twice as fast; loop plays it for ever (until stop() or estop())."""

class Player:
    """A sequence playing: call step() from a loop, or await it (await player, or await
    player.run())."""

    robot: Robot
    """The robot it plays on."""
    loop: bool
    """Play for ever."""
    speed: float
    """The speed it plays at: 2.0 is twice as fast."""
    index: int
    """The pose last sent (-1: none yet)."""
    loops: int
    """How many times the sequence has come round again."""
    done: bool
    """The last pose has been reached, or stop() was called."""

    def __init__(
        self, robot: Robot, sequence: Sequence, speed: float = 1.0, loop: bool = False
    ) -> None:
        """As sequence.play(robot, speed, loop). A new player stops the robot's last one."""
    def step(self) -> bool:
        """Send the next pose if the one before has been reached. Never waits (a pose that
        needs a position not known reads it: home() first). True if it sent a pose."""
    def stop(self) -> None:
        """Stop playing. Nothing is sent: the pose on its way is reached."""
    async def run(self, poll_ms: int = 10) -> None:
        """Play to the end (with loop, until stop()), sleeping between poses: other tasks
        run meanwhile."""
    def __await__(self) -> Generator[Any, None, None]: ...
