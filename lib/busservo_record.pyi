"""busservo_record: continuous recording of a limp arm moved by hand, and smooth playback of
it, on top of busservo_motion. An optional module.

    import busservo_record as br
    rec = br.Recorder(arm, path="demo.rec")   # the joints go limp: move the arm by hand
    while recording: rec.step()               # from the loop (or: await rec.run(ms=10000))
    recording = rec.stop()
    player = recording.play(arm, speed=1.0)   # into the first pose at dps=30, then its pace
    while not player.done: player.step()      # or: await player, or player.wait()
    recording.save("demo.jsonl")              # JSON lines, for a computer
    seq = recording.to_sequence(tolerance=2)  # keyframes, for busservo_motion's Player

A read is the driver's own query (BusServo.ask()), a step at a time: the loop never waits for
the wire, and a read that times out is skipped and counted. Samples are the servos' positions
and the ticks_ms each came, 8 bytes a sample for 6 joints; degrees are made from them, with
the calibration the recording keeps, when it is read. Bad input raises ValueError or TypeError
naming the argument, what is allowed and what came.
"""

from typing import Any, Final, Generator, Iterator, Mapping

from busservo import BusServo
from busservo_motion import Joint, Robot, Sequence

MAGIC: Final = b"BSREC1\n"
"""The first bytes of the compact file form; a JSON line of the joints follows, then the
samples."""
PIECE: Final = 256
"""Bytes a Recorder writes to its file at a time, between a reply and the next request."""
HALT_MS: int
"""A playback stopped by Ctrl-C in wait() on a move's way: the servos go where they are
within this."""

class Recorder:
    """A recording under way: step() from the loop, or await it."""

    names: list[str]
    """The joints recorded, in the robot's order (by servo id)."""
    robot: Robot
    """The robot recorded."""
    bus: BusServo
    """The robot's bus: its ask() reads the positions."""
    path: str | None
    """The file it writes to (None: kept in RAM)."""
    timeout_ms: int | None
    """A read's timeout (None: the driver's default, 100 ms and 10 a servo)."""
    joints: dict[str, Joint]
    """The joints recorded, with their calibrations: the recording keeps them."""
    samples: int
    """Samples kept so far."""
    missed: int
    """Reads skipped: timed out, or a servo did not answer."""
    done: bool
    """stop() was called."""
    recording: Recording | None
    """The Recording, once stopped."""

    def __init__(
        self,
        robot: Robot,
        names: list[str] | None = None,
        path: str | None = None,
        limp: bool = True,
        timeout_ms: int | None = None,
    ) -> None:
        """Record the joints (names, all by default) of robot: they go limp (limp=True) to be
        moved by hand. path: a file the compact form goes to as it comes ("*.jsonl": JSON
        lines, written at stop()); None: kept in RAM."""
    def step(self) -> bool:
        """From the control loop: take a reply if one has come, and ask for the next read.
        Never waits for the wire; a full piece goes to the file only between a reply and the
        next request. True if a sample was kept."""
    def take(self, ticks_ms: int, positions: Mapping[int, int | None] | None) -> bool:
        """A read made elsewhere (a busservo_teleop.Teleop's of its leader, given
        Teleop(..., recorder=rec)): positions {servo_id: position}, as BusServo.positions
        holds a reply, taken at ticks_ms; None for a read that failed (counted in missed).
        Call it between a reply and the next request: a full piece goes to the file then.
        Once given one, step() reads nothing. True if a sample was kept."""
    def stop(self) -> Recording:
        """Stop recording: what waits in RAM goes to the file, which is closed. Return the
        Recording (also self.recording). The joints stay limp."""
    async def run(self, ms: float | None = None, poll_ms: int = 2) -> Recording | None:
        """Record until stop() (or for ms), a step every poll_ms: other tasks run meanwhile."""
    def __await__(self) -> Generator[Any, None, Recording | None]: ...

class Recording:
    """Samples of joints, as the servos' positions and the ms each came."""

    names: list[str]
    """The joints, in the order of each sample's positions."""
    joints: dict[str, Joint]
    """Their calibrations, as recorded: degrees are made with these."""
    data: bytes
    """The samples, packed: 2 bytes of ms since the one before and a byte a joint (its
    position's change), or a key sample (FF FF, 4 bytes of ms, 2 bytes a position)."""

    def __init__(
        self, joints: dict[str, Joint], names: list[str] | None = None, data: bytes = b""
    ) -> None:
        """Recorder.stop() and Recording.load() make these."""
    def samples(self) -> Iterator[tuple[int, list[int]]]:
        """(ms from the first sample, [positions, in names' order]) of each sample; the list
        is the same one each time, filled anew."""
    def __iter__(self) -> Iterator[tuple[int, dict[str, float]]]:
        """(ms from the first sample, {name: degrees}) of each sample, in order."""
    def __len__(self) -> int: ...
    @property
    def duration_ms(self) -> int:
        """ms from the first sample to the last."""
    def save(self, path: str) -> None:
        """Write it to path: JSON lines if it ends in .jsonl (a line of the joints, then one a
        sample: {"t": ms, "pose": {name: degrees}}), else the compact form."""
    @staticmethod
    def load(path: str) -> Recording:
        """The recording in path, in either form; ValueError naming the file if it holds
        none."""
    def to_sequence(self, tolerance: float = 1.0, ms: int = 1000) -> Sequence:
        """Keyframes for busservo_motion's Player: the fewest samples that, joined by straight
        moves, pass within tolerance degrees of every sample. ms: the time to the first."""
    def play(self, robot: Robot, speed: float = 1.0, dps: float = 30) -> Playback:
        """A Playback of this recording on robot."""

class Playback:
    """A recording playing: call step() from a loop, await it, or wait()."""

    robot: Robot
    """The robot it plays on."""
    recording: Recording
    """What it plays."""
    speed: float
    """0.25..2: 2 plays twice as fast."""
    dps: float
    """The speed (degrees a second) it goes into the first pose at."""
    names: list[str]
    """The joints it moves."""
    index: int
    """The sample the last move went to (-1: none yet)."""
    done: bool
    """The last sample has been reached, or stop() was called."""
    slowed: int
    """Moves a joint's own dps made longer than the recording's pace."""
    started: int | None
    """ticks_ms when the first pose was reached and the recorded pace began."""
    frame_ms: int
    """A move's time on the wire, as measured (0: not yet)."""

    def __init__(
        self, robot: Robot, recording: Recording, speed: float = 1.0, dps: float = 30
    ) -> None:
        """As recording.play(robot, speed, dps): into the first pose at dps, then at the
        recorded pace times speed, each move's time the gap to its sample so that the servos
        glide. Registers as robot.player: estop() or a new player stops it."""
    def step(self) -> bool:
        """Send the next move if its time has come; never waits for the wire (the first,
        a read of where the joints are, is the driver's ask(), a step at a time). True if it
        sent."""
    def stop(self) -> None:
        """Stop playing; nothing is sent (the move on its way, a sample's gap, is made)."""
    def wait(self) -> None:
        """Play to the end, blocking; Ctrl-C stops it, and is raised again."""
    async def run(self, poll_ms: int = 20) -> None:
        """Play to the end (or until stop()), sleeping until each move is due."""
    def __await__(self) -> Generator[Any, None, None]: ...
