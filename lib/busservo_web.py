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
# the joints hold where they are (Robot.hold()), and a sequence stops playing.
# The stop button (Robot.estop(): every joint limp) works from any logged-in
# page, armed or not, mid-drag and mid-sequence.
#
# Security. Without the password only the page itself is served (it shows a
# login form): every other request gets 401 and does nothing. The password is
# compared in constant time; a login gives the page a random token that it sends
# with each request (Authorization: Bearer). Bad input gets a 4xx naming what was
# wrong and moves nothing. At most _CLIENTS connections are served at once, each
# for at most _CLIENT_MS (more get 503), and bodies over _BODY bytes get 413.
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

_CLIENTS = 4  # connections served at once; more get 503
_CLIENT_MS = 10000  # a connection that takes longer is closed
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
_NAME_CHARS = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_"

try:
    _PAGE = __file__.rpartition("/")[0] or "."
except NameError:  # frozen into the firmware: look in /lib
    _PAGE = "/lib"
_PAGE += "/busservo_web.html.gz"


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
    504: "Gateway Timeout",
}


def _error(status, why):
    return Response({"error": why}, status, reason=_REASONS.get(status))


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


class _App(Microdot):
    # Microdot, with a limit on the connections served at once and on their time:
    # a board has few sockets and little RAM, and a client that never finishes
    # its request must not hold one for ever.
    def __init__(self):
        super().__init__()
        self.clients = 0

    async def handle_request(self, reader, writer):
        if self.clients >= _CLIENTS:
            try:
                # Its request read first, so that closing does not reset the connection
                # (which could lose the answer on its way).
                await asyncio.wait_for_ms(reader.read(_BODY), 100)
            except (asyncio.TimeoutError, OSError):
                pass
            try:
                await writer.awrite(
                    b"HTTP/1.0 503 Service Unavailable\r\nContent-Type: application/json\r\n"
                    b'Connection: close\r\n\r\n{"error": "too many clients"}'
                )
                await writer.aclose()
            except OSError:
                pass
            return
        self.clients += 1
        try:
            await asyncio.wait_for_ms(super().handle_request(reader, writer), _CLIENT_MS)
        except asyncio.TimeoutError:
            try:
                await writer.aclose()
            except OSError:
                pass
        finally:
            self.clients -= 1


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

    def _session(self, request):
        # The session of the request's token (and note it was seen), or None.
        given = request.headers.get("Authorization", "")
        if not given.startswith("Bearer "):
            return None
        given = given[7:].encode()
        found = None
        for session in self._sessions:  # all compared: the time says nothing
            if _same(given, session[0].encode()):
                found = session
        if found:
            found[1] = self._seen = time.ticks_ms()
        return found

    # What the page can do.

    def disarm(self):
        """Stop driving: the stream ends (the joints hold) and the sequence stops."""
        self.armed = None
        self.robot.hold()
        if self.player:
            self.player.stop()
            self.player = None

    def estop(self):
        self.disarm()
        self.limp = True
        self.robot.estop()

    def _driver(self, token):
        if self.armed != token:
            raise _Refused(409, "arm the panel first (another page may have it armed)")

    def _target(self, token, targets):
        self._driver(token)
        if self.player:
            raise _Refused(409, "a sequence is playing: stop it first")
        if type(targets) is not dict or not targets:
            raise _Refused(400, "targets must be {joint: degrees}, got %r" % (targets,))
        for name in targets:
            joint = self.robot.joints.get(name)
            if joint is None:
                raise _Refused(400, "no joint %r: the joints are %s" % (name, self.robot.names))
            _need(targets, name, float, joint.lo, joint.hi, "targets[%r]" % name)
        self.robot.stream(targets)
        self.limp = False

    def _play(self, token, speed, loop):
        self._driver(token)
        if not self.sequence.steps:
            raise _Refused(409, "the sequence is empty: add poses first")
        self.robot.hold()
        self.player = self.sequence.play(self.robot, speed, loop)
        self.limp = False

    def state(self):
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
                if self.player:
                    self.player.stop()
                    self.player = None
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
        app = _App()
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
            return panel.state()

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
            return panel.state()

        @app.post("/api/target")
        @_guard
        async def target(request):
            panel._target(request.g.token, request.g.body.get("targets"))
            return {}

        @app.post("/api/estop")
        @_guard
        async def estop(request):
            panel.estop()
            return panel.state()

        @app.post("/api/limp")
        @_guard
        async def limp(request):
            panel.disarm()
            robot.limp()
            panel.limp = True
            return panel.state()

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
            return panel.state()

        @app.post("/api/remove")
        @_guard
        async def remove(request):
            steps = panel.sequence.steps
            i = _need(request.g.body, "index", int, 0, max(0, len(steps) - 1))
            if not steps or panel.player:
                raise _Refused(409, "nothing to remove, or a sequence is playing")
            steps.pop(i)
            return panel.state()

        @app.post("/api/clear")
        @_guard
        async def clear(request):
            if panel.player:
                raise _Refused(409, "a sequence is playing: stop it first")
            panel.sequence = bm.Sequence()
            return panel.state()

        @app.post("/api/play")
        @_guard
        async def play(request):
            body = request.g.body
            speed = 1.0 if body.get("speed") is None else _need(body, "speed", float, 0.1, 10)
            loop = bool(body.get("loop"))
            panel._play(request.g.token, speed, loop)
            return panel.state()

        @app.post("/api/stop")
        @_guard
        async def stop(request):
            if panel.player:
                panel.player.stop()
                panel.player = None
            return panel.state()

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
            panel.sequence.save(path)
            return {}

        @app.post("/api/load")
        @_guard
        async def load(request):
            path = _name(request.g.body)
            if panel.player:
                raise _Refused(409, "a sequence is playing: stop it first")
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
            return panel.state()

        # Anything else: 401 without a session (before_request), else 404.
        @app.route("/<path:path>", methods=["GET", "POST", "PUT", "DELETE", "PATCH", "HEAD"])
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
        panel.disarm()
        server = getattr(panel.app, "server", None)
        if server:
            server.close()
