"""busservo_web: a control panel for a busservo_motion.Robot, served by the board itself to a
browser on the same Wi-Fi (or on the board's own access point), on asyncio, with a small HTTP
server of its own. An optional module: it needs busservo, busservo_motion, its parts
(busservo_web_sliders, busservo_web_teach, busservo_web_jog, busservo_web_calibrate) and its
page busservo_web.html.gz beside it (docs/panel.md's mip command brings them all). This module
is the panel's core: HTTP and safety (sessions, arming and the dead-man, STOP, the routes, the
state and the loop); what the page does plugs into it as parts (docs/panel.md: adding one).

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
panel then serves within a 64 KB heap (from .py source, about 104 KB).
Without the password only the page is served (and /favicon.ico: 204); every other request
gets 401. Every request is answered, or its connection closed: 503 when too many come at once
or the panel fails (out of memory, say) before its answer has begun; 408 when it takes over a
second to send.
"""

from typing import Any, Callable

from busservo import BusServo
from busservo_arm import Arm
from busservo_motion import Robot

PAGE: str
"""The page's file: busservo_web.html.gz beside this module (else in /lib)."""
HALT_MS: int
"""A move stopped on its way (Panel.halt()): the joints go where they are within this."""
PARTS: tuple[tuple[Any, ...], ...]
"""The parts serve() plugs in by default: (module, None: at once; or NAME: when /api/NAME is
first asked for, or, with a condition, when condition(panel) holds)."""

class Refused(Exception):
    """Refused(status, why): a request the panel refuses, its HTTP status, and why (args[0],
    which the page shows)."""

    status: int
    args: tuple[Any, ...]

def need(
    body: dict[str, Any],
    key: str,
    kind: type,
    low: float | None = None,
    high: float | None = None,
    what: str | None = None,
) -> Any:
    """body[key], checked: of kind (int also stands for float), in low..high; else
    Refused(400) naming what (default: key), the range and what came."""

async def serve(
    robot: Robot,
    password: str,
    port: int = 80,
    arm: Arm | None = None,
    path: str | None = None,
    host: str = "0.0.0.0",
    parts: tuple[tuple[Any, ...], ...] = ...,
    page: str | None = None,
    **options: Any,
) -> None:
    """Serve the panel for robot on port, on every interface (or host's: "127.0.0.1" for
    this machine alone), until cancelled. password: a str of 8 or more characters, which
    the page asks for (ValueError otherwise). arm: an Arm on robot for the page to jog (None:
    the one path's links make, if it has any). path: the calibration file
    (busservo_motion.CALIBRATION by default), which the calibration page saves. parts: the
    parts to plug in (PARTS by default: all). page: the page's file (default: PAGE).
    options: settings for the parts, kept as Panel.options (leader=robot2: a leader Robot
    that drives robot, turned on and off from the page: busservo_web_record's teleop)."""

class Panel:
    """The panel's core: sessions and arming, STOP, the route table, the state, the loop and
    the HTTP side; serve() makes one, and its parts plug into it."""

    robot: Robot
    """The robot driven (a calibration saved gives the panel a new one: adopt())."""
    bus: BusServo
    dps: float | None
    """The speed cap of the robot the panel was given (busservo_motion.least_dps()), which a
    calibration saved on its page keeps."""
    armed: str | None
    """The session token of the page that armed the panel, or None."""
    arm: Arm | None
    """The Arm the program gave to jog, or None (the jog part then makes one of the links)."""
    path: str
    """The calibration file: the links, and where the calibration page saves."""
    page: str
    """The page's file."""
    error: str | None
    """The last error of the panel's loop, shown on the page until 3 s after it last
    happened."""
    limp: bool
    """The joints were let go (limp or STOP) and not moved since."""
    busy: tuple[Any, str] | None
    """(part, why) while a part holds the joints (a sequence playing, a calibration under
    way): driving() refuses every other part, saying why."""
    orders: int
    """The number of the last order (order()): a read begun before it is void."""
    read_ms: int | None
    """How often (ms) the loop reads positions while a page is open (a part may make it
    shorter while it needs them; None: a part reads them itself, and the loop asks for
    none)."""
    options: dict[str, Any]
    """What the program gave serve() for the parts (its **options), as {name: value}."""
    halting: Any
    """The task of the last halt() (None before one), awaited as serve() ends."""
    parts: dict[str, Any]
    """{module: its part} of the parts plugged in."""
    robots: int
    """Robots the panel has had (a calibration saved gives it a new one): the page reads the
    joints again when this grows."""
    to: dict[str, float]
    """{name: degrees} a slider, a jog or a home last sent each joint towards (cleared by
    limp, STOP, a sequence and a calibration): the page's thumbs follow it."""
    def __init__(
        self,
        robot: Robot,
        password: str,
        arm: Arm | None = None,
        path: str | None = None,
        page: str | None = None,
        parts: tuple[tuple[Any, ...], ...] = ...,
        options: dict[str, Any] | None = None,
    ) -> None:
        """arm: an Arm on robot (ValueError if on another) for the jog part. parts: as
        serve() takes them; options: its **options."""
    # What the parts use.
    def add(self, part: Any) -> None:
        """Call the methods of part, those it has: await get_NAME(body, token) and
        post_NAME(body, token) answer GET and POST /api/NAME (the answer's JSON, or raise
        Refused; a POST's body is the dict of its JSON, a GET's is not read); state(out,
        token) adds its keys to the state; tick(read), each turn of the loop (read: positions
        came since the last); still(halt), when something else is ordered or the panel
        disarms (halt: a sequence's pose on the way too); free(), when another part needs
        the RAM (a calibration): let go of what it can make again; await close(), as serve()
        ends."""
    def plug(
        self,
        module: str,
        route: str | tuple[str, ...] | None = None,
        condition: Callable[[Any], Any] | None = None,
    ) -> None:
        """Plug in the part of module (module.attach(panel), which returns the part): now, or
        with route (NAME, or a tuple of them), when /api/NAME is first asked for, or
        condition(panel) holds (now, or once a calibration is saved)."""
    def unplug(self, module: str) -> None:
        """Take out the part of module, plugged in when first asked for, once it is done: it
        is plugged in again when next asked for (a part plugged in at once stays)."""
    def load(self, name: str) -> Any:
        """The module name, imported now if it is not yet, the heap collected first (its code
        then fills the holes that what came before left). How the core plugs parts in, and
        how a part imports what it needs only when used; unload() lets it go."""
    def unload(self, name: str) -> None:
        """Let go of module name, if load() imported it (the program did not): its RAM is
        free once nothing holds what it made, and load() imports it again."""
    def free(self, by: Any) -> None:
        """Every part but by lets go of what it can make again (its free()), and the heap is
        collected: for a part that takes much RAM (a calibration)."""
    def saved(self, key: str) -> bool:
        """True if the calibration file (path) holds key (as {"key": ...})."""
    def order(self, by: Any = None, halt: bool = False) -> int:
        """A new order, from part by (None: the core): every other part's still(halt); a read
        begun before it is void. Returns its number (orders)."""
    def driving(self, token: str, by: Any = None) -> None:
        """Refuse (409) unless the page of token has the panel armed and no part but by holds
        the joints (busy)."""
    def pose(self, pose: Any, what: str) -> dict[str, float]:
        """A pose {joint: degrees}, checked (known joints, within their limits); else Refused
        (400) naming what."""
    def halt(self, names: list[str]) -> None:
        """Send these joints where they are, once a read of them has come (a move stopped on
        its way: a sequence's pose, a replay's first pose), unless something else is ordered
        meanwhile (a stream, a limp, a STOP). Never waits: a task reads (halting)."""
    async def positions(self, ids: list[int]) -> dict[int, int | None]:
        """{servo_id: position} of ids, read now without blocking: the driver's
        BusServo.ask(), a step every 5 ms, so the panel's loop, the stream and the other
        pages go on while the reply is on its way. One such query at a time; raises
        OSError(ETIMEDOUT) as the driver's queries do."""
    async def where(self, names: list[str] | None = None) -> dict[str, float]:
        """{name: degrees} of these joints (all by default), as Robot.where() gives them, read
        as positions() reads."""
    def adopt(self, robot: Robot) -> None:
        """Drive robot from now on (the calibration just saved): the page reads its joints
        again."""
    def failed(self, e: BaseException) -> None:
        """Show e on the page until 3 s after it last happened."""
    # Safety.
    def disarm(self, halt: bool = True, why: str | None = None) -> None:
        """Stop driving: every part stops what it drives (the stream holds; a sequence stops,
        with halt where the joints are; a calibration is given up, its joints limp). why:
        what ended it, told to the armed page (the state's "lost")."""
    def estop(self, why: str | None = None) -> None:
        """Disarm at once, then Robot.estop(): every joint limp. why: as disarm() takes it."""
    def state(self, token: str | None = None) -> dict[str, Any]:
        """What GET /api/state answers: positions in degrees ("at") and the targets sent
        ("to"), battery, armed (and "mine": armed by token's page; "lost": why its arming
        ended, if something else ended it), limp, the loop's error, and what each part
        adds (the sequence's steps, the jog's arm and tool point, a calibration's step)."""
    async def handle_request(self, reader: Any, writer: Any) -> None:
        """Answer one connection's request (HTTP/1.0), then close it: serve()'s server calls
        this for each connection."""
    async def run(self) -> None:
        """The panel's loop, for ever: the bus's replies, the dead-man, the parts' ticks, the
        stream, and position and battery requests."""
