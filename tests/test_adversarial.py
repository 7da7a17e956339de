# An adversarial review of the driver's reply rule (issue 28, part 1): which reply answers
# which query, with replies late, lost, cut or sooner than the wire allows. Each test is a
# scenario a user could meet, named for what the user sees. Those marked "(holds)" are
# guarantees that held under attack, kept because the suite lacked the case; the others
# failed on the driver as reviewed (lib/busservo.py at a34e7c4), each fixed since.
#
# Most run in tests/wire.py's world (a clock the test steps, the wire at 10 bits a byte, the
# simulated controller at its far end), on every port model; the fast peers also as a user
# has them (tests/fakeuart.py, busservo_sim with no line), on a simulated clock too: on real
# time a loaded machine's pauses are busy moments no test asked for.
import asyncio
import errno
import time
import unittest

import busservo
import busservo_async
import busservo_sim
import fakeuart
import wire
from busservo import CMD_GET_BATTERY_VOLTAGE
from fakeuart import FakeUART
from test_frames import BATTERY_7500, STOP
from test_queries import GET_BATTERY, UsersFake, timed_out
from test_reliability import SimAsyncio, settle


def world(port, baudrate=9600):
    """(world, bus): the driver at 9600 baud on the world's clock; the world's line at
    baudrate (more: a controller faster than the driver's wire model, as on USB HID)."""
    w = wire.World(port, baudrate=baudrate)
    busservo.time = w.clock
    return w, busservo.BusServo(w.uart)


def byte(state):
    """The next of a repeatable run of pseudo-random bytes (state: a list of one int)."""
    state[0] = (state[0] * 1103515245 + 12345) & 0x7FFFFFFF
    return state[0] >> 16 & 0xFF


def move_servo_1(w, position):
    """Servo 1 of the simulated controller goes to position at once (a command from
    elsewhere: the hand of a test), so that each query has a value of its own."""
    w.sim.write(b"\x55\x55\x08\x03\x01\x00\x00\x01" + bytes((position & 0xFF, position >> 8)))


def ask(w, bus, query, n):
    """Run query n (battery or positions of servo 1), each with a value of its own: its
    answer, None if it timed out."""
    if query == "battery":
        w.sim.battery = 7000 + n
        try:
            return bus.read_battery() - 7000
        except OSError:
            return None
    move_servo_1(w, n)
    try:
        return bus.read_positions([1])[1]
    except OSError:
        return None


def wrong_answers(w, bus, queries, until_us):
    """Ask queries (a list of "battery", "positions") in turn, back to back, until the
    world's clock passes until_us: [(query, its number, the other query's answer it got)]."""
    wrong = []
    n = 0
    while w.clock.now_us < until_us:
        for query in queries:
            n += 1
            got = ask(w, bus, query, n)
            if got is not None and got != n:
                wrong.append((query, n, got))
    return wrong


class LateReplies(unittest.TestCase):
    # Guarantee 1: a late reply costs at most one wrong answer.
    def tearDown(self):
        busservo.time = time

    def test_a_controller_stuck_for_2_s_then_a_pause_makes_one_answer_wrong_at_most(self):
        # Found by the review (fixed since).
        # The controller is stuck for about 2 s: the first read_battery()'s reply comes
        # late, and the replies to the next queries come behind it, so they time out too.
        # The program then pauses for 1.5 s (it retries later) and asks back to back. The
        # stuck replies come in a burst while the first query after the pause waits for its
        # own: taking the first of them is the one wrong answer the protocol allows (it
        # numbers no replies). But the given-up requests left the wire over a second ago, so
        # the next query does not listen first (ask(): `gone`); it asks at once, the rest of
        # the burst comes after its request could have been answered, and it takes one of
        # those: with 2 queries timed out, 2 wrong answers (each one behind); with 3, 3.
        # Seen for a ~100 ms span of lateness (2110..2205 ms with 2, 2420..2680+ with 3).
        for port in wire.PORTS:
            for timeouts, late in ((2, 2150), (3, 2450)):
                w, bus = world(port)
                w.late(late)
                for n in range(timeouts):
                    w.sim.battery = 6000 + n
                    self.assertTrue(timed_out(bus.read_battery), (port, late))
                w.run_ms(1500)
                wrong = wrong_answers(w, bus, ["battery"], w.clock.now_us + 600000)
                self.assertTrue(len(wrong) <= 1, (port, timeouts, late, wrong))

    def test_a_late_reply_amid_battery_and_position_queries_makes_one_answer_wrong_at_most(
        self,
    ):
        # Found by the review (fixed since).
        # As test_reliability's late-reply tests, with read_battery() and
        # read_positions([1]) in turn, back to back: one battery reply comes late, and
        # every reply behind it (of both kinds) with it. The driver counts the requests
        # given up on per kind, and each kind's queries take one wrong answer: a battery
        # query one behind, then a positions query one behind (or the other way round).
        # Seen for 35 of 312 lateness values (300..3500 ms, every 31 ms; 'bp', 'bpp' and
        # 'bbp' orders): 14 of 104 with the queries in turn. Part of it is the `gone` of the
        # test above (1106, 1464 ms); part (1757, 2046 ms) remains when that one is fixed:
        # the positions queries do not listen while the battery's late replies come.
        for port in wire.PORTS:
            for late, queries in (
                (1106, ["battery", "positions"]),
                (1757, ["battery", "positions"]),
                (2046, ["battery", "battery", "positions"]),
            ):
                w, bus = world(port)
                w.late(late)
                wrong = wrong_answers(w, bus, queries, (late + 800) * 1000)
                self.assertTrue(len(wrong) <= 1, (port, late, queries, wrong))

    def test_two_replies_late_in_a_row_leave_no_answer_one_behind_for_good(self):
        # Found by the review, and the worst: a regression of f628b15 (fixed since). The
        # controller answers two read_battery() in a row about 300 ms late (each 300 ms after
        # its request came: busy, or a USB hiccup twice), then every one at once; the
        # program asks back to back. The first late reply comes while the second query's
        # request is on the wire: too soon for it, so it is taken for the late reply it is,
        # and when the second query's own reply does not come by its deadline, ask() takes
        # the early one for its answer after all (waiting[kind + 8]) and forgets every
        # request given up on (`waiting[kind] = waiting[kind + 2] = 0`): "the late ones were
        # lost". They were not: the second reply comes 300 ms later, answers the third query
        # (which timed out meanwhile) as if it were its own, and from then on one reply is
        # always on its way that the driver does not count. Each query's request goes out
        # while the previous query's reply is still coming; that reply comes too soon to be
        # the answer, but with nothing given up on a too-soon reply answers (_apply(), the
        # `fits and not (early and waiting[kind + 2])` test), so every later answer is the
        # query before's, for as long as the queries go back to back (143 of 143 in 1.2 s;
        # a pause between two queries lets the extra reply come as an event, and ends it).
        # At 9600 baud for lateness 296..303 ms (10 of 400 values from 100 to 1500 ms, with 2,
        # 3 or 5 replies late in a row); with a controller faster than the wire (USB HID)
        # about as often (310 ms here).
        # Through busservo_async the same (poll_ms 1 to 5: lateness 297..304 ms).
        for port in wire.PORTS:
            for baudrate, late in ((9600, 300), (115200, 310)):
                w, bus = world(port, baudrate)
                w.late(late, 2)
                wrong = wrong_answers(w, bus, ["battery"], (late + 1200) * 1000)
                self.assertTrue(len(wrong) <= 2, (port, baudrate, late, len(wrong), wrong[:4]))

        async def queries(w, bus, until_us):
            wrong = []
            n = 0
            while w.clock.now_us < until_us:
                n += 1
                w.sim.battery = 7000 + n
                try:
                    got = await bus.read_battery() - 7000
                except OSError:
                    continue
                if got != n:
                    wrong.append((n, got))
            return wrong

        try:
            for port in wire.PORTS:
                w, bus = world(port)
                busservo_async.time = w.clock
                busservo_async.asyncio = SimAsyncio(w.clock)
                w.late(302, 2)
                wrong = asyncio.run(
                    queries(w, busservo_async.AsyncBusServo(bus, poll_ms=5), 1500000)
                )
                self.assertTrue(len(wrong) <= 2, (port, "busservo_async", len(wrong), wrong[:4]))
        finally:
            busservo_async.time = time
            busservo_async.asyncio = asyncio

    def test_one_reply_late_by_any_of_many_lateness_values_makes_one_answer_wrong_at_most(self):
        # (holds) test_reliability's battery_after_a_late_reply at lateness values between
        # the ones it tries, alone and with read_positions([1]) between (the late reply
        # and those behind it then meet the queries at other moments). Swept every 3 ms from
        # 100 to 2000 ms (battery alone) during the review: at most one wrong answer.
        for port in wire.PORTS:
            for late in (211, 999, 1999):
                w, bus = world(port)
                w.late(late)
                self.assertTrue(timed_out(bus.read_battery), (port, late))
                wrong = wrong_answers(w, bus, ["battery"], (late + 600) * 1000)
                self.assertTrue(len(wrong) <= 1, (port, late, wrong))

    def test_a_late_position_reply_is_never_the_answer_to_other_ids(self):
        # (holds) The reply to read_positions([1]) comes 150 or 1200 ms late while the program
        # asks for servos 1 and 2 back to back: no answer for [1, 2] is ever the late one
        # (it carries other ids), and read_positions([1]) afterwards is right.
        for port in wire.PORTS:
            for late in (150, 1200):
                w, bus = world(port)
                move_servo_1(w, 111)
                w.late(late)
                self.assertTrue(timed_out(lambda b=bus: b.read_positions([1])), (port, late))
                while w.clock.now_us < (late + 300) * 1000:
                    move_servo_1(w, w.clock.now_us // 1000 % 900 + 1)
                    want = w.sim.position(1)
                    try:
                        got = bus.read_positions([1, 2])
                    except OSError:
                        continue
                    self.assertEqual(got, {1: want, 2: 500}, (port, late))
                move_servo_1(w, 950)
                self.assertEqual(bus.read_positions([1]), {1: 950}, (port, late))

    def test_a_late_reply_with_requests_through_poll_between_queries(self):
        # (holds) A loop that sends request_battery() and polls its reply in, then asks
        # read_battery(), while one reply comes 150 or 2500 ms late: at most one wrong answer
        # from the queries, and every poll()ed battery reply is one of the controller's.
        for port in wire.PORTS:
            for late in (150, 2500):
                w, bus = world(port)
                w.late(late)
                self.assertTrue(timed_out(bus.read_battery), (port, late))
                wrong = []
                n = 0
                while w.clock.now_us < (late + 600) * 1000:
                    n += 1
                    w.sim.battery = 7000 + n
                    bus.request_battery()
                    for cmd in settle(w, bus, 20):
                        self.assertEqual(cmd, CMD_GET_BATTERY_VOLTAGE, port)
                    got = ask(w, bus, "battery", n)
                    if got is not None and got != n:
                        wrong.append((n, got))
                self.assertTrue(len(wrong) <= 1, (port, late, wrong))


class NoHang(unittest.TestCase):
    # Guarantee 3: no query hangs or waits far past its timeout.
    def tearDown(self):
        busservo.time = time

    def test_queries_end_in_time_under_a_stream_of_noise_or_frames(self):
        # (holds) One query timed out first (so each query first listens for its reply).
        # Then, while the program asks read_battery() and read_positions([1, 2, 3, 4]) in
        # turn for 0.8 s (polling 5 ms between), 3 bytes of noise or a STOP frame go onto
        # the line every 5 ms: the line is busy most of the time, some replies come too
        # late and some are lost in the noise. No query takes longer than waiting out the
        # earlier request (its timeout and 100 ms), then its own timeout (and the wire's few
        # ms); each ends with its answer or ETIMEDOUT. Also with the controller 12 times as
        # fast as the driver's 9600. (Tried for the review with frame starts 55 55 xx as
        # the noise, every 2 to 15 ms, for 3 s: the same.)
        for port in wire.PORTS:
            for baudrate in (9600, 115200):
                for kind in ("random", "STOP"):
                    why = (port, baudrate, kind)
                    rnd = [5]  # a small linear congruential generator: the same bytes each run
                    w, bus = world(port, baudrate)
                    due = [0]

                    def noise(w=w, rnd=rnd, kind=kind, due=due):
                        if w.clock.now_us >= due[0]:
                            due[0] = w.clock.now_us + 5000
                            if kind == "random":
                                w.noise(bytes(byte(rnd) for _ in range(3)))
                            else:
                                w.noise(b"\x55\x55\x02\x07")

                    w.uart.during("any", noise, times=1 << 30)
                    w.sim.silent = True
                    self.assertTrue(timed_out(bus.read_battery), why)
                    w.sim.silent = False
                    n = 0
                    while w.clock.now_us < 800000:
                        n += 1
                        timeout = 100 if n % 2 else 140  # the defaults: 100 ms, + 10 a servo
                        start = w.clock.now_us
                        try:
                            if n % 2:
                                bus.read_battery()
                            else:
                                bus.read_positions([1, 2, 3, 4])
                        except OSError as e:
                            self.assertEqual(e.args[0], errno.ETIMEDOUT, why)
                        took = (w.clock.now_us - start) // 1000
                        self.assertTrue(took <= 2 * timeout + 100 + 15, (why, n, took))
                        settle(w, bus, 5)
                    self.assertTrue(n >= 2, why)


class Early(unittest.TestCase):
    # bus.early counts replies sooner than the wire at baudrate allows: 0 with a
    # controller at that speed (docs/driver.md), and docs/troubleshooting.md tells a user
    # whose bus.early grows to change baudrate=.
    def tearDown(self):
        busservo.time = time

    def test_a_9600_controller_is_never_early_with_two_requests_in_flight(self):
        # Found by the review (fixed since).
        # Two request_battery() back to back (or request_positions() of the same ids:
        # a loop that asks again before the last reply is in), to a controller at 9600: the
        # first reply comes before the second request's own reply could, and _apply()
        # counts it early (its time is measured against the last request of its kind,
        # waiting[kind + 4], though it answers an older one: the `waiting[kind] > 1` branch
        # still counts `early and fits`). bus.early grows on a wire-faithful controller, and
        # the troubleshooting table sends the user to change a baudrate that is right.
        for port in wire.PORTS:
            w, bus = world(port)
            bus.request_battery()
            bus.request_battery()
            self.assertEqual(settle(w, bus, 50), [CMD_GET_BATTERY_VOLTAGE] * 2, port)
            for _ in range(10):  # a control loop: positions every 20 ms, 6 servos
                bus.request_positions([1, 2, 3, 4, 5, 6])
                settle(w, bus, 20)  # the reply takes 35 ms: two requests are in flight
            settle(w, bus, 50)
            self.assertEqual(bus.early, 0, port)

    def test_a_controller_faster_than_the_wire_is_counted_early(self):
        # (holds) The same controller on a line 12 times as fast: every reply is early.
        for port in wire.PORTS:
            w, bus = world(port, baudrate=115200)
            self.assertEqual(bus.read_battery(), 7500, port)
            self.assertEqual(bus.read_positions([1, 2]), {1: 500, 2: 500}, port)
            self.assertEqual(bus.early, 2, port)


class FastPeers(unittest.TestCase):
    # Guarantee 2: a peer faster than the wire always gets its answers.
    def tearDown(self):
        busservo.time = busservo_async.time = fakeuart.time = time
        busservo_async.asyncio = asyncio

    def async_world(self, port):
        w, bus = world(port, baudrate=115200)  # a controller on USB HID, say: 1 ms a reply
        busservo_async.time = w.clock
        busservo_async.asyncio = SimAsyncio(w.clock)
        return w, busservo_async.AsyncBusServo(bus, poll_ms=1)

    def queries_while_another_task_requests(self, port, kind, every_ms, missed):
        """One task asks read_battery() (kind 0) or read_positions([4]) 8 times, while
        another sends request_battery() or request_positions([1, 2, 3]) every every_ms and
        takes the replies as events; with missed, the controller missed one request first.
        The answers ('.') and timeouts ('T') of the 8 queries."""
        w, bus = self.async_world(port)

        def query():
            return bus.read_positions([4]) if kind else bus.read_battery()

        async def main():
            got = ""
            if missed:
                w.sim.silent = True  # unplugged for a moment
                try:
                    await query()
                except OSError:
                    pass
                w.sim.silent = False
            done = []

            async def monitor():
                while not done:
                    if kind:
                        bus.request_positions([1, 2, 3])
                    else:
                        bus.request_battery()
                    while bus.poll() is not None:
                        pass
                    await busservo_async.asyncio.sleep_ms(every_ms)

            task = asyncio.create_task(monitor())
            for _ in range(8):
                try:
                    await query()
                    got += "."
                except OSError:
                    got += "T"
            done.append(1)
            await task
            return got

        return asyncio.run(main())

    def test_a_fast_controller_answers_one_task_while_another_requests_every_10_ms(self):
        # Found by the review (fixed since).
        # A controller that answers within 1 ms; one task awaits read_battery() (or
        # read_positions([4])) while another sends request_battery() every 10 ms (or
        # request_positions([1, 2, 3]) every 20 ms: a 50 Hz monitor) and takes the replies
        # as events. The controller missed one request earlier (unplugged a moment). Then
        # every query times out, for as long as the other task runs, though each reply
        # comes within 1 ms. Why: the missed request stays counted in flight (waiting[kind]
        # 1 for good), as each reply to the other task's request is taken for the older one
        # in flight (_apply: `waiting[kind] > 1`); the query gives it up and asks; its reply,
        # early while one is given up on, is taken for the given-up one and sets
        # waiting[kind + 8], but the other task's next request clears that flag (_went), so
        # at its deadline the query raises ETIMEDOUT, and the count stays 1 in flight again.
        # Battery every 2..10 ms and positions every 2..20 ms fail; with nothing missed, or
        # with the monitor at 13 ms (battery) or 40 ms (positions), every query is answered.
        for port in wire.PORTS:
            for kind, every_ms in ((0, 10), (1, 20)):
                self.assertEqual(
                    self.queries_while_another_task_requests(port, kind, every_ms, False),
                    "........",
                    (port, kind, every_ms, "nothing missed"),
                )
                self.assertEqual(
                    self.queries_while_another_task_requests(port, kind, every_ms, True),
                    "........",
                    (port, kind, every_ms, "one missed"),
                )

    def test_a_fast_controllers_answer_to_a_query_is_no_event_after_a_missed_one(self):
        # Found by the review (fixed since).
        # A controller faster than the wire misses one read_battery() (unplugged a
        # moment); the next query waits out its timeout and takes the reply that came (the
        # early reply taken for the missed one's, then found to be its own: ask()'s
        # waiting[kind + 8] path). But ask() held that reply for poll() when it came
        # (`_hold(self, got)`, as it was not the answer then), so poll() also gives it as an
        # event: a task reading events() sees a battery reply that nobody requested (the
        # driver promises a query's reply is never an event: test_reliability's
        # test_a_querys_reply_is_never_an_event_for_another_task). Every time.
        for port in wire.PORTS:
            for query in ("battery", "positions"):
                w, bus = world(port, baudrate=115200)
                w.sim.silent = True
                self.assertIsNone(ask(w, bus, query, 1), port)
                w.sim.silent = False
                self.assertEqual(ask(w, bus, query, 2), 2, port)
                self.assertEqual(settle(w, bus, 20), [], (port, query))

    def test_a_fast_controller_after_missed_requests_answers_every_query(self):
        # (holds) A controller on a line 12 times as fast as the driver's 9600 misses 1 or 3
        # queries (unplugged), comes back, and the program asks again: with requests
        # through poll() between, after a pause of 1.2 s, or at once. The first query after
        # waits out its timeout (the driver cannot tell its reply from a late one), and
        # every query after it is answered, each with its own value.
        for port in wire.PORTS:
            for missed, between in ((1, ""), (3, ""), (1, "poll"), (1, "pause"), (2, "both")):
                why = (port, missed, between)
                w, bus = world(port, baudrate=115200)
                w.sim.silent = True
                for _ in range(missed):
                    self.assertTrue(timed_out(bus.read_battery), why)
                w.sim.silent = False
                for n in range(1, 8):
                    if between in ("poll", "both"):
                        bus.request_battery()
                        self.assertIn(CMD_GET_BATTERY_VOLTAGE, settle(w, bus, 5), why)
                    if between in ("pause", "both") and n == 2:
                        w.run_ms(1200)
                    self.assertEqual(ask(w, bus, "battery", n), n, why)
                    self.assertEqual(ask(w, bus, "positions", n), n, why)

    def test_fake_uarts_and_the_simulator_answer_every_query_after_missed_ones(self):
        # (holds) FakeUART(at_once=True) as it is, handing out 1 byte a readinto()
        # (chunks=[1]), answering 3 ms after the write (sooner than the wire's 12.5 ms round
        # trip); SimController(baudrate=None); and a user's own fake. Each misses two
        # queries (no reply), then answers: every query after is answered, with requests
        # through poll() between them. On a simulated clock (the fake's and the driver's): on
        # real time a loaded machine may read a reply late, and then one query may time out
        # (test_a_fast_peers_reply_read_late_once_does_not_stop_every_later_answer).
        clock = wire.Clock(cost_us=20)
        busservo.time = fakeuart.time = clock

        def fake(delay_ms=0, **kw):
            uart = FakeUART(**kw)

            def answer(on):
                if on:
                    uart.reply(GET_BATTERY, BATTERY_7500, delay_ms=delay_ms)
                else:
                    uart._replies.clear()

            return uart, answer

        def sim():
            uart = busservo_sim.SimController(baudrate=None)

            def answer(on):
                uart.silent = not on

            return uart, answer

        class Unplugged(UsersFake):
            silent = False

            def write(self, buf, off=None, n=None):
                out = len(self.out)
                took = UsersFake.write(self, buf, off, n)
                if self.silent:
                    self.out = self.out[:out]  # no reply
                return took

        def users():
            uart = Unplugged()

            def answer(on):
                uart.silent = not on

            return uart, answer

        peers = (
            ("at once", lambda: fake(at_once=True)),
            ("1 byte a read", lambda: fake(at_once=True, chunks=[1])),
            ("3 ms after", lambda: fake(at_once=True, delay_ms=3)),
            ("simulator", sim),
            ("a user's fake", users),
        )
        for name, make in peers:
            uart, answer = make()
            bus = busservo.BusServo(uart)
            answer(False)
            for _ in range(2):
                self.assertTrue(timed_out(lambda b=bus: b.read_battery(timeout_ms=20)), name)
            answer(True)
            for _ in range(4):
                self.assertEqual(bus.read_battery(timeout_ms=20), 7500, name)
                bus.request_battery()
                start = clock.ticks_ms()
                got = None
                while got is None and clock.ticks_diff(clock.ticks_ms(), start) < 1000:
                    got = bus.poll()
                self.assertEqual(got, CMD_GET_BATTERY_VOLTAGE, name)

    def test_a_fast_peers_reply_read_late_once_does_not_stop_every_later_answer(self):
        # A peer that answers 3 ms after the request (sooner than the wire's 10 ms), two
        # queries missed, and then the program is busy for 15 ms just after one request
        # leaves: its reply, read late, looked as slow as the wire, and the driver took the
        # peer for one; after a request through poll() every later query timed out, for good
        # (found under load: a fresh clone's run beside another). Now one does, at most. On
        # a simulated clock (the fake's and the driver's), so that only the busy moment the
        # test makes happens: a loaded machine's own made the real-time version miss more.
        clock = wire.Clock(cost_us=20)
        busservo.time = fakeuart.time = clock

        class Busy(FakeUART):
            busy_ms = 0

            def write(self, buf, off=None, n=None):
                took = FakeUART.write(self, buf, off, n)
                clock.sleep_ms(self.busy_ms)
                self.busy_ms = 0
                return took

        uart = Busy(at_once=True)
        bus = busservo.BusServo(uart)
        for _ in range(2):
            self.assertTrue(timed_out(lambda: bus.read_battery(timeout_ms=20)))
        uart.reply(GET_BATTERY, BATTERY_7500, delay_ms=3)
        uart.busy_ms = 15
        self.assertEqual(bus.read_battery(timeout_ms=20), 7500)
        bus.request_battery()
        start = clock.ticks_ms()
        got = None
        while got is None and clock.ticks_diff(clock.ticks_ms(), start) < 1000:
            got = bus.poll()
        self.assertEqual(got, CMD_GET_BATTERY_VOLTAGE)
        answered = 0
        for _ in range(6):
            try:
                answered += bus.read_battery(timeout_ms=20) == 7500
            except OSError:
                pass
        self.assertTrue(answered >= 5, answered)  # one timed out at most


class PositionsAndPoll(unittest.TestCase):
    # Guarantee 4: poll() never loses a frame, and bus.positions are right.
    def tearDown(self):
        busservo.time = time

    def test_every_frame_of_a_flood_during_a_query_is_polled_or_counted_lost(self):
        # Found by the review (fixed since):
        # by one frame. A peer at USB speed sends STOP frames back to back while a
        # query waits for a reply that never comes. The driver promises that a frame it
        # cannot hold for poll() (more than 32 came during one query) is counted in
        # bus.lost, not hidden. But ask() gives up after 32 frames past its deadline
        # (`late > _QUEUE`) and raises before it holds the frame it has just decoded
        # (`_hold(self, got)` comes after the raise): that frame is neither polled nor
        # counted. Every time a query times out in such a flood (also when it takes the
        # waiting[kind + 8] path and returns there).
        class Flood(FakeUART):
            frames = 0  # STOPs made readable so far
            flowing = True

            def any(self):
                if self.flowing and len(self._in) - self._head < 64:
                    self.frames += 16
                    self.feed(STOP * 16)
                return FakeUART.any(self)

        uart = Flood(at_once=True)
        bus = busservo.BusServo(uart)
        self.assertTrue(timed_out(lambda: bus.read_battery(timeout_ms=20)))
        uart.flowing = False
        polled = 0
        while bus.poll() is not None:
            polled += 1
        self.assertEqual((polled + bus.lost, uart.any()), (uart.frames, 0))

    # Not kept: a cut position reply followed at once by the next, read as one frame, puts
    # servos nobody asked for into bus.positions. The protocol has no checksum, and the
    # driver keeps the ids of the last request only; a bitmap of every id asked would cost
    # the driver RAM it does not have (8 KB on a board). Left for a later issue.


if __name__ == "__main__":
    unittest.main()
