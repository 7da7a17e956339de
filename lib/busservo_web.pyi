"""busservo_web: a control panel for a busservo_motion.Robot, served by the board itself to a
browser on the same Wi-Fi (or on the board's own access point), on asyncio, with a small HTTP
server of its own. An optional module: it needs busservo, busservo_motion, and its page
busservo_web.html.gz beside it (docs/panel.md's mip command brings them all).

    import asyncio, busservo_web
    asyncio.run(busservo_web.serve(robot, "a password of yours", port=80))

The page: a slider per joint (its thumb the target, a mark on its track where the joint is,
read about 5 times a second, its limits at its ends), the battery, limp, capture
(the pose shown, a number per joint to change, is the pose added), a sequence whose steps can
each be edited or removed, play (loop, speed), halt, save and load, and a STOP button (Esc)
that lets every joint go limp. Nothing moves until the page is armed; when the armed page goes
silent for a second (tab closed, Wi-Fi gone), the stream stops and the joints hold, and a
sequence stops where the joints are. The panel never waits on the wire: the positions it
reads for a page come through BusServo.ask(), while its loop goes on.
With an arm (an Arm given, or links in the calibration file: busservo_arm is imported only
then) the armed page jogs its tool point along x, y, z (mm) or its pitch (degrees), in a
straight line; a step it cannot reach is refused by name and nothing moves. Its calibration
page (busservo_calibrate, imported only when it starts) lets every joint go limp on the
armed page, reads the rest pose, the ranges and the nudges by hand, refuses by joint what it
cannot trust, saves the calibration file, and homes at 30 degrees/s only when the page
confirms. The dead-man and STOP end a jog and a calibration as they end the stream.
Installed by mip from lib/busservo_web.json, the modules are .mpy: on a 32-bit board the
panel then serves within a 56 KB heap (from .py source, about 112 KB).
Without the password only the page is served (and /favicon.ico: 204); every other request
gets 401. Every request is answered, or its connection closed: 503 when too many come at once
or the panel fails (out of memory, say) before its answer has begun; 408 when it takes over a
second to send.
"""

from typing import Any

from busservo import BusServo
from busservo_arm import Arm
from busservo_calibrate import Calibration
from busservo_motion import Player, Robot, Sequence

async def serve(
    robot: Robot,
    password: str,
    port: int = 80,
    arm: Arm | None = None,
    path: str = "robot.json",
    host: str = "0.0.0.0",
) -> None:
    """Serve the panel for robot on port, on every interface (or host's: "127.0.0.1" for
    this machine alone), until cancelled. password: a str of 8 or more characters, which
    the page asks for (ValueError otherwise). arm: an Arm on robot for the page to jog (None:
    the one path's links make, if it has any). path: the calibration file
    (busservo_board.CALIBRATION by default), which the calibration page saves."""

class Panel:
    """The panel's state, its loop and its HTTP side; serve() makes one."""

    robot: Robot
    bus: BusServo
    armed: str | None
    """The session token of the page that armed the panel, or None."""
    sequence: Sequence
    """The sequence the page builds and plays."""
    edits: int
    """How many times the sequence has changed: a page reads it again when this grows."""
    player: Player | None
    error: str | None
    """The last error of the panel's loop, shown on the page until 3 s after it last
    happened."""
    limp: bool
    """The joints were let go (limp or stop) and not moved since."""
    arm: Arm | None
    """The arm the page jogs, or None: no jog."""
    no_arm: str | None
    """Why the calibration file's links make no arm, if they make none."""
    path: str
    """The calibration file: the links, and where the calibration page saves."""
    cal: Calibration | None
    """The calibration under way on the page, or None."""
    robots: int
    """Robots the panel has had (a calibration saved gives it a new one): the page reads the
    joints again when this grows."""
    to: dict[str, float]
    """{name: degrees} the page's slider or a jog last sent each joint towards (cleared by
    limp, stop, a sequence and a calibration)."""
    def __init__(
        self, robot: Robot, password: str, arm: Arm | None = None, path: str = "robot.json"
    ) -> None:
        """arm: an Arm on robot (ValueError if on another); None: the one path's links make,
        if any (busservo_arm is imported only then)."""
    def disarm(self, halt: bool = True) -> None:
        """Stop driving: the stream and a jog end (the joints hold), the sequence stops (see
        stop(): with halt, its pose on the way too), and a calibration is given up (its
        joints stay limp)."""
    def stop(self, halt: bool = True) -> None:
        """Stop the sequence; with halt, its pose on the way too: the joints it moves are
        sent where they are, once a read of their positions has come (about 30 ms later; the
        read does not block: see where()), unless something else was ordered meanwhile."""
    async def where(self, names: list[str] | None = None) -> dict[str, float]:
        """{name: degrees} of these joints (all by default), as Robot.where() gives them, read
        now without blocking: the query is the driver's BusServo.ask(), a step every 5 ms, so
        the panel's loop, the stream and the other pages go on while the reply is on its
        way. One such query at a time; raises OSError(ETIMEDOUT) as Robot.where() does."""
    def estop(self) -> None:
        """Disarm and stop the sequence at once, then Robot.estop(): every joint limp."""
    def state(self, token: str | None = None) -> dict[str, Any]:
        """What GET /api/state answers: positions in degrees ("at") and the targets sent
        ("to"), battery, armed (and "mine": armed by token's page), the sequence's times and
        how many times it changed; with an arm, its tool point (x, y, z, pitch) and the jog's
        target; a calibration's step, what it has seen, and what it refuses by joint."""
    async def handle_request(self, reader: Any, writer: Any) -> None:
        """Answer one connection's request (HTTP/1.0), then close it: serve()'s server calls
        this for each connection."""
    async def run(self) -> None:
        """The panel's loop, for ever: the bus's replies, the stream, the player, the
        dead-man, and position and battery requests."""
