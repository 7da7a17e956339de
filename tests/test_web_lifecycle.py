# Review 35: reproductions of what the panel's RAM changes (load, unload, free, unplug, the
# loop's cuts) break. Each test here failed on review35's head (3df4968) when written.
import asyncio
import os
import sys
import unittest

import busservo_web
import web_world
from busservo import CMD_MULT_SERVO_POS_READ
from shell import free_port, scratch, sh
from test_web import LINKS, PASSWORD, _panels, arm_robot, armed, recorded, state
from web_world import http

PARTS_AT_ONCE = (
    ("busservo_web_sliders", None),
    ("busservo_web_teach", None),
    ("busservo_web_calibrate", None),  # a program's own list: the calibration page at once
)


def served(scenario, links=LINKS, **kw):
    """scenario(port, world, robot, path) against serve(robot, ..., **kw) on arm_robot(), its
    calibration file (with links, if given) in a scratch folder."""
    folder = scratch("rev35")
    os.mkdir(folder)
    path = folder + "/robot.json"
    world = web_world.live()
    robot = arm_robot(world)
    if links:
        robot.save(path, links=links)
    port = free_port()

    async def main():
        server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, port, path=path, **kw))
        await asyncio.sleep_ms(50)
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


def forget(*names):
    for name in names:
        sys.modules.pop(name, None)


class Review35(unittest.TestCase):
    def test_a_calibration_page_plugged_in_at_once_is_there_for_a_second_calibration(self):
        # docs/panel.md: a program may give its own parts list; with the calibration page
        # plugged in at once (None), its first calibration's end unplugs it for good.
        async def scenario(port, world, robot, path):
            token = await armed(port)
            ask = lambda body: http(port, "POST", "/api/calibrate", body, token)  # noqa: E731
            self.assertEqual((await ask({"step": "start"}))[0], 200)
            self.assertEqual((await ask({"step": "cancel"}))[0], 200)
            status, reply = await ask({"step": "start"})
            self.assertEqual(status, 200, reply)

        served(scenario, parts=PARTS_AT_ONCE)

    def test_the_loop_reads_positions_again_after_a_calibration_that_follows_a_recording(self):
        # The calibration page, plugged in again after each calibration, keeps the panel's
        # read_ms as it was when plugged in: a request for it while a recording runs (the
        # loop reads none of its own then) leaves read_ms None after the next calibration.
        async def scenario(port, world, robot):
            token = await armed(port)
            panel = _panels[-1]
            ask = lambda body: http(port, "POST", "/api/calibrate", body, token)  # noqa: E731
            self.assertEqual((await ask({"step": "start"}))[0], 200)  # one calibration
            self.assertEqual((await ask({"step": "cancel"}))[0], 200)
            status, reply = await http(port, "POST", "/api/record", {"on": True}, token)
            self.assertEqual(status, 200, reply)
            self.assertEqual((await ask({"step": "start"}))[0], 409)  # a recording runs
            await http(port, "POST", "/api/record", {"on": False}, token)
            self.assertEqual(panel.read_ms, busservo_web._READ_MS)
            self.assertEqual((await ask({"step": "start"}))[0], 200)  # another calibration
            self.assertEqual((await ask({"step": "cancel"}))[0], 200)
            first = world.frames_total
            for _ in range(10):  # the page open for a second
                await state(port, token)
                await asyncio.sleep_ms(100)
            reads = sum(f[3] == CMD_MULT_SERVO_POS_READ for f in world.frames(first))
            self.assertEqual(panel.read_ms, busservo_web._READ_MS)
            self.assertTrue(reads >= 3, reads)

        recorded(scenario)

    def test_a_connection_open_as_serve_ends_is_closed_within_its_second(self):
        # Before: each connection's wait_for_ms() ended it (408) within _HEAD_MS, loop or no
        # loop. Now only the panel's loop cuts it, and serve() cancels the loop as it ends:
        # a connection half-sent then stays open for ever (a socket and a task each).
        world = web_world.live()
        robot = web_world.robot(world)
        port = free_port()
        got = []

        async def main():
            server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, port))
            await asyncio.sleep_ms(50)
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
            await writer.awrite(b"GET /api/st")
            await asyncio.sleep_ms(50)
            server.cancel()
            await asyncio.sleep_ms(20)
            try:
                got.append(await asyncio.wait_for_ms(reader.read(200), 3000))
            except asyncio.TimeoutError:
                got.append(b"(still open after 3 s)")
            await writer.aclose()

        asyncio.new_event_loop()
        asyncio.run(main())
        self.assertFalse(got[0].startswith(b"(still"), got)  # closed, or answered

    def test_the_stub_has_every_method_the_header_lists_for_a_part(self):
        # busservo_web.py's header and docs/panel.md list panel.unplug() for a part.
        here = __file__.rpartition("/")[0] or "."
        with open(here + "/../lib/busservo_web.pyi") as f:
            stub = f.read()
        for name in ("load", "unload", "free", "unplug"):
            self.assertTrue("def %s(" % name in stub, "no %s() in the stub" % name)


if __name__ == "__main__":
    unittest.main()


class Review35Loop(unittest.TestCase):
    def test_a_half_sent_request_gets_408_while_the_loop_fails_each_turn(self):
        # The loop's turn fails before it cuts late connections (bus.poll() raising: a USB
        # controller unplugged under `busservo panel`): no connection is cut any more.
        async def scenario(port, world, robot, path):
            panel = _panels[-1]

            def gone():
                raise OSError(19, "the port is gone (unplugged?)")

            panel.bus.poll = gone
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
            await writer.awrite(b"GET /api/st")
            try:
                got = await asyncio.wait_for_ms(reader.read(200), 3000)
            except asyncio.TimeoutError:
                got = b"(still open after 3 s)"
            await writer.aclose()
            self.assertTrue(got == b"" or got.startswith(b"HTTP/1.0 408"), got)

        served(scenario)
