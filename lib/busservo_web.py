# busservo_web: a control panel for a busservo_motion.Robot, served by the board
# itself to a browser on the same Wi-Fi (or on the board's own access point):
# a slider per joint, live positions, the battery, teach and play back, and an
# emergency stop. It runs on asyncio, beside the robot's own tasks:
#
#   import asyncio, busservo_web
#   asyncio.run(busservo_web.serve(robot, "a password of yours", port=80))
#
# The page is one file, lib/busservo_web.html, served gzipped (busservo_web.html.gz
# beside this module; no internet needed), a chunk at a time from the file. The HTTP
# side is this module's own, and small: a board without PSRAM has about 110 KB of heap
# once its Wi-Fi is up, and the panel should leave most of it to the robot's program.
#
# Safety. Nothing moves until a page is armed (its switch), and only the page
# that armed can drive. Disarming, closing that page or losing its connection
# ends the stream: when it has been silent for _DEAD_MS, the stream stops and
# the joints hold where they are (Robot.hold()), and a sequence stops playing,
# its pose on the way too (the joints it moves are sent where they are).
# The stop button (Robot.estop(): every joint limp) works from any logged-in
# page, armed or not, mid-drag and mid-sequence.
#
# Security. Without the password only the page itself is served (it shows a
# login form): every other request gets 401 and does nothing. The password is
# compared in constant time; a login gives the page a random token that it sends
# with each request (Authorization: Bearer). Bad input gets a 4xx naming what was
# wrong and moves nothing. A connection has _HEAD_MS to send its request, of at
# most _REQUEST bytes (a body of at most _BODY, else 413); connections that say
# nothing, then those slow to say it, are pushed out by new ones; at most _CLIENTS
# are answered at once (more get 503), but a logged-in page is (up to twice as
# many): its STOP gets through. Whatever fails (the RAM, say), the connection is
# closed, with a 503 if its answer had not begun, and the server goes on.
# Sequences are saved under sequences/ by a name of letters, digits, - and _.
# Plain HTTP: anyone who can watch the Wi-Fi can read the password. Use a
# network you trust, or the board's own access point with a WPA2 key.
#
# The loop never waits on the wire: the positions a route needs (arm, capture, add,
# a stop's halt) are read with the driver's ask(), a step every few ms, so the
# stream, the dead-man and the other pages go on while the reply is on its way.
#
# What the page asks for (JSON in and out; errors are {"error": "..."}):
#   POST /api/login {"password"}   -> {"token"}
#   GET  /api/joints               -> [{"name", "lo", "hi"}, ...]
#   GET  /api/state                -> positions in degrees, battery, armed, sequence, ...
#   GET  /api/steps                -> the sequence: [{"pose": {name: degrees}, "ms"}, ...]
#   POST /api/arm {"on"}, /api/target {"targets": {name: degrees}}, /api/estop,
#        /api/limp, /api/capture -> {"pose"}, /api/add {"pose", "ms"} (no pose: read now),
#        /api/edit {"index", "pose", "ms"}, /api/remove {"index"}, /api/clear,
#        /api/play {"speed", "loop"}, /api/stop, /api/save {"name"}, /api/load {"name"}
#   GET  /api/sequences            -> ["name", ...]
#   POST /api/jog {"axis": "x"|"y"|"z"|"pitch", "by"} (with an arm: mm, or degrees of pitch)
#   POST /api/calibrate {"step": "start"|"rest"|"nudge"|"check"|"save"|"home"|"cancel"}
#        ("save" may give "links" {name: mm}; "home" needs "confirm": true)
# and GET /favicon.ico -> 204, without a login (a browser asks for it before one).
import asyncio
import json
import os
import time

try:
    import micropython  # noqa: F401 (on a board; CPython has none)
except ImportError:  # CPython, on a computer: busservo_cpython gives what it lacks
    from busservo_cpython import asyncio, json, time

import busservo_motion as bm

_CLIENTS = 4  # requests being read, and answered, at once
_HEAD_MS = 1000  # a connection's request must be in within this, or it is closed
_REQUEST = 4096  # bytes: a request's line, headers and body; a longer one gets 400
_CLIENT_MS = 10000  # an answer that takes longer is cut
_SESSIONS = 4  # logins remembered; a new one forgets the oldest
_BODY = 1024  # bytes: a larger request body gets 413
_CHUNK = 256  # bytes of the page sent at a time
_DEAD_MS = 1000  # the armed page silent this long: hold (the dead-man)
_OPEN_MS = 3000  # a page asked within this: read positions often
_READ_MS = 150  # positions asked this often while a page is open
_BATTERY_MS = 2000
_TICK_MS = 10  # the panel's loop: poll the bus, step the stream and the player
_ASK_MS = 5  # a query's next step: a byte takes 1 ms at 9600 baud
_ERROR_MS = 3000  # the loop's last error is shown until this long after it last happened
_FOLDER = "sequences"
_NAME_MAX = 24
_MS_DEFAULT = 1000  # time to reach an added pose, if the request gives none
_HALT_MS = 100  # a sequence stopped mid-pose: the joints go where they are, in this
_CALIBRATION = "robot.json"  # busservo_board.CALIBRATION: the joints, and an arm's links
_CAL_READ_MS = 100  # positions read this often while a calibration sweeps or is nudged
_NAME_CHARS = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_"


# The page: beside this module (installed by mip or mpremote, or on the unix port), else in
# /lib (a module frozen into the firmware has no folder on the filesystem). Found here, at
# import, rather than by a function: the module's own code goes once it has run, and the RAM
# it took is the robot program's.
try:
    _PAGE = __file__.rpartition("/")[0] or "."
except NameError:
    _PAGE = "/lib"
for _folder in (_PAGE, "/lib"):
    try:
        os.stat(_folder + "/busservo_web.html.gz")
        _PAGE = _folder
        break
    except OSError:
        pass
del _folder
_PAGE += "/busservo_web.html.gz"  # not there: serve() says so


def _same(given, secret):
    # True if given == secret, in a time that depends on given's length only:
    # an attacker timing a wrong guess learns nothing of where it went wrong.
    diff = len(given) ^ len(secret)
    n = len(secret) or 1
    for i in range(len(given)):
        diff |= given[i] ^ (secret[i % n] if secret else 0)
    return diff == 0 and len(secret) > 0


class _Refused(Exception):
    # A request the panel refuses: its status code and why.
    def __init__(self, status, why):
        super().__init__(why)
        self.status = status


def _need(body, key, kind, low=None, high=None, what=None):
    # body[key], checked: of kind (int also stands for float), in low..high.
    value = body.get(key)
    what = what or key
    ok = type(value) is kind or (kind is float and type(value) is int)
    if not ok or (kind is float and not -1e9 < value < 1e9):  # NaN fails this too
        kind = "number" if kind is float else kind.__name__
        raise _Refused(400, "%s must be a %s, got %r" % (what, kind, value))
    if low is not None and not low <= value <= high:
        raise _Refused(400, "%s must be in %s..%s, got %r" % (what, low, high, value))
    return value


# The status lines the panel answers with.
_STATUS = {
    200: b"200 OK",
    204: b"204 No Content",
    400: b"400 Bad Request",
    401: b"401 Unauthorized",
    404: b"404 Not Found",
    409: b"409 Conflict",
    413: b"413 Payload Too Large",
    500: b"500 Internal Server Error",
    503: b"503 Service Unavailable",
    504: b"504 Gateway Timeout",
}

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
_POSITIONS = 21  # busservo.CMD_MULT_SERVO_POS_READ: a reply of positions


def _name(body):
    # A sequence's name, safe as a file name under _FOLDER.
    name = body.get("name")
    if (
        type(name) is not str
        or not 1 <= len(name) <= _NAME_MAX
        or not all(c in _NAME_CHARS for c in name)
    ):
        raise _Refused(
            400, "name must be 1..%d letters, digits, - or _, got %r" % (_NAME_MAX, name)
        )
    return _FOLDER + "/" + name + ".json"


class _Conn:
    # A connection, read and written. It gives a request at most _REQUEST bytes
    # (MicroPython's readline() has no limit of its own), then ValueError: a 400. It notes
    # whether a byte came (a client that said something is told why it is closed) and
    # whether a write went out (until then a failure can still be answered 503).
    def __init__(self, reader, writer):
        self._reader = reader
        self._writer = writer
        self._buf = b""
        self._left = _REQUEST
        self.heard = False  # a byte has come
        self.sent = False  # a write has gone out whole: the status line first

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
    # (method, path, the Authorization header's value, the body) of the request on conn.
    # A malformed one raises ValueError (a 400); a body over _BODY, _Refused (413).
    method, path, _ = (await conn.readline()).decode().split()
    path = path.partition("?")[0]
    auth = ""
    length = 0
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
    if length > _BODY:
        # Some of the body read, so that closing does not reset the connection before
        # the answer has gone; past that, the client hears a reset.
        for _ in range(8):
            try:
                if not await asyncio.wait_for_ms(conn.read(_BODY), 100):
                    break
            except asyncio.TimeoutError:
                break
        raise _Refused(413, "the body is over %d bytes" % _BODY)
    body = await conn.read(length) if length else b""
    if len(body) < length:
        raise ValueError("the body was cut short")
    return method, path, auth, body


async def _answer(conn, status, answer):
    # A JSON answer (None: no body, 204).
    if answer is None:
        await conn.write(_EMPTY)
        return
    data = json.dumps(answer).encode()  # its length in bytes: a joint's name may be é
    await conn.write(
        b"HTTP/1.0 %s\r\nContent-Type: application/json\r\nContent-Length: %d\r\n\r\n"
        % (_STATUS[status], len(data))
    )
    await conn.write(data)


async def _page(conn, head):
    # The page, from its file a chunk at a time (head: its headers only).
    with open(_PAGE, "rb") as f:
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
    """The panel's state, its loop and its HTTP side, for serve(); a test may drive one
    directly."""

    # The jog's and the calibration's, here until they are used (a panel without an arm
    # keeps its instances' RAM): busservo_web_arm sets them.
    no_arm = None  # why there is no arm to jog, if the file's links make none
    _line = None  # a jog's busservo_arm.Line on its way
    _jog = None  # [x, y, z, pitch] the jogs have reached, while _jogged == _orders
    _jogged = -1
    cal = None  # a busservo_calibrate.Calibration under way
    _cal = None  # its news: {"step", "seen", "why", "joints"}

    def __init__(self, robot, password, arm=None, path=_CALIBRATION):
        if type(password) is not str or len(password) < 8:
            # Why, never the password itself: the message may end up in a log or on a screen.
            got = type(password).__name__
            if got == "str":
                got = "%d characters" % len(password)
            raise ValueError("password must be a str of 8 or more characters, got " + got)
        if arm is not None and arm.robot is not robot:
            raise ValueError("arm must be an Arm on robot")
        self.path = path  # the calibration file: an arm's links, and where a calibration goes
        self.robot = robot
        self.bus = robot.bus
        self._ids = [robot.joints[name].servo_id for name in robot.names]
        self.to = {}  # {name: degrees} the page or a jog last sent each joint towards
        self.robots = 1  # robots the panel has had (a calibration saved gives it another)
        if arm is None:  # the arm its calibration file's links make, if it has links
            try:
                with open(path) as f:
                    if '"links"' in f.read():
                        arm = _arm_part().arm(self, robot)  # (busservo_arm imported then)
            except OSError:
                pass  # no calibration file (yet)
        self.arm = arm
        self._password = password.encode()
        self._sessions = []  # [token, ticks_ms last seen], oldest first
        self.armed = None  # the token of the page that armed, or None
        self.sequence = bm.Sequence()
        self.edits = 0  # changes to the sequence: the page reads it again when this grows
        self.player = None
        self.error = None  # the last error of the loop, for the page
        self._error_at = 0
        self.limp = False  # joints let go by limp() or estop(), until the next move
        self._orders = 0  # bumped by each order: a halt or an arm begun before one is void
        self._halting = None  # the task that halts a sequence stopped mid-pose
        self._asking = asyncio.Lock()  # one query of the panel's on the bus at a time
        now = time.ticks_ms()
        self._seen = time.ticks_add(now, -_OPEN_MS)  # any page, last
        self._read = self._battery = now
        # Connections: (task, _Conn) of the requests being read, oldest first; how many
        # requests are being answered.
        self._reading = []
        self._clients = 0

    # Sessions.

    def _login(self, password):
        if type(password) is not str or not _same(password.encode(), self._password):
            return None
        token = "".join("%02x" % b for b in os.urandom(16))
        self._sessions.append([token, time.ticks_ms()])
        if len(self._sessions) > _SESSIONS:
            old = self._sessions.pop(0)
            if old[0] == self.armed:
                self.disarm()
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

    # Reading positions without waiting on the wire.

    async def where(self, names=None):
        """{name: degrees} of these joints (all by default), as Robot.where() gives them,
        read now without blocking: the query is the driver's ask(), a step every few ms,
        while the loop, the stream and the other pages go on."""
        robot = self.robot
        names = robot.names if names is None else names
        ids = [robot.joints[name].servo_id for name in names]
        async with self._asking:
            for _ in self.bus.ask(ids):
                await asyncio.sleep_ms(_ASK_MS)
            return robot.where(names, self.bus.positions)  # what came: it does not ask again

    # What the page can do.

    def disarm(self, halt=True):
        """Stop driving: the stream ends (the joints hold), a jog and the sequence stop, and
        a calibration is given up (its joints stay limp)."""
        self.armed = None
        self._still()
        self.cal = None
        self.stop(halt)

    def _still(self):
        # End the stream and a jog's line: each joint stops at the last target sent.
        if self._line:
            self._line.stop()
            self._line = None
        self.robot.hold()

    def stop(self, halt=True):
        """Stop the sequence; with halt, its pose on the way too (which would go on for
        its ms): the joints it moves are sent where they are, once a read of their
        positions has come (about 30 ms; the loop goes on meanwhile)."""
        self._orders += 1
        player = self.player
        self.player = None
        if player and not player.done:
            player.stop()
            if halt:
                names = set()
                for pose, _ in self.sequence.steps:
                    names.update(pose)
                self._halting = asyncio.create_task(self._halt(list(names), self._orders))

    async def _halt(self, names, orders):
        try:
            pose = await self.where(names)
            if self._orders == orders:  # nothing else ordered since: no stream, no limp
                self.robot.move(pose, ms=_HALT_MS)
        except Exception as e:  # the controller did not answer: the pose is reached
            self._failed(e)

    def estop(self):
        self.disarm(halt=False)  # at once: the joints go limp
        self.limp = True
        self.to = {}
        self.robot.estop()

    def _failed(self, e):
        self.error = "%s: %s" % (type(e).__name__, e)
        self._error_at = time.ticks_ms()

    def _driver(self, token):
        if self.armed != token:
            raise _Refused(409, "arm the panel first (another page may have it armed)")
        if self.cal:  # nothing moves but the calibration's home
            raise _Refused(409, "a calibration is under way: finish or cancel it first")

    def _pose(self, pose, what):
        # A pose {joint: degrees}, checked: known joints, within their limits.
        if type(pose) is not dict or not pose:
            raise _Refused(400, "%s must be {joint: degrees}, got %r" % (what, pose))
        for name in pose:
            joint = self.robot.joints.get(name)
            if joint is None:
                raise _Refused(400, "no joint %r: the joints are %s" % (name, self.robot.names))
            _need(pose, name, float, joint.lo, joint.hi, "%s[%r]" % (what, name))
        return pose

    def _not_playing(self):
        if self.player:
            raise _Refused(409, "a sequence is playing: stop it first")

    def _target(self, token, targets):
        self._driver(token)
        self._not_playing()
        targets = self._pose(targets, "targets")
        self._orders += 1
        if self._line:
            self._still()  # the slider takes over from a jog
        self.robot.stream(targets)
        self.to.update(targets)
        self.limp = False

    def _play(self, token, speed, loop):
        self._driver(token)
        if not self.sequence.steps:
            raise _Refused(409, "the sequence is empty: add poses first")
        self._orders += 1
        self._still()
        self.to = {}
        self.player = self.sequence.play(self.robot, speed, loop)
        self.limp = False

    def state(self, token=None):
        """What the page shows; "mine": the page of token has the panel armed."""
        robot = self.robot
        positions = self.bus.positions
        at = []
        for name in robot.names:
            joint = robot.joints[name]
            p = positions.get(joint.servo_id)
            at.append(None if p is None else round(joint.degrees(p), 1))
        player = self.player
        if self.error and time.ticks_diff(time.ticks_ms(), self._error_at) > _ERROR_MS:
            self.error = None  # over: it has not happened again for a while
        out = {
            "at": at,
            "to": [self.to.get(name) for name in robot.names] if self.to else None,
            "robots": self.robots,  # the page reads the joints again when this grows
            "battery": self.bus.battery,
            "armed": self.armed is not None,
            "mine": token is not None and self.armed == token,
            "limp": self.limp,
            "steps": [ms for _, ms in self.sequence.steps],
            "edits": self.edits,
            "playing": player.index if player else None,
            "updates": robot.updates,
            "error": self.error,
        }
        if self.arm or self.cal:  # only then: a panel without an arm answers as before
            _arm_part().state(self, out, at)
        return out

    # The loop: the bus's replies, the stream, the player, the dead-man and the reads.

    async def run(self):
        """Run for ever (until cancelled): serve() runs it beside the web server."""
        while True:
            try:
                self._tick()
            except Exception as e:  # the panel must go on, and say so
                self._failed(e)
                try:
                    self.stop()
                except Exception:
                    self.stop(halt=False)  # the bus failed: stop sending, at least
            await asyncio.sleep_ms(_TICK_MS)

    def _tick(self):
        bus = self.bus
        read = False
        while True:  # replies update bus.positions and bus.battery
            cmd = bus.poll()
            if cmd is None:
                break
            read = read or cmd == _POSITIONS
        now = time.ticks_ms()
        if self.armed is not None:
            for token, seen in self._sessions:
                if token == self.armed and time.ticks_diff(now, seen) > _DEAD_MS:
                    self.disarm()
            if self._line:
                _arm_part().step(self)  # a jog: its line's next point, sent when it can be
            self.robot.step()
        if self.cal and read:
            _arm_part().feel(self)  # the positions just read: the sweep's, or the nudge's
        if self.player:
            if self.player.done:
                self.player = None
            else:
                self.player.step()
        if bus.wire_ms() or self._asking.locked():
            return  # the stream, the player and a route's query come first
        open_ = time.ticks_diff(now, self._seen) < _OPEN_MS
        every = (_CAL_READ_MS if self.cal else _READ_MS) if open_ else _OPEN_MS
        if time.ticks_diff(now, self._read) >= every:
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
        conn = None
        try:
            conn = _Conn(reader, writer)
            reading = self._reading
            if len(reading) >= _CLIENTS:
                # A request sent whole is read within a few ms: the ones still reading
                # when more come are the silent, then the slow.
                out = 0
                for i in range(len(reading)):
                    if not reading[i][1].heard:
                        out = i
                        break
                reading.pop(out)[0].cancel()
            mine = (asyncio.current_task(), conn)
            reading.append(mine)
            try:
                request = await asyncio.wait_for_ms(_request(conn), _HEAD_MS)
            except asyncio.TimeoutError:
                if conn.heard:
                    await conn.write(_LATE)
                return
            except asyncio.CancelledError:  # pushed out by a newer connection
                if conn.heard:
                    await conn.write(_BUSY)
                return
            except _Refused as e:  # too large
                request = e
            except (ValueError, UnicodeError):  # malformed, cut short, or too long
                request = _Refused(400, "bad request")
            finally:
                if mine in reading:
                    reading.remove(mine)
            if self._clients >= _CLIENTS and (
                self._clients >= 2 * _CLIENTS
                or type(request) is not tuple
                or not self._session(request[2], note=False)
            ):
                await conn.write(_BUSY)
                return
            self._clients += 1
            try:
                await asyncio.wait_for_ms(self._dispatch(conn, request), _CLIENT_MS)
            finally:
                self._clients -= 1
        except Exception as e:  # out of memory, say, or an answer over _CLIENT_MS; an
            # OSError is the client gone (CPython's TimeoutError is an OSError too)
            gone = isinstance(e, OSError) and not isinstance(e, asyncio.TimeoutError)
            if not (gone or conn and conn.sent):
                try:
                    await writer.awrite(_FAILED)
                except Exception:
                    pass
        finally:
            await _close(writer)

    async def _dispatch(self, conn, request):
        # Answer a request: the route's answer, or why not ({"error": why}).
        try:
            if type(request) is not tuple:
                raise request  # refused as it was read
            method, path, auth, body = request
            if path == "/" and method in ("GET", "HEAD"):
                await _page(conn, method == "HEAD")
                return
            if path == "/favicon.ico" and method == "GET":
                await _answer(conn, 204, None)  # no icon: nothing to log in for
                return
            name = path[5:] if path.startswith("/api/") else ""
            if name == "login" and method == "POST":
                answer = await self._post_login(body)
            else:
                session = self._session(auth)
                if session is None:
                    raise _Refused(401, "log in first")
                handler = None
                if name.isalpha() and method in ("GET", "POST"):
                    handler = getattr(self, "_%s_%s" % (method.lower(), name), None)
                if handler is None:
                    raise _Refused(404, "no such page")
                if method == "POST":
                    try:
                        body = json.loads(body) if body else {}
                    except ValueError:
                        raise _Refused(400, "the body is not JSON")
                    if type(body) is not dict:
                        raise _Refused(400, "the body must be a JSON object, got %r" % (body,))
                answer = await handler(body, session[0])
            status = 200
        except _Refused as e:
            status, answer = e.status, {"error": e.args[0]}
        except (ValueError, TypeError) as e:  # the motion layer's checks
            status, answer = 400, {"error": str(e)}
        except OSError as e:  # the controller did not answer, or the UART failed
            status, answer = 504, {"error": "the controller: %r" % (e,)}
        await _answer(conn, status, answer)

    # The routes: _METHOD_NAME(body, token) for /api/NAME. A GET's body is not read.

    async def _post_login(self, body):
        try:
            body = json.loads(body)
        except ValueError:
            body = None
        if type(body) is not dict:
            raise _Refused(400, 'the body must be {"password": "..."}')
        token = self._login(body.get("password"))
        if token is None:
            await asyncio.sleep_ms(500)  # a guess costs time
            raise _Refused(401, "wrong password")
        return {"token": token}

    async def _get_joints(self, body, token):
        joints = self.robot.joints
        return [{"name": n, "lo": joints[n].lo, "hi": joints[n].hi} for n in self.robot.names]

    async def _get_state(self, body, token):
        return self.state(token)

    async def _get_steps(self, body, token):
        return [{"pose": pose, "ms": ms} for pose, ms in self.sequence.steps]

    async def _post_arm(self, body, token):
        if _need(body, "on", bool):
            if self.armed not in (None, token):
                raise _Refused(409, "another page has the panel armed")
            orders = self._orders
            self.robot.hold()  # arming moves nothing: targets come from the page
            await self.where()  # where the joints are (a joint with a dps limit needs it)
            if self._orders != orders or self.armed not in (None, token):
                raise _Refused(409, "stopped, or armed elsewhere, while arming: arm again")
            self.armed = token
        elif self.armed == token:
            self.disarm()
        return self.state(token)

    async def _post_target(self, body, token):
        self._target(token, body.get("targets"))
        return {}

    async def _post_estop(self, body, token):
        self.estop()
        return self.state(token)

    async def _post_limp(self, body, token):
        self.disarm(halt=False)  # limp stops every joint, even with no controller
        self.robot.limp()
        self.limp = True
        self.to = {}
        return self.state(token)

    async def _post_capture(self, body, token):
        return {"pose": await self.where()}

    async def _post_add(self, body, token):
        # The pose given (the one the page showed, maybe edited), else the one read now.
        ms = _MS_DEFAULT if body.get("ms") is None else _need(body, "ms", int, 0, 65535)
        pose = body.get("pose")
        pose = await self.where() if pose is None else self._pose(pose, "pose")
        self.sequence.append(pose, ms)
        self.edits += 1
        return self.state(token)

    def _step(self, body):
        # The index of a step of the sequence, checked; none while it plays.
        steps = self.sequence.steps
        if not steps:
            raise _Refused(409, "the sequence is empty")
        self._not_playing()
        return _need(body, "index", int, 0, len(steps) - 1)

    async def _post_edit(self, body, token):
        i = self._step(body)
        pose, ms = self.sequence.steps[i]
        if body.get("pose") is not None:
            pose = dict(self._pose(body["pose"], "pose"))
        if body.get("ms") is not None:
            ms = _need(body, "ms", int, 0, 65535)
        self.sequence.steps[i] = (pose, ms)
        self.edits += 1
        return self.state(token)

    async def _post_remove(self, body, token):
        self.sequence.steps.pop(self._step(body))
        self.edits += 1
        return self.state(token)

    async def _post_clear(self, body, token):
        self._not_playing()
        self.sequence = bm.Sequence()
        self.edits += 1
        return self.state(token)

    async def _post_play(self, body, token):
        speed = 1.0 if body.get("speed") is None else _need(body, "speed", float, 0.1, 10)
        self._play(token, speed, bool(body.get("loop")))
        return self.state(token)

    async def _post_stop(self, body, token):
        self.stop()
        return self.state(token)

    async def _get_sequences(self, body, token):
        try:
            names = os.listdir(_FOLDER)
        except OSError:
            names = []
        return sorted(n[:-5] for n in names if n.endswith(".json"))

    async def _post_save(self, body, token):
        path = _name(body)
        if not self.sequence.steps:
            raise _Refused(409, "the sequence is empty: add poses first")
        try:
            os.mkdir(_FOLDER)
        except OSError:
            pass  # it is there
        try:
            self.sequence.save(path)
        except OSError as e:  # the board's filesystem, not the controller
            raise _Refused(500, "could not save %s: %r" % (path, e))
        return {}

    async def _post_load(self, body, token):
        path = _name(body)
        self._not_playing()
        try:
            sequence = bm.Sequence.load(path)
        except OSError:
            raise _Refused(404, "no sequence %r" % body["name"])
        except (ValueError, KeyError, TypeError) as e:
            raise _Refused(400, "%s is not a sequence: %s" % (path, e))
        for pose, _ in sequence.steps:
            for name in pose:
                if name not in self.robot.joints:
                    raise _Refused(
                        400, "%s moves joint %r, which this robot has not" % (path, name)
                    )
        self.sequence = sequence
        self.edits += 1
        return self.state(token)

    # The arm's routes, in busservo_web_arm (imported then): POST /api/jog, /api/calibrate.

    async def _post_jog(self, body, token):
        return await _arm_part().jog(self, body, token)

    async def _post_calibrate(self, body, token):
        return await _arm_part().calibrate(self, body, token)


def _arm_part():
    # The jog and the calibration page: their module, imported when first used.
    import busservo_web_arm

    return busservo_web_arm


async def serve(robot, password, port=80, arm=None, path=_CALIBRATION, host="0.0.0.0"):
    """Serve the panel for robot on port, on every interface (or host's), until cancelled.
    password: a str of 8 or more characters, which the page asks for. arm: a
    busservo_arm.Arm on robot to jog (default: the one path's links make, if it has them);
    path: the calibration file, which the calibration page writes."""
    panel = Panel(robot, password, arm, path)
    try:
        os.stat(_PAGE)
    except OSError:
        raise OSError(2, "the page %s is missing: install it beside busservo_web" % _PAGE)
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
        panel.disarm()
        if panel._halting:
            await panel._halting  # a sequence stopped mid-pose: where the joints are
