"""busservo_web: a control panel for a busservo_motion.Robot, served by the board itself to a
browser on the same Wi-Fi (or on the board's own access point), on asyncio, with a small HTTP
server of its own. An optional module: it needs busservo, busservo_motion, and its page
busservo_web.html.gz beside it (docs/panel.md's mip command brings them all).

    import asyncio, busservo_web
    asyncio.run(busservo_web.serve(robot, "a password of yours", port=80))

The page: a slider per joint, live positions (about 5 a second), the battery, limp, capture
(the pose shown, a number per joint to change, is the pose added), a sequence whose steps can
each be edited or removed, play (loop, speed), halt, save and load, and a STOP button (Esc)
that lets every joint go limp. Nothing moves until the page is armed; when the armed page goes
silent for a second (tab closed, Wi-Fi gone), the stream stops and the joints hold, and a
sequence stops where the joints are. The panel never waits on the wire: the positions it
reads for a page come through BusServo.ask(), while its loop goes on.
Installed by mip from lib/busservo_web.json, the modules are .mpy: on a 32-bit board the
panel then serves within a 56 KB heap (from .py source, about 104 KB).
Without the password only the page is served (and /favicon.ico: 204); every other request
gets 401. Every request is answered, or its connection closed: 503 when too many come at once
or the panel fails (out of memory, say) before its answer has begun; 408 when it takes over a
second to send.
"""

from typing import Any

from busservo import BusServo
from busservo_motion import Player, Robot, Sequence

async def serve(robot: Robot, password: str, port: int = 80) -> None:
    """Serve the panel for robot on port, on every interface, until cancelled. password: a
    str of 8 or more characters, which the page asks for (ValueError otherwise)."""

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
    def __init__(self, robot: Robot, password: str) -> None: ...
    def disarm(self, halt: bool = True) -> None:
        """Stop driving: the stream ends (the joints hold) and the sequence stops (see
        stop(): with halt, its pose on the way too)."""
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
        """What GET /api/state answers: positions in degrees, battery, armed (and "mine":
        armed by token's page), the sequence's times and how many times it changed."""
    async def handle_request(self, reader: Any, writer: Any) -> None:
        """Answer one connection's request (HTTP/1.0), then close it: serve()'s server calls
        this for each connection."""
    async def run(self) -> None:
        """The panel's loop, for ever: the bus's replies, the stream, the player, the
        dead-man, and position and battery requests."""
