"""busservo_teleop: a leader arm, limp, moved by hand, drives a follower arm live at the wire's
pace, on busservo_motion. An optional module: it needs busservo_motion (and busservo), nothing
needs it.

    import busservo_teleop
    t = busservo_teleop.Teleop(leader, follower, dps=30)   # two Robots, joints by name
    while True:
        t.step()                                            # never waits for the wire
    # or, in asyncio: await t

Each arm is a Robot with its own calibration: the same degrees are the same pose on both. The
arms may be on two UARTs (two BusServo), on one controller's bus (one BusServo, their servo ids
apart) or on two serial ports of a computer. The follower first goes to the leader's pose at
dps and follows only once every joint is within ENGAGE degrees; a leader joint that does not
answer holds it, naming the joint. The teleop is the follower's player: its estop() stops it.
"""

from typing import Any, Callable, Generator

from busservo_motion import Robot
from busservo_record import Recorder

ENGAGE: int
"""Degrees: the follower follows freely once every joint is this near the leader's (3)."""
REST: int
"""Degrees: at the start, a joint whose two calibrations disagree by more at rest is warned of
(2)."""

class Teleop:
    """A leader Robot driving a follower Robot: call step() from a loop, or await it."""

    leader: Robot
    follower: Robot
    names: list[str]
    """The joints both arms have, by name, in the leader's servo_id order: those it drives."""
    shared: bool
    """Both arms are on one BusServo (one controller's bus)."""
    dps: float
    """How fast the follower goes to the leader's pose before it follows, degrees/s."""
    rest: bool
    """Both arms start at rest: their first readings are compared (see REST)."""
    timeout_ms: int | None
    """Each read's timeout, as BusServo.ask() takes it (None: its default)."""
    engaged: bool
    """The follower follows the leader freely (else it is on its way to its pose, at dps)."""
    held: str | None
    """The joint whose servo does not answer, holding the follower; None when all answer."""
    done: bool
    """stop() was called (or the follower's estop(), or another player took the follower)."""
    reads: int
    """The leader's replies taken."""
    moves: int
    """Moves sent to the follower."""
    timeouts: int
    """Reads that had no reply in time: skipped, never fatal."""
    clamped: int
    """Targets clamped to the follower's limits."""
    slowed: int
    """Moves slowed to dps (engaging) or to a follower joint's own dps."""
    period_ms: int
    """ms between the last two replies of the leader: the rate is 1000 / period_ms a second."""
    read_at: int
    """ticks_ms when the last reply of the leader came: its positions are in
    leader.bus.positions."""
    warnings: list[str]
    """What was warned of: a calibration that disagrees at rest, a joint that does not
    answer."""
    warn: Callable[[str], Any] | None
    """Where warnings go as they come: warn(text); None (the default) prints them."""
    recorder: Recorder | None
    """The Recorder of the leader given each read of it (Recorder.take()), or None."""

    def __init__(
        self,
        leader: Robot,
        follower: Robot,
        dps: float = 30,
        rest: bool = True,
        timeout_ms: int | None = None,
        recorder: Recorder | None = None,
    ) -> None:
        """leader drives follower, their joints matched by name. dps: how fast the follower
        goes to the leader's pose first. rest: both arms start in their rest pose (warn of a
        joint whose calibrations disagree there). timeout_ms: each read's (None: ask()'s
        default). recorder: a busservo_record.Recorder of the leader (of joints both arms
        have), given each read of the leader: it is recorded with no read of its own (a read
        that times out counts in its missed). Registers as follower.player. Nothing is sent
        until the first step()."""
    def step(self) -> bool:
        """From the loop: take the leader's reply if it has come, ask again, and send the
        follower its targets once its wire is free. The first step lets the leader's joints go
        limp and asks where the follower is. Never waits for the wire; allocates nothing but
        each read's ask(). True if it sent the follower a move."""
    def stop(self) -> None:
        """Stop: nothing more is sent (the move on its way is made); the leader stays limp."""
    async def run(self, poll_ms: int = 1) -> None:
        """Follow until stop() (or the follower's estop()), a step every poll_ms."""
    def __await__(self) -> Generator[Any, None, None]: ...
