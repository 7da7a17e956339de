# busservo_web: a control panel for a busservo_motion.Robot, served by the board
# itself to a browser on the same Wi-Fi (or on the board's own access point):
# a slider per joint, live positions, the battery, teach and play back, and an
# emergency stop. It runs on asyncio, beside the robot's own tasks:
#
#   import asyncio, busservo_web
#   asyncio.run(busservo_web.serve(robot, "a password of yours", port=80))
#
# The page is one file, lib/busservo_web.html, served gzipped (busservo_web.html.gz
# beside this module; no internet needed). The web framework is Microdot.
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
# What the page asks for (JSON in and out; errors are {"error": "..."}):
#   POST /api/login {"password"}   -> {"token"}
#   GET  /api/joints               -> [{"name", "lo", "hi"}, ...]
#   GET  /api/state                -> positions in degrees, battery, armed, sequence, ...
#   POST /api/arm {"on"}, /api/target {"targets": {name: degrees}}, /api/estop,
#        /api/limp, /api/capture, /api/add {"ms"}, /api/remove {"index"}, /api/clear,
#        /api/play {"speed", "loop"}, /api/stop, /api/save {"name"}, /api/load {"name"}
#   GET  /api/sequences            -> ["name", ...]
import asyncio
import json
import os
import time

from microdot import Microdot, Request, Response

import busservo_motion as bm

_CLIENTS = 4  # requests being read, and answered, at once
_HEAD_MS = 1000  # a connection's request must be in within this, or it is closed
_REQUEST = 4096  # bytes: a request's line, headers and body; a longer one gets 400
_CLIENT_MS = 10000  # an answer that takes longer is cut
_SESSIONS = 4  # logins remembered; a new one forgets the oldest
_BODY = 1024  # bytes: a larger request body gets 413
_DEAD_MS = 1000  # the armed page silent this long: hold (the dead-man)
_OPEN_MS = 3000  # a page asked within this: read positions often
_READ_MS = 150  # positions asked this often while a page is open
_BATTERY_MS = 2000
_TICK_MS = 10  # the panel's loop: poll the bus, step the stream and the player
_FOLDER = "sequences"
_NAME_MAX = 24
_MS_DEFAULT = 1000  # time to reach an added pose, if the page gives none
_HALT_MS = 100  # a sequence stopped mid-pose: the joints go where they are, in this
_METHODS = ["GET", "POST", "PUT", "DELETE", "PATCH", "HEAD", "OPTIONS"]
_NAME_CHARS = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_"


def _find_page():
    # The page: beside this module (installed by mip or mpremote, or on the unix port),
    # else in /lib (a module frozen into the firmware has no folder on the filesystem).
    try:
        here = __file__.rpartition("/")[0] or "."
    except NameError:
        here = "/lib"
    for folder in (here, "/lib"):
        try:
            os.stat(folder + "/busservo_web.html.gz")
            return folder + "/busservo_web.html.gz"
        except OSError:
            pass
    return here + "/busservo_web.html.gz"  # not there: serve() says so


_PAGE = _find_page()


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


_REASONS = {
    400: "Bad Request",
    401: "Unauthorized",
    404: "Not Found",
    409: "Conflict",
    413: "Payload Too Large",
    500: "Internal Server Error",
    503: "Service Unavailable",
    504: "Gateway Timeout",
}


def _error(status, why):
    return Response({"error": why}, status, reason=_REASONS.get(status))


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


def _guard(handler):
    # A route's handler, whose refusals and errors become a 4xx or 5xx with
    # {"error": why}: nothing is half done, and the server goes on.
    async def guarded(request, **args):
        try:
            return await handler(request, **args)
        except _Refused as e:
            return _error(e.status, e.args[0])
        except (ValueError, TypeError) as e:  # the motion layer's checks
            return _error(400, str(e))
        except OSError as e:  # the controller did not answer, or the UART failed
            return _error(504, "the controller: %r" % (e,))

    return guarded


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
    # A connection, as Microdot reads and writes it. It gives a request at most _REQUEST
    # bytes (MicroPython's readline() has no limit of its own, and a negative
    # Content-Length would read until the RAM is full), then ValueError: a 400. It notes
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
                break
        line, nl, self._buf = self._buf.partition(b"\n")
        return line + nl

    async def readexactly(self, n):
        if not 0 <= n <= _BODY:
            raise ValueError("Content-Length %d" % n)
        while len(self._buf) < n:
            if not await self._more():
                raise EOFError
        data, self._buf = self._buf[:n], self._buf[n:]
        return data

    async def read(self, n=-1):
        # A body too large to keep, read to be dropped (413): not counted.
        if self._buf:
            data, self._buf = self._buf, b""
            return data
        return await self._reader.read(n)

    async def awrite(self, data):
        await self._writer.awrite(data)
        self.sent = True


class _App(Microdot):
    # Microdot, with limits on its connections: a board has few sockets and
    # little RAM, and the STOP button must get through whatever else comes.
    # - A request must be in within _HEAD_MS (else 408). When _CLIENTS connections
    #   are still reading theirs, a new one pushes out the oldest that has sent
    #   nothing yet, else the oldest (which hears 503). So connections that say
    #   nothing, or little, hold nothing, and a page's request, sent at once, gets in.
    # - At most _CLIENTS requests are answered at once, each within _CLIENT_MS;
    #   more get 503, except a logged-in page's (up to twice as many).
    # - Every connection ends closed, whatever is raised: an error (a MemoryError,
    #   say) before its answer has begun is answered 503; after, the answer is cut.
    def __init__(self, logged_in):
        super().__init__()
        self.options_handler = None  # OPTIONS too needs the password (a route below)
        self._logged_in = logged_in  # request -> True if it comes with a session
        self._reading = []  # (task, _Conn) of the requests being read, oldest first
        self.clients = 0  # requests being answered

    async def handle_request(self, reader, writer):
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
                request = await asyncio.wait_for_ms(
                    Request.create(self, conn, conn, writer.get_extra_info("peername")),
                    _HEAD_MS,
                )
            except asyncio.TimeoutError:
                if conn.heard:
                    await conn.awrite(_LATE)
                return
            except asyncio.CancelledError:  # pushed out by a newer connection
                if conn.heard:
                    await conn.awrite(_BUSY)
                return
            except (OSError, MemoryError):
                raise  # gone, or out of memory: below
            except Exception:  # malformed or too long: Microdot answers None with 400
                request = None
            finally:
                if mine in reading:
                    reading.remove(mine)
            if self.clients >= _CLIENTS and (
                self.clients >= 2 * _CLIENTS or not self._logged_in(request)
            ):
                await conn.awrite(_BUSY)
                return
            self.clients += 1
            try:
                response = await asyncio.wait_for_ms(self.dispatch_request(request), _CLIENT_MS)
                if response is not Response.already_handled:
                    await asyncio.wait_for_ms(response.write(conn), _CLIENT_MS)
            finally:
                self.clients -= 1
        except OSError:
            pass  # the client has gone
        except Exception:  # out of memory, say, or an answer over _CLIENT_MS
            if not (conn and conn.sent):
                try:
                    await writer.awrite(_FAILED)
                except Exception:
                    pass
        finally:
            await _close(writer)


async def _close(writer):
    try:
        await writer.aclose()
    except Exception:
        pass


class Panel:
    """The panel's state and its loop, for serve(); a test may drive one directly."""

    def __init__(self, robot, password):
        if type(password) is not str or len(password) < 8:
            raise ValueError("password must be a str of 8 or more characters, got %r" % password)
        self.robot = robot
        self.bus = robot.bus
        self._ids = [robot.joints[name].servo_id for name in robot.names]
        self._password = password.encode()
        self._sessions = []  # [token, ticks_ms last seen], oldest first
        self.armed = None  # the token of the page that armed, or None
        self.sequence = bm.Sequence()
        self.player = None
        self.error = None  # the last error of the loop, for the page
        self.limp = False  # joints let go by limp() or estop(), until the next move
        now = time.ticks_ms()
        self._seen = time.ticks_add(now, -_OPEN_MS)  # any page, last
        self._read = self._battery = now
        self.app = self._routes()

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

    def _session(self, request, note=True):
        # The session of the request's token (and note it was seen), or None.
        given = request.headers.get("Authorization", "")
        if not given.startswith("Bearer "):
            return None
        given = given[7:].encode()
        found = None
        for session in self._sessions:  # all compared: the time says nothing
            if _same(given, session[0].encode()):
                found = session
        if found and note:
            found[1] = self._seen = time.ticks_ms()
        return found

    # What the page can do.

    def disarm(self, halt=True):
        """Stop driving: the stream ends (the joints hold) and the sequence stops."""
        self.armed = None
        self.robot.hold()
        self.stop(halt)

    def stop(self, halt=True):
        """Stop the sequence; with halt, its pose on the way too (which would go
        on for its ms): the joints it moves are sent where they are now (a read
        of their positions first, ~30 ms)."""
        player = self.player
        self.player = None
        if player and not player.done:
            player.stop()
            if halt:
                names = set()
                for pose, _ in self.sequence.steps:
                    names.update(pose)
                self.robot.move(self.robot.where(list(names)), ms=_HALT_MS)

    def estop(self):
        self.disarm(halt=False)  # at once: the joints go limp
        self.limp = True
        self.robot.estop()

    def _driver(self, token):
        if self.armed != token:
            raise _Refused(409, "arm the panel first (another page may have it armed)")

    def _target(self, token, targets):
        self._driver(token)
        self._not_playing()
        if type(targets) is not dict or not targets:
            raise _Refused(400, "targets must be {joint: degrees}, got %r" % (targets,))
        for name in targets:
            joint = self.robot.joints.get(name)
            if joint is None:
                raise _Refused(400, "no joint %r: the joints are %s" % (name, self.robot.names))
            _need(targets, name, float, joint.lo, joint.hi, "targets[%r]" % name)
        self.robot.stream(targets)
        self.limp = False

    def _not_playing(self):
        if self.player:
            raise _Refused(409, "a sequence is playing: stop it first")

    def _play(self, token, speed, loop):
        self._driver(token)
        if not self.sequence.steps:
            raise _Refused(409, "the sequence is empty: add poses first")
        self.robot.hold()
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
        return {
            "at": at,
            "battery": self.bus.battery,
            "armed": self.armed is not None,
            "mine": token is not None and self.armed == token,
            "limp": self.limp,
            "steps": [ms for _, ms in self.sequence.steps],
            "playing": player.index if player else None,
            "updates": robot.updates,
            "error": self.error,
        }

    # The loop: the bus's replies, the stream, the player, the dead-man and the reads.

    async def run(self):
        """Run for ever (until cancelled): serve() runs it beside the web server."""
        while True:
            try:
                self._tick()
            except Exception as e:  # the panel must go on, and say so
                self.error = "%s: %s" % (type(e).__name__, e)
                try:
                    self.stop()
                except Exception:
                    self.stop(halt=False)  # the bus failed: stop sending, at least
            await asyncio.sleep_ms(_TICK_MS)

    def _tick(self):
        bus = self.bus
        while bus.poll() is not None:  # replies update bus.positions and bus.battery
            pass
        now = time.ticks_ms()
        if self.armed is not None:
            for token, seen in self._sessions:
                if token == self.armed and time.ticks_diff(now, seen) > _DEAD_MS:
                    self.disarm()
            self.robot.step()
        if self.player:
            if self.player.done:
                self.player = None
            else:
                self.player.step()
        if bus.wire_ms():
            return  # the stream and the player come first
        open_ = time.ticks_diff(now, self._seen) < _OPEN_MS
        if time.ticks_diff(now, self._read) >= (_READ_MS if open_ else _OPEN_MS):
            self._read = now
            bus.request_positions(self._ids)
        elif open_ and time.ticks_diff(now, self._battery) >= _BATTERY_MS:
            self._battery = now
            bus.request_battery()

    # The web server's routes.

    def _routes(self):
        app = _App(lambda request: request and self._session(request, note=False))
        panel = self
        robot = self.robot

        def refuse(status, why):
            return _error(status, why)

        @app.before_request
        async def check(request):
            # Only the page and the login are served without a session.
            if request.content_length > _BODY:
                return refuse(413, "the body is over %d bytes" % _BODY)
            if request.path in ("/", "/api/login"):
                return None
            session = panel._session(request)
            if session is None:
                return refuse(401, "log in first")
            request.g.token = session[0]
            if request.method == "POST":
                try:
                    body = json.loads(request.body) if request.body else {}
                except ValueError:
                    return refuse(400, "the body is not JSON")
                if type(body) is not dict:
                    return refuse(400, "the body must be a JSON object, got %r" % (body,))
                request.g.body = body
            return None

        @app.errorhandler(413)
        async def too_large(request):
            # Some of the body read, so that closing does not reset the connection
            # before the answer has gone; past that, the client hears a reset.
            try:
                for _ in range(8):
                    if not await asyncio.wait_for_ms(request.stream.read(_BODY), 100):
                        break
            except (asyncio.TimeoutError, OSError):
                pass
            return refuse(413, "the body is over %d bytes" % _BODY)

        @app.errorhandler(400)
        async def bad(request):
            return refuse(400, "bad request")

        @app.errorhandler(MemoryError)
        async def no_memory(request, e):
            # Written here (Microdot then writes nothing): making an answer could fail too.
            await request.sock[1].awrite(_FAILED)
            return Response.already_handled

        @app.route("/")
        @_guard
        async def page(request):
            response = Response.send_file(
                _PAGE, content_type="text/html; charset=utf-8", compressed=True
            )
            response.headers["X-Frame-Options"] = "DENY"  # not inside another site's page
            response.headers["Cache-Control"] = "no-cache"
            return response

        @app.post("/api/login")
        @_guard
        async def login(request):
            try:
                body = json.loads(request.body)
            except ValueError:
                body = None
            if type(body) is not dict:
                return refuse(400, 'the body must be {"password": "..."}')
            token = panel._login(body.get("password"))
            if token is None:
                await asyncio.sleep_ms(500)  # a guess costs time
                return refuse(401, "wrong password")
            return {"token": token}

        @app.get("/api/joints")
        @_guard
        async def joints(request):
            return [
                {"name": n, "lo": robot.joints[n].lo, "hi": robot.joints[n].hi}
                for n in robot.names
            ]

        @app.get("/api/state")
        @_guard
        async def state(request):
            return panel.state(request.g.token)

        @app.post("/api/arm")
        @_guard
        async def arm(request):
            on = _need(request.g.body, "on", bool)
            if on:
                if panel.armed not in (None, request.g.token):
                    raise _Refused(409, "another page has the panel armed")
                robot.hold()  # arming moves nothing: targets come from the page
                robot.where()  # where the joints are (a joint with a dps limit needs it)
                panel.armed = request.g.token
            elif panel.armed == request.g.token:
                panel.disarm()
            return panel.state(request.g.token)

        @app.post("/api/target")
        @_guard
        async def target(request):
            panel._target(request.g.token, request.g.body.get("targets"))
            return {}

        @app.post("/api/estop")
        @_guard
        async def estop(request):
            panel.estop()
            return panel.state(request.g.token)

        @app.post("/api/limp")
        @_guard
        async def limp(request):
            panel.disarm(halt=False)  # limp stops every joint, even with no controller
            robot.limp()
            panel.limp = True
            return panel.state(request.g.token)

        @app.post("/api/capture")
        @_guard
        async def capture(request):
            return {"pose": robot.capture()}

        @app.post("/api/add")
        @_guard
        async def add(request):
            body = request.g.body
            ms = _MS_DEFAULT if body.get("ms") is None else _need(body, "ms", int, 0, 65535)
            panel.sequence.append(robot.capture(), ms)
            return panel.state(request.g.token)

        @app.post("/api/remove")
        @_guard
        async def remove(request):
            steps = panel.sequence.steps
            i = _need(request.g.body, "index", int, 0, max(0, len(steps) - 1))
            if not steps or panel.player:
                raise _Refused(409, "nothing to remove, or a sequence is playing")
            steps.pop(i)
            return panel.state(request.g.token)

        @app.post("/api/clear")
        @_guard
        async def clear(request):
            panel._not_playing()
            panel.sequence = bm.Sequence()
            return panel.state(request.g.token)

        @app.post("/api/play")
        @_guard
        async def play(request):
            body = request.g.body
            speed = 1.0 if body.get("speed") is None else _need(body, "speed", float, 0.1, 10)
            loop = bool(body.get("loop"))
            panel._play(request.g.token, speed, loop)
            return panel.state(request.g.token)

        @app.post("/api/stop")
        @_guard
        async def stop(request):
            panel.stop()
            return panel.state(request.g.token)

        @app.get("/api/sequences")
        @_guard
        async def sequences(request):
            try:
                names = os.listdir(_FOLDER)
            except OSError:
                names = []
            return sorted(n[:-5] for n in names if n.endswith(".json"))

        @app.post("/api/save")
        @_guard
        async def save(request):
            path = _name(request.g.body)
            if not panel.sequence.steps:
                raise _Refused(409, "the sequence is empty: add poses first")
            try:
                os.mkdir(_FOLDER)
            except OSError:
                pass  # it is there
            try:
                panel.sequence.save(path)
            except OSError as e:  # the board's filesystem, not the controller
                raise _Refused(500, "could not save %s: %r" % (path, e))
            return {}

        @app.post("/api/load")
        @_guard
        async def load(request):
            path = _name(request.g.body)
            panel._not_playing()
            try:
                sequence = bm.Sequence.load(path)
            except OSError:
                raise _Refused(404, "no sequence %r" % request.g.body["name"])
            except (ValueError, KeyError, TypeError) as e:
                raise _Refused(400, "%s is not a sequence: %s" % (path, e))
            for pose, _ in sequence.steps:
                for name in pose:
                    if name not in robot.joints:
                        raise _Refused(
                            400, "%s moves joint %r, which this robot has not" % (path, name)
                        )
            panel.sequence = sequence
            return panel.state(request.g.token)

        # Anything else: 401 without a session (before_request), else 404.
        @app.route(
            "/<path:path>", methods=["GET", "POST", "PUT", "DELETE", "PATCH", "HEAD", "OPTIONS"]
        )
        @_guard
        async def other(request, path):
            return refuse(404, "no such page")

        return app


async def serve(robot, password, port=80):
    """Serve the panel for robot on port, on every interface, until cancelled.
    password: a str of 8 or more characters, which the page asks for."""
    panel = Panel(robot, password)
    try:
        os.stat(_PAGE)
    except OSError:
        raise OSError(2, "the page %s is missing: install it beside busservo_web" % _PAGE)
    Request.max_content_length = Request.max_body_length = _BODY  # all Microdot apps here
    loop = asyncio.create_task(panel.run())
    try:
        await panel.app.start_server(host="0.0.0.0", port=port)
    finally:
        loop.cancel()
        server = getattr(panel.app, "server", None)
        if server:
            server.close()
        panel.disarm()
