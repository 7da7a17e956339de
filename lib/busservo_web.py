# busservo_web: a control panel for a busservo_motion.Robot, served by the board
# itself to a browser on the same Wi-Fi (or on the board's own access point). This
# module is its core: HTTP and safety. What the page does (sliders, teaching and
# sequences, the arm's jog, the calibration page) are parts that plug into it.
#
#   import asyncio, busservo_web
#   asyncio.run(busservo_web.serve(robot, "a password of yours", port=80))
#
# The page is one file, lib/busservo_web.html, served gzipped (busservo_web.html.gz
# beside this module; no internet needed), a chunk at a time from the file. The HTTP
# side is this module's own, and small: a board without PSRAM has about 110 KB of heap
# once its Wi-Fi is up, and the panel should leave most of it to the robot's program.
#
# Safety. Nothing moves until a page is armed (its switch), and only the page that
# armed can drive. Disarming, closing that page or losing its connection ends what
# drives: when it has been silent for _DEAD_MS, every part stops (the stream holds
# where it is, a sequence stops where the joints are). The stop button (Robot.estop():
# every joint limp) works from any logged-in page, armed or not, mid-drag and
# mid-sequence. A page whose arming something else ended is told why (the state's
# "lost").
#
# Security. Without the password only the page itself is served (it shows a login
# form): every other request gets 401 and does nothing. The password is compared in
# constant time; a wrong one costs half a second, and more than _WRONG of them a minute
# from one client (or _WRONG_ALL from all) get 429 until the minute is over. A login's
# body must be JSON (Content-Type: application/json, which another site's page cannot
# send without asking), and gives the page a random token that it sends with each
# request (Authorization: Bearer). The board remembers _SESSIONS logins; a new one
# forgets the oldest, never the armed page's. Bad input gets a 4xx naming what was
# wrong and moves nothing. A connection has _HEAD_MS to send its request, of at most
# _REQUEST bytes (a body of at most _BODY, else 413); connections that say nothing, then
# those slow to say it, are pushed out by new ones; at most _CLIENTS are answered at
# once (more get 503), but a logged-in page is (up to twice as many): its STOP gets
# through. Whatever fails (the RAM, say), the connection is closed, with a 503 if its
# answer had not begun, and the server goes on. Plain HTTP: anyone who can watch the
# Wi-Fi can read the password. Use a network you trust, or the board's own access point
# with a WPA2 key.
#
# RAM: the core and its parts use loops where a comprehension would do: on MicroPython
# each comprehension is a function of its own (about 60 bytes of a 32-bit heap kept with
# the module, and made again at each call).
#
# The loop never waits on the wire: the positions a route needs are read with the
# driver's ask(), a step every few ms (Panel.positions()), so the stream, the dead-man
# and the other pages go on while the reply is on its way.
#
# The core's own routes (JSON in and out; errors are {"error": "..."}):
#   POST /api/login {"password"}   -> {"token"}
#   GET  /api/joints               -> [{"name", "lo", "hi"}, ...]
#   GET  /api/state                -> positions in degrees, battery, armed, ... (below)
#   POST /api/arm {"on"}, /api/estop
# and GET /favicon.ico -> 204, without a login (a browser asks for it before one). The
# parts add theirs (serve()'s default parts, PARTS below: each module's header lists its).
#
# Parts. A part is a module with attach(panel), which registers on the Panel an object
# (its part) and returns it; the part reaches the core only through this interface
# (docs/panel.md shows one):
#   panel.add(part)                     the core calls these methods of part, those it has:
#                                       get_NAME(body, token) and post_NAME(body, token)
#                                       answer GET and POST /api/NAME (the answer's JSON, or
#                                       raise Refused(status, why)): methods of its class (or
#                                       of one it comes from); a route the core or an
#                                       earlier part has stays theirs; state(out, token) adds
#                                       its keys to the state; tick(read) each turn of the
#                                       loop (read: positions came since the last); still(
#                                       halt) stops what it drives (halt: a sequence's pose
#                                       on the way too); free() lets go of what it can make
#                                       again (another part needs the RAM); close() is
#                                       awaited as serve() ends
#   panel.order(by)                     a new order, from part `by`: every other part's
#                                       still(); what began before it (a read) is void.
#                                       Returns its number: panel.orders is the last's
#   panel.driving(token, by)            refuse (409) unless token's page is armed, and no
#                                       part but by holds the joints (panel.busy)
#   await panel.positions(ids)          {servo_id: position}, read without waiting on the
#   await panel.where(names)            wire; {name: degrees}, as Robot.where() gives them
#   panel.pose(pose, what)              a pose {joint: degrees}, checked, or refused (400)
#   panel.halt(names)                   a move stopped on its way (a sequence's pose, a
#                                       replay's first pose): these joints are sent where
#                                       they are, once read, unless something is ordered
#                                       meanwhile (never waits: a task, panel.halting)
#   panel.adopt(robot)                  drive another robot (a calibration just saved)
#   panel.load(name), .unload(name)     import a module a part needs only when used (the
#                                       heap collected first), and let it go again
#   panel.unplug(module)                take a part plugged in when first asked for out,
#                                       once done (plugged in again when next asked for;
#                                       one plugged in at once stays)
#   panel.free(by)                      every part but by: free(); then a collection (a
#                                       calibration makes room: the jog lets its arm go)
#   panel.failed(e)                     show an error on the page while it lasts
#   panel.robot, .bus, .path            the robot, its bus, the calibration file
#   panel.to, .limp, .armed             targets shown (name: degrees), joints let go, the
#                                       armed page's token
#   panel.busy                          (part, why) while a part holds the joints (a
#                                       sequence playing, a calibration), else None
#   panel.read_ms                       how often positions are read while a page is open
#                                       (None: a part reads them itself, as a recording
#                                       does, and the loop asks for none)
#   panel.options                       {name: value}: what the program gave serve() for
#                                       the parts, as serve(robot, password, leader=robot2)
#                                       (busservo_web_record's teleop reads "leader")
#   Refused(status, why), need(body, key, kind, low, high, what): refusals, and checks
import asyncio
import binascii
import gc
import json
import os
import sys
import time

import busservo_motion as bm

try:
    from micropython import const
except ImportError:  # CPython, on a computer: busservo_cpython gives what it lacks
    from busservo_cpython import asyncio, const, json, time

# The limits and times (those not const() the tests read, or shorten):
_CLIENTS = const(4)  # requests being read, and answered, at once
_HEAD_MS = 1000  # a connection's request must be in within this, or it is closed
_REQUEST = const(4096)  # bytes: a request's line, headers and body; a longer one gets 400
_CLIENT_MS = 10000  # an answer that takes longer is cut
_SESSIONS = const(4)  # logins remembered; a new one forgets the oldest (never the armed page's)
_WRONG = const(10)  # wrong passwords a minute from one client; more get 429 till the minute ends
_WRONG_ALL = const(30)  # wrong passwords a minute from all clients
_WRONG_MS = const(60000)
_BODY = const(1024)  # bytes: a larger request body gets 413
_CHUNK = const(256)  # bytes of the page sent at a time
_DEAD_MS = const(1000)  # the armed page silent this long: hold (the dead-man)
_OPEN_MS = const(3000)  # a page asked within this: read positions often
_READ_MS = 150  # positions asked this often while a page is open
_BATTERY_MS = const(2000)
_TICK_MS = const(10)  # the panel's loop: poll the bus, step the stream and the parts
_ASK_MS = const(5)  # a query's next step: a byte takes 1 ms at 9600 baud
_ERROR_MS = const(3000)  # the loop's last error shows this long after it last happened
_POSITIONS = 21  # busservo.CMD_MULT_SERVO_POS_READ: a reply of positions
HALT_MS = 100  # a move stopped on its way (halt()): the joints go where they are, in this
# The parts serve() plugs in: (module, None: at once; or NAME: when /api/NAME is first asked
# for, or, with a condition, when condition(panel) holds: at the start, or once a
# calibration is saved; NAME may be a tuple of names, any of which plugs it in). The jog, the
# calibration page and the recording are loaded only when used: a panel without an arm keeps
# their RAM, and busservo_arm's, busservo_calibrate's and busservo_record's, for the robot's
# program.
PARTS = (
    ("busservo_web_sliders", None),
    ("busservo_web_teach", None),
    ("busservo_web_jog", "jog", lambda panel: panel.arm or panel.saved("links")),
    ("busservo_web_calibrate", "calibrate"),
    ("busservo_web_record", ("record", "replay", "teleop"), lambda p: "leader" in p.options),
)

# The page: beside this module (installed by mip or mpremote, or on the unix port), else in
# /lib (a module frozen into the firmware has no folder on the filesystem). Found here, at
# import, rather than by a function: the module's own code goes once it has run, and the RAM
# it took is the robot program's. serve(page=...) gives another.
try:
    PAGE = __file__.replace("\\", "/").rpartition("/")[0] or "."  # (Windows: backslashes)
except NameError:
    PAGE = "/lib"
for _folder in (PAGE, "/lib"):
    try:
        os.stat(_folder + "/busservo_web.html.gz")
        PAGE = _folder
        break
    except OSError:
        pass
del _folder
PAGE += "/busservo_web.html.gz"  # not there: serve() says so


def _same(given, secret):
    # True if given == secret, in a time that depends on given's length only:
    # an attacker timing a wrong guess learns nothing of where it went wrong.
    diff = len(given) ^ len(secret)
    n = len(secret) or 1
    for i in range(len(given)):
        diff |= given[i] ^ (secret[i % n] if secret else 0)
    return diff == 0 and len(secret) > 0


def _routes(kind):
    # The route methods (get_NAME, post_NAME; the core's begin with _) that class kind, or a
    # class it comes from, defines. A route is looked up among these, not with getattr()
    # alone: MicroPython keeps, for good, every name getattr() is asked for, and a page
    # asking for made-up routes would fill the heap. Read once a class (Panel._known): on
    # MicroPython each read of a class's __dict__ makes a copy of it.
    names = []
    for n in kind.__dict__:
        if n.lstrip("_")[:4] in ("get_", "post"):
            names.append(n)
    for base in kind.__bases__:
        if base is not object:
            names += _routes(base)
    return tuple(names)


class Refused(Exception):
    """A request the panel refuses: its HTTP status and why, which the page shows."""

    def __init__(self, status, why):
        super().__init__(why)
        self.status = status


def need(body, key, kind, low=None, high=None, what=None):
    """body[key], checked: of kind (int also stands for float), in low..high; else
    Refused(400) naming what (default: key), the range and what came."""
    value = body.get(key)
    what = what or key
    ok = type(value) is kind or (kind is float and type(value) is int)
    if not ok or (kind is float and not -1e9 < value < 1e9):  # NaN fails this too
        kind = "number" if kind is float else kind.__name__
        raise Refused(400, "%s must be a %s, got %r" % (what, kind, value))
    if low is not None and not low <= value <= high:
        raise Refused(400, "%s must be in %s..%s, got %r" % (what, low, high, value))
    return value


# The status lines the panel answers with, one a line (one bytes object: a dict of them
# keeps 352 bytes more of RAM, on a 32-bit port from .mpy).
_STATUS = (
    b"200 OK\n204 No Content\n400 Bad Request\n401 Unauthorized\n404 Not Found\n409 Conflict\n"
    b"413 Payload Too Large\n415 Unsupported Media Type\n429 Too Many Requests\n"
    b"500 Internal Server Error\n503 Service Unavailable\n504 Gateway Timeout\n"
)

# Answers made beforehand, whole: sent where making one could fail (no memory left), or
# would cost RAM for a connection that is let go (pushed out, or too slow).
_BUSY = (
    b"HTTP/1.0 503 Service Unavailable\r\nContent-Type: application/json\r\n"
    b'Content-Length: 29\r\n\r\n{"error": "too many clients"}'
)
_LATE = (
    b"HTTP/1.0 408 Request Timeout\r\nContent-Type: application/json\r\n"
    b'Content-Length: 38\r\n\r\n{"error": "the request took over 1 s"}'
)
_FAILED = (
    b"HTTP/1.0 503 Service Unavailable\r\nContent-Type: application/json\r\nContent-Length: 67"
    b'\r\n\r\n{"error": "the panel could not answer (out of memory?): try again"}'
)
_EMPTY = b"HTTP/1.0 204 No Content\r\n\r\n"


class _Conn:
    # A connection, read and written. It gives a request at most _REQUEST bytes
    # (MicroPython's readline() has no limit of its own), then ValueError: a 400. It notes
    # whether a byte came (a client that said something is told why it is closed) and
    # whether a write went out (until then a failure can still be answered 503).
    def __init__(self, reader, writer, due):
        self._reader = reader
        self._writer = writer
        self._buf = b""
        self._left = _REQUEST
        self.heard = False  # a byte has come
        self.sent = False  # a write has gone out whole: the status line first
        self.reading = True  # its request is being read (then answered)
        self.due = due  # ticks_ms by which the request must be in (then answered)
        self.cut = None  # what it is told if the panel cuts it (pushed out, too slow)

    def client(self):
        # Who is asking: the address the connection came from (its port left out).
        try:
            peer = self._writer.get_extra_info("peername")
        except Exception:
            return None
        return peer[0] if type(peer) is tuple else bytes(peer[4:8])  # (ip, port), or sockaddr_in

    async def _more(self):
        data = await self._reader.read(256)
        self.heard = self.heard or bool(data)
        self._left -= len(data)
        if self._left < 0:
            raise ValueError("the request is over %d bytes" % _REQUEST)
        self._buf += data
        return data

    async def readline(self):
        while b"\n" not in self._buf:
            if not await self._more():
                raise ValueError("the request was cut short")
        line, nl, self._buf = self._buf.partition(b"\n")
        return line

    async def read(self, n):
        # n bytes of the body (n <= _BODY), or b"" once the client has sent all.
        while len(self._buf) < n:
            if not await self._more():
                break
        data, self._buf = self._buf[:n], self._buf[n:]
        return data

    async def write(self, data):
        await self._writer.awrite(data)
        self.sent = True


async def _request(conn):
    # (method, path, the Authorization header's value, the body, whether the body is JSON by
    # its Content-Type) of the request on conn. A malformed one raises ValueError (a 400); a
    # body over _BODY, Refused (413).
    method, path, _ = (await conn.readline()).decode().split()
    path = path.partition("?")[0]
    auth = ""
    length = 0
    is_json = False
    while True:
        line = (await conn.readline()).strip()
        if not line:
            break
        name, colon, value = line.partition(b":")
        if not colon:
            raise ValueError("a header with no ':'")
        name = name.strip().lower()
        if name == b"content-length":
            length = int(value)
            if length < 0:
                raise ValueError("Content-Length %d" % length)
        elif name == b"authorization":
            auth = value.strip().decode()
        elif name == b"content-type":
            is_json = value.strip().lower().startswith(b"application/json")
    if length > _BODY:
        # Some of the body read, so that closing does not reset the connection before
        # the answer has gone; past that, the client hears a reset.
        for _ in range(8):
            try:
                if not await asyncio.wait_for_ms(conn.read(_BODY), 100):
                    break
            except asyncio.TimeoutError:
                break
        raise Refused(413, "the body is over %d bytes" % _BODY)
    body = await conn.read(length) if length else b""
    if len(body) < length:
        raise ValueError("the body was cut short")
    return method, path, auth, body, is_json


async def _answer(conn, status, answer):
    # A JSON answer (None: no body, 204).
    if answer is None:
        await conn.write(_EMPTY)
        return
    data = json.dumps(answer).encode()  # its length in bytes: a joint's name may be é
    at = _STATUS.find(b"%d " % status)
    await conn.write(
        b"HTTP/1.0 %s\r\nContent-Type: application/json\r\nContent-Length: %d\r\n\r\n"
        % (_STATUS[at : _STATUS.find(b"\n", at)], len(data))
    )
    await conn.write(data)


async def _page(conn, page, head):
    # The page, from its file a chunk at a time (head: its headers only).
    with open(page, "rb") as f:
        size = f.seek(0, 2)
        f.seek(0)
        await conn.write(
            b"HTTP/1.0 200 OK\r\nContent-Type: text/html; charset=utf-8\r\n"
            b"Content-Encoding: gzip\r\nContent-Length: %d\r\n"
            b"X-Frame-Options: DENY\r\nCache-Control: no-cache\r\n\r\n" % size
        )
        if head:
            return
        buf = bytearray(_CHUNK)
        view = memoryview(buf)
        while True:
            n = f.readinto(buf)
            if not n:
                break
            await conn.write(view[:n])


async def _close(writer):
    try:
        await writer.aclose()
    except Exception:
        pass


class Panel:
    """The panel's core: sessions and arming, STOP, the route table, the state, the loop
    and the HTTP side, for serve(); the parts plug into it (attach(panel)). A test may
    drive one directly."""

    def __init__(self, robot, password, arm=None, path=None, page=None, parts=PARTS, options=None):
        if type(password) is not str or len(password) < 8:
            # Why, never the password itself: the message may end up in a log or on a screen.
            got = type(password).__name__
            if got == "str":
                got = "%d characters" % len(password)
            raise ValueError("password must be a str of 8 or more characters, got " + got)
        if arm is not None and arm.robot is not robot:
            raise ValueError("arm must be an Arm on robot")
        self.arm = arm  # the program's Arm to jog, if it gave one (the jog part's)
        self.options = options or {}  # what the program gave the parts (serve()'s **options)
        # The calibration file: an arm's links, and where a calibration goes.
        self.path = path or bm.CALIBRATION
        self.page = page or PAGE
        self.bus = robot.bus
        self.dps = bm.least_dps(robot.joints)  # the speed cap a calibration saved here keeps
        self.robots = 0  # robots the panel has had (a calibration saved gives it another)
        self.limp = False  # joints let go by a limp or a STOP, until the next move
        self.armed = None  # the token of the page that armed, or None
        self.busy = None  # (part, why) while a part holds the joints, else None
        self.orders = 0  # one more with each order: a read begun before one is void
        self.read_ms = _READ_MS
        self.halting = None  # the task of the last halt(), awaited as serve() ends
        self.error = None  # the last error of the loop, for the page
        self._error_at = 0
        self._password = password.encode()
        self._sessions = []  # [token, ticks_ms last seen, why its arming ended], oldest first
        self._wrong = {}  # {client: wrong passwords} since _minute (ticks_ms)
        self._parts = []
        self._known = {}  # {class: _routes(class)} of the core and the parts, as asked for
        self._later = {}  # {NAME: the module of a part to plug in when /api/NAME is asked for}
        self._lazy = []  # (module, condition) of the parts not plugged in yet
        self._loaded = []  # the modules load() imported
        self.parts = {}  # {module: its part}, as attach() returns it
        # One query of the panel's on the bus at a time: True while one is (a flag, not an
        # asyncio.Lock: the lock's module would keep 448 bytes more of a board's heap).
        self._asking = False
        now = time.ticks_ms()
        self._seen = time.ticks_add(now, -_OPEN_MS)  # any page, last
        self._minute = now
        self._read = self._battery = now
        # Connections: (task, _Conn) of the requests being read or answered, oldest first
        # (the loop cuts those past their time); how many requests are being answered.
        self._conns = []
        self._clients = 0
        self.adopt(robot)  # (the robot, its servos' ids, to; no part is waiting yet)
        for part in parts:
            self.plug(*part)

    # What the parts use.

    def add(self, part):
        """Answer /api/NAME with part's get_NAME() and post_NAME(), and call its state(),
        tick(), still() and close(), those it has (this module's header says how)."""
        self._parts = self._parts + [part]  # (a new list, as unplug() makes)

    def plug(self, module, route=None, condition=None):
        """Plug in the part of module (its attach(self)): now, or with route (NAME), when
        /api/NAME is first asked for (route: NAME, or a tuple of them), or condition(self)
        holds (now, or once a calibration is saved). The one way parts are loaded."""
        if route and not (condition and condition(self)):
            for name in (route,) if type(route) is str else route:
                self._later[name] = module
            if condition:
                self._lazy.append((module, condition))
        elif module not in self.parts:
            self.parts[module] = self.load(module).attach(self)

    def unplug(self, module):
        """Take out the part of module, plugged in when first asked for, once it is done
        (the calibration page, its calibration over): its module is let go (unload()), and
        it is plugged in again when next asked for."""
        if module not in self._later.values():
            return  # plugged in at once (the program's parts): it stays, or it would be gone
        part = self.parts.pop(module, None)
        if part is not None:  # a new list: a loop over the parts (order()) goes on as it was
            parts = []
            for p in self._parts:
                if p is not part:
                    parts.append(p)
            self._parts = parts
            self._known = {}  # its class kept there would keep its module
            self.unload(module)

    def load(self, name):
        """The module name, imported now if it is not yet, the heap collected first (its
        code then fills the holes that what came before left: on a 32-bit port from .mpy,
        the panel without an arm serves within 3 KB less heap). How the core plugs parts
        in, and how a part imports what it needs only when used; unload() lets it go."""
        module = sys.modules.get(name)
        if module is None:
            gc.collect()
            module = __import__(name)
            self._loaded.append(name)
        return module

    def unload(self, name):
        """Let go of module name, if load() imported it (the program did not): its RAM is
        free once nothing holds what it made, and load() imports it again."""
        if name in self._loaded:
            self._loaded.remove(name)
            del sys.modules[name]

    def free(self, by):
        """Every part but by lets go of what it can make again (its free()), and the heap
        is collected: for a part that takes much RAM (a calibration)."""
        for part in self._parts:
            if part is not by and hasattr(part, "free"):
                part.free()
        gc.collect()

    def saved(self, key):
        """True if the calibration file (path) holds key (as {"key": ...})."""
        try:
            with open(self.path) as f:
                return ('"%s"' % key) in f.read()
        except OSError:
            return False  # no calibration file (yet)

    def order(self, by=None, halt=False):
        """A new order, from part by (None: the core): every other part stops what it drives
        (still(halt)), and a read begun before it is void. Returns its number."""
        self.orders += 1
        for part in self._parts:
            if part is not by and hasattr(part, "still"):
                part.still(halt)
        return self.orders

    def driving(self, token, by=None):
        """Refuse (409) unless the page of token has the panel armed and no part but by
        holds the joints (busy: a sequence playing, a calibration under way)."""
        if self.armed != token:
            raise Refused(409, "arm the panel first (another page may have it armed)")
        if self.busy and self.busy[0] is not by:
            raise Refused(409, self.busy[1])

    def pose(self, pose, what):
        """A pose {joint: degrees}, checked: known joints, within their limits; else
        Refused(400) naming what."""
        if type(pose) is not dict or not pose:
            raise Refused(400, "%s must be {joint: degrees}, got %r" % (what, pose))
        for name in pose:
            joint = self.robot.joints.get(name)
            if joint is None:
                raise Refused(400, "no joint %r: the joints are %s" % (name, self.robot.names))
            need(pose, name, float, joint.lo, joint.hi, "%s[%r]" % (what, name))
        return pose

    async def positions(self, ids):
        """{servo_id: position} of ids, read now without blocking: the driver's ask(), a step
        every few ms, while the loop, the stream and the other pages go on. One such query
        at a time; raises OSError(ETIMEDOUT) as the driver's queries do."""
        bus = self.bus
        while self._asking:  # another's: this one waits its turn
            await asyncio.sleep_ms(_ASK_MS)
        self._asking = True
        try:
            for _ in bus.ask(ids):
                await asyncio.sleep_ms(_ASK_MS)
            got = {}
            for i in ids:
                got[i] = bus.positions.get(i)
            return got
        finally:
            self._asking = False

    async def where(self, names=None):
        """{name: degrees} of these joints (all by default), as Robot.where() gives them,
        read as positions() reads."""
        robot = self.robot
        names = robot.names if names is None else names
        ids = []
        for name in names:
            ids.append(robot.joints[name].servo_id)
        got = await self.positions(ids)
        return robot.where(names, got)  # what came: it does not ask again

    def halt(self, names):
        """Send these joints where they are, once a read of them has come (a move stopped on
        its way: a sequence's pose, a replay's first pose), unless something else is ordered
        meanwhile (a stream, a limp, a STOP). Never waits: a task reads (panel.halting)."""
        self.halting = asyncio.create_task(self._halt(names, self.orders))

    async def _halt(self, names, orders):
        try:
            pose = await self.where(names)
            if self.orders == orders:  # nothing else ordered since: no stream, no limp
                self.robot.move(pose, ms=HALT_MS)
        except Exception as e:  # the controller did not answer: the move on its way is made
            self.failed(e)

    def adopt(self, robot):
        """Drive robot from now on (the calibration just saved): the page reads its joints
        again."""
        self.robot = robot
        self._ids = []
        for name in robot.names:
            self._ids.append(robot.joints[name].servo_id)
        self.to = {}  # {name: degrees} each joint was last sent towards (the thumbs follow)
        self.robots += 1
        for module, condition in self._lazy:
            if condition(self):
                self.plug(module)  # what the new calibration file calls for

    def failed(self, e):
        """Show e on the page, until _ERROR_MS after it last happened."""
        self.error = "%s: %s" % (type(e).__name__, e)
        self._error_at = time.ticks_ms()

    # Sessions.

    def _login(self, password, client=None):
        # The wrong passwords are counted by client, a minute at a time.
        now = time.ticks_ms()
        if time.ticks_diff(now, self._minute) > _WRONG_MS:
            self._minute = now
            self._wrong = {}
        wrong = self._wrong
        if wrong.get(client, 0) >= _WRONG or sum(wrong.values()) >= _WRONG_ALL:
            wait = (_WRONG_MS - time.ticks_diff(now, self._minute)) // 1000 + 1
            raise Refused(429, "too many wrong passwords: try again in %d s" % wait)
        if type(password) is not str or not _same(password.encode(), self._password):
            wrong[client] = wrong.get(client, 0) + 1
            return None
        token = binascii.hexlify(os.urandom(16)).decode()
        sessions = self._sessions
        sessions.append([token, now, None])
        if len(sessions) > _SESSIONS:  # the oldest forgotten, but not the armed page's
            sessions.pop(1 if sessions[0][0] == self.armed else 0)
        return token

    def _session(self, auth, note=True):
        # The session of an Authorization header's token (and note it was seen), or None.
        if not auth.startswith("Bearer "):
            return None
        given = auth[7:].encode()
        found = None
        for session in self._sessions:  # all compared: the time says nothing
            if _same(given, session[0].encode()):
                found = session
        if found and note:
            found[1] = self._seen = time.ticks_ms()
        return found

    # Safety: arming, the dead-man, STOP.

    def disarm(self, halt=True, why=None):
        """Stop driving: every part stops what it drives (the stream holds; a sequence
        stops, with halt where the joints are; a calibration is given up, its joints limp).
        why: what ended it, told to the armed page (when it was not that page's doing)."""
        if why:
            for session in self._sessions:
                if session[0] == self.armed:
                    session[2] = why
        self.armed = None
        self.order(halt=halt)
        self.robot.hold()

    def estop(self, why=None):
        """STOP: every joint limp, at once. why: as disarm() takes it."""
        self.disarm(halt=False, why=why)
        self.limp = True
        self.to = {}
        self.robot.estop()

    def state(self, token=None):
        """What the page shows; "mine": the page of token has the panel armed."""
        robot = self.robot
        positions = self.bus.positions
        at = []
        to = [] if self.to else None
        for name in robot.names:
            joint = robot.joints[name]
            p = positions.get(joint.servo_id)
            at.append(None if p is None else round(joint.degrees(p), 1))
            if to is not None:
                to.append(self.to.get(name))
        if self.error and time.ticks_diff(time.ticks_ms(), self._error_at) > _ERROR_MS:
            self.error = None  # over: it has not happened again for a while
        lost = None
        for session in self._sessions:
            if session[0] == token:
                lost = session[2]
        out = {
            "at": at,
            "to": to,
            "robots": self.robots,  # the page reads the joints again when this grows
            "battery": self.bus.battery,
            "armed": self.armed is not None,
            "mine": token is not None and self.armed == token,
            "lost": lost,
            "limp": self.limp,
            "updates": robot.updates,
            "error": self.error,
        }
        for part in self._parts:
            if hasattr(part, "state"):
                part.state(out, token)
        return out

    # The loop: the bus's replies, the dead-man, the parts, the stream and the reads.

    async def run(self):
        """Run for ever (until cancelled): serve() runs it beside the web server."""
        while True:
            try:
                self._tick()
            except Exception as e:  # the panel must go on, and say so
                self.failed(e)
                try:
                    self.order(halt=True)  # a sequence stops where the joints are
                except Exception:
                    self.order()  # the bus failed: stop sending, at least
            await asyncio.sleep_ms(_TICK_MS)

    def _tick(self):
        now = time.ticks_ms()
        conns = self._conns
        for i in range(len(conns) - 1, -1, -1):  # not in, or not answered, in time: cut
            if time.ticks_diff(now, conns[i][1].due) >= 0:  # (first: the bus may fail)
                self._cut(conns[i], _LATE if conns[i][1].reading else _FAILED)
        bus = self.bus
        read = False
        while True:  # replies update bus.positions and bus.battery
            cmd = bus.poll()
            if cmd is None:
                break
            read = read or cmd == _POSITIONS
        if self.armed is not None:
            for token, seen, _ in self._sessions:
                if token == self.armed and time.ticks_diff(now, seen) > _DEAD_MS:
                    self.disarm(why="disarmed: this page was silent for over 1 s (the dead-man)")
        for part in self._parts:
            if hasattr(part, "tick"):
                part.tick(read)
        if self.armed is not None:
            self.robot.step()  # the stream the parts fed
        if bus.wire_ms() or self._asking:
            return  # the stream, a sequence and a route's query come first
        open_ = time.ticks_diff(now, self._seen) < _OPEN_MS
        every = self.read_ms if open_ else _OPEN_MS
        if self.read_ms is None:
            pass  # a part reads the positions itself: a read of the loop's would cut in
        elif time.ticks_diff(now, self._read) >= every:
            self._read = now
            bus.request_positions(self._ids)
        elif open_ and time.ticks_diff(now, self._battery) >= _BATTERY_MS:
            self._battery = now
            bus.request_battery()

    # The HTTP side. Each connection carries one request (HTTP/1.0), and is then closed.
    # - A request must be in within _HEAD_MS (else 408). When _CLIENTS connections are
    #   still reading theirs, a new one pushes out the oldest that has sent nothing yet,
    #   else the oldest (which hears 503). So connections that say nothing, or little,
    #   hold nothing, and a page's request, sent at once, gets in.
    # - At most _CLIENTS requests are answered at once, each within _CLIENT_MS; more
    #   get 503, except a logged-in page's (up to twice as many).
    # - Every connection ends closed, whatever is raised: an error (a MemoryError, say)
    #   before its answer has begun is answered 503; after, the answer is cut.

    async def handle_request(self, reader, writer):
        """Answer the request of one connection, then close it (serve()'s server calls
        this for each)."""
        conn = mine = None
        try:
            conn = _Conn(reader, writer, time.ticks_add(time.ticks_ms(), _HEAD_MS))
            conns = self._conns
            # A request sent whole is read within a few ms: the ones still reading when
            # more come are the silent, then the slow.
            out = None
            reading = 0
            for c in conns:
                if c[1].reading:
                    reading += 1
                    if out is None or out[1].heard and not c[1].heard:
                        out = c
            if reading >= _CLIENTS:
                self._cut(out, _BUSY)
            mine = (asyncio.current_task(), conn)
            conns.append(mine)
            try:
                request = await _request(conn)
            except asyncio.CancelledError:  # pushed out by a newer connection, or too slow
                if conn.cut is None:
                    raise  # not the panel's doing: serve() is ending
                if conn.heard:
                    await conn.write(conn.cut)
                return
            except Refused as e:  # too large
                request = e
            except (ValueError, UnicodeError):  # malformed, cut short, or too long
                request = Refused(400, "bad request")
            conn.reading = False
            if self._clients >= _CLIENTS and (
                self._clients >= 2 * _CLIENTS
                or type(request) is not tuple
                or not self._session(request[2], note=False)
            ):
                await conn.write(_BUSY)
                return
            conn.due = time.ticks_add(time.ticks_ms(), _CLIENT_MS)
            self._clients += 1
            try:
                await self._dispatch(conn, request)
            finally:
                self._clients -= 1
        except (Exception, asyncio.CancelledError) as e:  # out of memory, say, or an answer
            # over _CLIENT_MS (cut); an OSError is the client gone
            if type(e) is asyncio.CancelledError and (conn is None or conn.cut is None):
                raise  # not the panel's doing: serve() is ending
            gone = isinstance(e, OSError)
            if not (gone or conn and conn.sent):
                try:
                    await writer.awrite(_FAILED)
                except Exception:
                    pass
        finally:
            if mine in self._conns:
                self._conns.remove(mine)
            await _close(writer)

    def _defines(self, part, name):
        # True if part's class (or one it comes from) has route method name (see _routes).
        kind = type(part)
        names = self._known.get(kind)
        if names is None:
            names = self._known[kind] = _routes(kind)
        return name in names

    def _cut(self, c, answer):
        # End connection c = (task, _Conn), which is told answer if it said something.
        self._conns.remove(c)
        c[1].cut = answer
        c[0].cancel()

    async def _dispatch(self, conn, request):
        # Answer a request: the route's answer, or why not ({"error": why}).
        try:
            if type(request) is not tuple:
                raise request  # refused as it was read
            method, path, auth, body, is_json = request
            if path == "/" and method in ("GET", "HEAD"):
                await _page(conn, self.page, method == "HEAD")
                return
            if path == "/favicon.ico" and method == "GET":
                await _answer(conn, 204, None)  # no icon: nothing to log in for
                return
            name = path[5:] if path.startswith("/api/") else ""
            if name == "login" and method == "POST":
                answer = await self._post_login(body, is_json, conn.client())
            else:
                session = self._session(auth)
                if session is None:
                    raise Refused(401, "log in first")
                handler = None
                if name.isalpha() and method in ("GET", "POST"):
                    if name in self._later:  # a part plugged in when first asked for
                        self.plug(self._later[name])  # (once: by any name, till unplugged)
                    attr = "%s_%s" % (method.lower(), name)
                    if self._defines(self, "_" + attr):  # the core's own
                        handler = getattr(self, "_" + attr)
                    for part in self._parts:
                        if handler is None and self._defines(part, attr):
                            handler = getattr(part, attr)
                if handler is None:
                    raise Refused(404, "no such page")
                if method == "POST":
                    try:
                        body = json.loads(body) if body else {}
                    except ValueError:
                        raise Refused(400, "the body is not JSON")
                    if type(body) is not dict:
                        raise Refused(400, "the body must be a JSON object, got %r" % (body,))
                answer = await handler(body, session[0])
            status = 200
        except Refused as e:
            status, answer = e.status, {"error": e.args[0]}
        except (ValueError, TypeError) as e:  # the motion layer's checks
            status, answer = 400, {"error": str(e)}
        except OSError as e:  # the controller did not answer, or the UART failed
            status, answer = 504, {"error": "the controller: %r" % (e,)}
        await _answer(conn, status, answer)

    # The core's routes.

    async def _post_login(self, body, is_json, client):
        if not is_json:
            raise Refused(415, "send the password as JSON (Content-Type: application/json)")
        try:
            body = json.loads(body)
        except ValueError:
            body = None
        if type(body) is not dict:
            raise Refused(400, 'the body must be {"password": "..."}')
        token = self._login(body.get("password"), client)
        if token is None:
            await asyncio.sleep_ms(500)  # a guess costs time
            raise Refused(401, "wrong password")
        return {"token": token}

    async def _get_joints(self, body, token):
        joints = self.robot.joints
        out = []
        for n in self.robot.names:
            out.append({"name": n, "lo": joints[n].lo, "hi": joints[n].hi})
        return out

    async def _get_state(self, body, token):
        return self.state(token)

    async def _post_arm(self, body, token):
        if need(body, "on", bool):
            if self.armed not in (None, token):
                raise Refused(409, "another page has the panel armed")
            orders = self.orders
            self.robot.hold()  # arming moves nothing: targets come from the page
            await self.where()  # where the joints are (a joint with a dps limit needs it)
            if self.orders != orders or self.armed not in (None, token):
                raise Refused(409, "stopped, or armed elsewhere, while arming: arm again")
            self.armed = token
            for session in self._sessions:
                if session[0] == token:
                    session[2] = None  # armed again: what ended it before is over
        elif self.armed == token:
            self.disarm()
        return self.state(token)

    async def _post_estop(self, body, token):
        self.estop(None if self.armed == token else "another page pressed STOP")
        return self.state(token)


async def serve(
    robot,
    password,
    port=80,
    arm=None,
    path=None,
    host="0.0.0.0",
    parts=PARTS,
    page=None,
    **options,
):
    """Serve the panel for robot on port, on host's interface (default: every one), until
    cancelled. password: a str of 8 or more characters, which the page asks for. arm: a
    busservo_arm.Arm on robot to jog (default: the one path's links make, if it has them).
    path: the calibration file (default busservo_motion.CALIBRATION: an arm's links, and
    where the calibration page saves).
    parts: the parts to plug in, as PARTS gives them (all of them). page: the page's file
    (default: beside this module). options: settings for the parts, kept as panel.options
    (leader=robot2: a leader arm that drives robot, turned on and off from the page, as
    busservo_web_record offers it)."""
    panel = Panel(robot, password, arm, path, page, parts, options)
    try:
        os.stat(panel.page)
    except OSError:
        raise OSError(2, "the page %s is missing: install it beside busservo_web" % panel.page)
    loop = asyncio.create_task(panel.run())
    server = None
    try:
        # Each connection through the attribute, so that a test may wrap it.
        server = await asyncio.start_server(lambda r, w: panel.handle_request(r, w), host, port)
        await server.wait_closed()
    finally:
        loop.cancel()
        if server:
            server.close()
        for c in list(panel._conns):  # the loop cut them: now nothing would
            panel._cut(c, _BUSY)
        panel.disarm()
        for part in panel._parts:
            if hasattr(part, "close"):
                await part.close()
        if panel.halting:
            await panel.halting  # a move stopped on its way: where the joints are
