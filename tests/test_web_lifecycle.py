# The panel's parts as they come and go (load, unload, free, unplug), and its connections as
# its loop cuts them: what an adversarial review of those changes found. Each test here failed
# on the code before its fix.
import asyncio
import os
import sys
import unittest

import busservo_web
import web_world
from busservo import CMD_MULT_SERVO_POS_READ
from shell import free_port
from test_web import LINKS, PASSWORD, _panels, armed, calibrate, on_arm, recorded, state
from web_world import http

PARTS_AT_ONCE = (
    ("busservo_web_sliders", None),
    ("busservo_web_teach", None),
    ("busservo_web_calibrate", None),  # a program's own list: the calibration page at once
)


def exists(path):
    try:
        os.stat(path)
        return True
    except OSError:
        return False


def no_room_for(panel, module):
    """A panel.load() for a heap with no room for module (MemoryError); the others load."""
    load = panel.load

    def short(name):
        if name == module:
            raise MemoryError
        return load(name)

    return short


def forget(*names):
    for name in names:
        sys.modules.pop(name, None)


class Parts(unittest.TestCase):
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

        on_arm(scenario, parts=PARTS_AT_ONCE)

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

    def test_a_first_calibration_that_gives_links_does_not_load_the_arm_while_under_way(self):
        # docs/panel.md: "a board's heap holds the jog's arm or a calibration, not both".
        # Saving links plugs the jog in (adopt()), which loads busservo_arm at once, the
        # calibration still under way; with no room for it, the save answers 503.
        async def scenario(port, world, robot, path):
            token = await armed(port)
            status, reply = await calibrate(port, world, token)
            self.assertEqual(status, 200, reply)
            status, reply = await http(
                port, "POST", "/api/calibrate", {"step": "save", "links": LINKS}, token
            )
            self.assertEqual(status, 200, reply)
            self.assertEqual(reply["cal"]["step"], "saved")
            self.assertFalse(reply["arm"], reply)  # no jog while it is under way

        forget("busservo_arm", "busservo_calibrate", "busservo_web_calibrate", "busservo_web_jog")
        on_arm(scenario, links=None)

    def test_links_given_to_a_save_leave_busservo_arm_for_the_next_calibration_to_free(self):
        # busservo_calibrate imports busservo_arm to check links given to a save: the panel
        # loads it for that (panel.load()) and lets it go after, so that the next calibration
        # does not hold busservo_arm's code beside its own (it did: imported behind the
        # panel's back, it was never let go).
        async def scenario(port, world, robot, path):
            token = await armed(port)
            status, reply = await calibrate(port, world, token)
            self.assertEqual(status, 200, reply)
            body = {"step": "save", "links": LINKS}
            status, reply = await http(port, "POST", "/api/calibrate", body, token)
            self.assertEqual(status, 200, reply)
            body = {"step": "cancel"}
            status, reply = await http(port, "POST", "/api/calibrate", body, token)
            self.assertTrue(reply["arm"], reply)  # the jog's arm, made
            body = {"step": "start"}
            status, reply = await http(port, "POST", "/api/calibrate", body, token)
            self.assertEqual(status, 200, reply)
            self.assertFalse("busservo_arm" in sys.modules)

        forget("busservo_arm", "busservo_calibrate", "busservo_web_calibrate", "busservo_web_jog")
        on_arm(scenario, links=None)

    def test_a_save_with_no_room_to_check_the_links_saves_nothing_and_can_be_tried_again(self):
        # A board at its heap's edge: busservo_arm (which checks the links) cannot load while
        # the calibration is held. Nothing is saved and the page is told (503); the same save,
        # once there is room, is saved, and the calibration goes on to its home.
        async def scenario(port, world, robot, path):
            token = await armed(port)
            panel = _panels[-1]
            load, short = panel.load, no_room_for(panel, "busservo_arm")
            status, reply = await calibrate(port, world, token)
            self.assertEqual(status, 200, reply)
            panel.load = short
            body = {"step": "save", "links": LINKS}
            status, reply = await http(port, "POST", "/api/calibrate", body, token)
            self.assertEqual(status, 503, reply)
            self.assertFalse(exists(path))  # nothing saved
            panel.load = load
            status, reply = await http(port, "POST", "/api/calibrate", body, token)
            self.assertEqual((status, reply["cal"]["step"]), (200, "saved"), reply)
            self.assertFalse(reply["arm"], reply)  # not while the calibration holds the joints
            body = {"step": "home", "confirm": True}
            status, reply = await http(port, "POST", "/api/calibrate", body, token)
            self.assertEqual((status, reply.get("arm")), (200, True), reply)

        forget("busservo_arm", "busservo_calibrate", "busservo_web_calibrate", "busservo_web_jog")
        on_arm(scenario, links=None)

    def test_the_state_is_answered_while_the_arm_cannot_be_made_again(self):
        # After a calibration, the jog makes its arm again in state(): every poll of the
        # page. With no room for it (not once, as test_web's, but for as long as the heap is
        # short), the state, and STOP's answer, are still answered (they were each a 503).
        async def scenario(port, world, robot, path):
            token = await armed(port)
            panel = _panels[-1]
            short = no_room_for(panel, "busservo_arm")
            await http(port, "POST", "/api/calibrate", {"step": "start"}, token)
            panel.load = short
            await http(port, "POST", "/api/calibrate", {"step": "cancel"}, token)
            for _ in range(3):
                status, reply = await http(port, "GET", "/api/state", token=token)
                self.assertEqual(status, 200, reply)
            status, reply = await http(port, "POST", "/api/estop", {}, token)
            self.assertEqual(status, 200, reply)

        on_arm(scenario)

    def test_free_lets_the_jogs_arm_go_at_once(self):
        # A calibration imports its code right after panel.free(): the jog's arm must be let
        # go by then (the heap holds the one or the other), not at the next state().
        async def scenario(port, world, robot, path):
            token = await armed(port)
            panel = _panels[-1]
            jog = panel.parts["busservo_web_jog"]
            self.assertTrue(jog.arm is not None)
            panel.free(None)
            self.assertTrue(jog.arm is None)
            self.assertTrue((await state(port, token))["arm"])  # made again: nothing holds

        on_arm(scenario)


class Cuts(unittest.TestCase):
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

        on_arm(scenario)


if __name__ == "__main__":
    unittest.main()
