# A day of the web panel, on simulated time: nothing grows.
#
# The panel (lib/busservo_web.py) with the arm of examples/web_panel.py, on the wire-faithful
# world (tests/wire.py: an rp2's UART, the 9600-baud line, the simulated controller) and its
# clock, for 24 simulated hours. Its loop, Panel.run(), runs every 10 ms all day, as
# serve() runs it; the page's requests go to the panel's routes as a connection's would
# once read (Panel._dispatch(): the session check, the routes, the JSON answer written to
# the connection), without a socket, so that no real time passes. A small scheduler
# (_Board) runs the panel's loop and the
# page as coroutines on the world's clock: busservo_web's asyncio.sleep_ms() is the
# scheduler's while the soak runs.
#
# First the page teaches the sequence (three poses: drag, then add). Then every 2 simulated
# minutes the page (one browser tab) does this:
#   0 s       it shows: it polls /api/state 5 times a second while it shows
#   0.1 s     arms the panel, then drags two sliders: a target every 50 ms for 3 s
#   3.1 s     plays the sequence (3 poses, 300 ms each) looping, for 3 s
#   6.1 s     stops it and disarms (every other time), or just goes quiet (the dead-man
#             disarms a second later and halts the sequence)
#   6.1-120 s it is hidden: it says nothing, and the panel reads the positions every 3 s
# and every 10 minutes it is reloaded (a new login: the panel keeps 4 sessions). So the
# wire is busy 6 s in 120 and nearly idle between, and the panel's loop runs every 10 ms
# throughout. A day of the page open all the time would take a quarter of an hour to run
# (the page's requests, and each arming's and halt's read spinning on the wire byte by
# byte); this takes a minute or two of CPU. The clock starts so that the ticks_ms counter
# wraps at hour 12 (ticks_us wraps every 18 minutes). The last burst is at hour 24.
#
# A minute into every hour from 1 to 24 (between bursts): the heap after gc.collect(),
# and the size of every list, dict, set and bytearray reachable from the panel (its
# sessions and sequence, the Robot, the BusServo; not the test world,
# which tests/test_wire.py checks), and how many attributes each object has; the sizes
# again as that hour's first burst plays the sequence (the player's too). The heap must
# stay within 1 KB from hour 1 to hour 24, and nothing may be larger than it was at hour
# 1. A leak of one list item per state poll is caught (the second test).
import gc
import json
import math
import time
import unittest

import busservo
import busservo_motion as bm
import busservo_web
import web_world
import wire

HOURS = 24
EVERY = 2  # minutes from one burst of the page to the next
PASSWORD = "secret-pw"
_MS = 1000  # us


class _Written:
    # A connection's writing side: what the panel answers a request.
    def __init__(self):
        self.out = b""

    async def write(self, data):
        self.out += data

    def client(self):
        return None  # who asks: the page, the only client


class _Lock:
    # asyncio.Lock on the _Board: one holder; another waits a ms at a time.
    def __init__(self):
        self.held = False

    def locked(self):
        return self.held

    async def __aenter__(self):
        while self.held:
            await _Asyncio.sleep_ms(1)
        self.held = True

    async def __aexit__(self, *exc):
        self.held = False


class _Asyncio:
    # busservo_web's asyncio while the soak runs: what the panel awaits and starts.
    Lock = _Lock

    def __init__(self, board):
        self._board = board

    @staticmethod
    def sleep_ms(ms):
        yield ms  # to the _Board, which resumes the task ms later

    def create_task(self, coro):
        self._board.start(coro)
        return coro


class _Board:
    # Coroutines on the world's clock: a task runs when the clock reaches its time, until it
    # awaits sleep_ms(ms); what it does moves the clock on (each ticks read and UART call
    # costs), and it runs again ms after that.
    def __init__(self, clock):
        self.clock = clock
        self.tasks = []  # [when, coroutine]

    def start(self, coro):
        self.tasks.append([self.clock.now_us, coro])

    def run_to(self, end):
        clock = self.clock
        tasks = self.tasks
        while tasks:
            task = tasks[0]
            for other in tasks:
                if other[0] < task[0]:
                    task = other
            if task[0] > end:
                break
            if task[0] > clock.now_us:
                clock.now_us = task[0]
            try:
                ms = task[1].send(None)
            except StopIteration:
                tasks.remove(task)
                continue
            task[0] = clock.now_us + ms * _MS
        if end > clock.now_us:
            clock.now_us = end


def sleep_ms(ms):
    return _Asyncio.sleep_ms(ms)


_PLAIN = (int, float, str, bytes, bool, type(None))


def sizes(root, skip):
    """{"path kind": len} of every list, dict, set and bytearray reachable from root
    through instances' attributes and containers, not into objects of the classes in skip;
    and of each instance, how many attributes it has."""
    out = {}
    seen = set()

    def walk(x, path, depth):
        if id(x) in seen or depth > 12 or isinstance(x, skip):
            return
        seen.add(id(x))
        if isinstance(x, (list, tuple)):
            if not isinstance(x, tuple):
                out[path + " list"] = len(x)
            for i, item in enumerate(x):
                if not isinstance(item, _PLAIN):
                    walk(item, "%s[%d]" % (path, i), depth + 1)
        elif isinstance(x, dict):
            out[path + " dict"] = len(x)
            for key, value in x.items():
                if not isinstance(value, _PLAIN):
                    walk(value, "%s[%r]" % (path, key), depth + 1)
        elif isinstance(x, (set, bytearray)):
            out["%s %s" % (path, type(x).__name__)] = len(x)
        elif hasattr(x, "__dict__") and not isinstance(x, type):
            attrs = x.__dict__  # in MicroPython a copy, made at each look
            out[path + " attributes"] = len(attrs)
            for key, value in attrs.items():
                if not isinstance(value, _PLAIN):
                    walk(value, "%s.%s" % (path, key), depth + 1)

    walk(root, "panel", 0)
    return out


class Soak:
    """The panel for hours on simulated time; figures of what it held each hour."""

    def __init__(self, hours, leak=False):
        self.hours = hours
        # ticks_ms wraps half way through, as a board's does every 12.4 days.
        start = (wire.PERIOD - hours * 1800 * 1000, 0)
        self.world = wire.World("rp2", start=start)
        self.board = _Board(self.world.clock)
        self.robot = self.panel = None  # made by run(), on the world's clock
        self.heap = [0] * (hours + 1)  # heap after gc.collect() at the start of each hour
        self.first = {}  # sizes() at hour 1: between bursts, and while the sequence plays
        self.grew = []  # (hour, path, size at hour 1, size then) of any that grew
        self.largest = {}  # kind: (size, "path kind") of the largest at the last hour
        self.counts = {"polls": 0, "targets": 0, "plays": 0, "loops": 0, "refused": 0}
        self.leak = leak
        self.token = None

    async def request(self, method, path, body=None):
        """The page's request, through the panel's routes: (status, the JSON it answered)."""
        auth = "Bearer " + self.token if self.token else ""
        data = json.dumps(body).encode() if body is not None else b""
        conn = _Written()
        await self.panel._dispatch(conn, (method, path, auth, data, True))
        head, _, answer = conn.out.partition(b"\r\n\r\n")
        if self.leak and path == "/api/state":  # a list in the panel, one more item a poll
            if not hasattr(self.panel, "_leaked"):
                self.panel._leaked = []
            self.panel._leaked.append(len(answer))
        try:
            return int(head.split()[1]), json.loads(answer)
        except (IndexError, ValueError):  # no status line, or not the panel's JSON
            raise AssertionError("%s %s: %r" % (method, path, conn.out[:200]))

    async def login(self):
        self.token = None
        status, reply = await self.request("POST", "/api/login", {"password": PASSWORD})
        assert status == 200, (status, reply)
        self.token = reply["token"]

    async def poll(self, ms):
        """The page while it shows: /api/state every 200 ms, for ms."""
        end = self.world.clock.now_us + ms * _MS
        while self.world.clock.now_us < end:
            status, state = await self.request("GET", "/api/state")
            assert status == 200, (status, state)
            assert state["error"] is None, state["error"]
            self.counts["polls"] += 1
            await sleep_ms(200)

    async def teach(self):
        """Three poses into the sequence, as the page teaches them: drag, then add."""
        await self.login()
        status, _ = await self.request("POST", "/api/arm", {"on": True})
        assert status == 200
        for base, elbow in ((-30, 20), (30, -20), (0, 45)):
            await self.request("POST", "/api/target", {"targets": {"base": base, "elbow": elbow}})
            await sleep_ms(1500)  # the stream gets it there
            status, state = await self.request("POST", "/api/add", {"ms": 300})
            assert status == 200, (status, state)
        await self.request("POST", "/api/arm", {"on": False})

    async def burst(self, m):
        """The page at minute m (see the top of this file)."""
        counts = self.counts
        if m % 10 == 0:
            await self.login()  # the page reloaded
        self.board.start(self.poll(6100))
        await sleep_ms(100)
        status, state = await self.request("POST", "/api/arm", {"on": True})
        assert status == 200 and state["mine"], (status, state)
        for k in range(60):  # 3 s of drag: a target every 50 ms
            x = (m * 60 + k) / 20
            targets = {"base": 40 * math.sin(x), "elbow": 30 * math.cos(x)}
            status, _ = await self.request("POST", "/api/target", {"targets": targets})
            counts["targets" if status == 200 else "refused"] += 1
            await sleep_ms(50)
        status, state = await self.request("POST", "/api/play", {"loop": True})
        assert status == 200 and state["playing"] is not None, (status, state)
        counts["plays"] += 1
        player = self.panel.parts["busservo_web_teach"].player
        await sleep_ms(3000)
        counts["loops"] += player.loops
        if m % 60 == 0 and m:
            self.compare(m // 60, "playing")  # the player's too
        if m % (2 * EVERY) == 0:
            await self.request("POST", "/api/stop", {})
            await self.request("POST", "/api/arm", {"on": False})

    def measure(self, hour):
        """The sizes and the heap at the start of hour."""
        self.compare(hour, "between")  # in a frame of its own: none of its objects is left
        gc.collect()
        self.heap[hour] = gc.mem_alloc()
        if hour == self.hours:  # the largest of each kind, for the figures: not counted
            for path, n in self.sizes().items():
                kind = path.rpartition(" ")[2]
                if n > self.largest.get(kind, (0,))[0]:
                    self.largest[kind] = (n, path)

    def sizes(self):
        return sizes(self.panel, (wire.World, wire.UART, wire.Clock))

    def compare(self, hour, when):
        now = self.sizes()
        first = self.first.get(when)
        if first is None:
            self.first[when] = now
            return
        for path, n in now.items():
            if n > first.get(path, 0):
                self.grew.append((hour, path, first.get(path), n))

    async def page(self):
        await self.teach()
        t0 = self.world.clock.now_us
        for m in range(0, self.hours * 60 + 1, EVERY):
            await sleep_ms((t0 + m * 60000 * _MS - self.world.clock.now_us) // _MS)
            await self.burst(m)
            if m % 60 == 0 and m:  # a minute into the hour: its first burst is over
                await sleep_ms((t0 + (m + 1) * 60000 * _MS - self.world.clock.now_us) // _MS)
                self.measure(m // 60)

    def run(self):
        saved = busservo_web.asyncio, busservo_web.time
        busservo_web.asyncio, busservo_web.time = _Asyncio(self.board), self.world.clock
        try:
            self.robot = web_world.robot(self.world)  # busservo's and bm's time too
            self.panel = busservo_web.Panel(self.robot, PASSWORD)
            self.board.start(self.panel.run())
            self.board.start(self.page())
            self.board.run_to(self.world.clock.now_us + (self.hours * 3600 + 90) * 1000 * _MS)
        finally:
            busservo_web.asyncio, busservo_web.time = saved
            busservo.time = bm.time = time
        return self


class Day(unittest.TestCase):
    def test_24_hours_of_page_slider_and_sequence_grow_nothing(self):
        start = time.ticks_ms()
        soak = Soak(HOURS).run()
        took = time.ticks_diff(time.ticks_ms(), start) / 1000
        heap = soak.heap[1:]
        counts = soak.counts
        largest = ", ".join("%s %d" % (path, n) for n, path in sorted(soak.largest.values()))
        figures = (HOURS, took, heap[0], heap[-1], HOURS, min(heap), max(heap), largest)
        figures += (counts["polls"], counts["targets"], counts["plays"], counts["loops"])
        figures += (soak.robot.updates, soak.world.frames_total)
        print(
            "\n    %d simulated hours in %.0f s: heap %d B at hour 1, %d B at hour %d (%d..%d);"
            "\n    largest: %s;"
            "\n    %d polls, %d targets, %d plays, %d loops, %d updates, %d frames" % figures
        )
        self.assertEqual(soak.panel.error, None)
        clock = soak.world.clock
        self.assertTrue(clock._ms0 + clock.now_us // 1000 > wire.PERIOD)  # ticks_ms came round
        self.assertFalse(soak.grew, soak.grew[-3:])  # (hour, path, size at hour 1, then)
        self.assertTrue(max(heap) - min(heap) <= 1024, heap)
        # It did what it says: every burst's drag and play, the sequence round and round.
        bursts = HOURS * 60 // EVERY + 1  # one at hour 24 too
        self.assertEqual((counts["targets"], counts["refused"]), (60 * bursts, 0))
        self.assertEqual(counts["plays"], bursts)
        self.assertTrue(counts["loops"] >= 3 * bursts, counts["loops"])
        self.assertTrue(counts["polls"] >= 30 * bursts, counts["polls"])
        self.assertTrue(soak.robot.updates >= 30 * bursts, soak.robot.updates)

    def test_a_list_that_grows_at_each_state_poll_is_caught(self):
        soak = Soak(2, leak=True).run()
        heap = soak.heap[1:]
        self.assertTrue(max(heap) - min(heap) > 1024, heap)
        self.assertIn("panel._leaked list", [path for _, path, _, _ in soak.grew])


if __name__ == "__main__":
    unittest.main()
