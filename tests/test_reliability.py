# The driver in a world as faithful as the wire (tests/wire.py): a UART with the
# semantics of a port's machine.UART, bytes that take 10 bits of 9600 baud each,
# the simulated controller at the far end, and faults injected on the way. Each
# scenario runs on every port model. One test a finding of the reliability issue.
import asyncio
import errno
import time
import unittest

import busservo
import busservo_async
import wire
from busservo import (
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_RUN,
    CMD_ACTION_GROUP_STOP,
    CMD_GET_BATTERY_VOLTAGE,
    CMD_MULT_SERVO_POS_READ,
)
from test_queries import timed_out

BATTERY_7500 = bytes((0x55, 0x55, 0x04, 0x0F, 0x4C, 0x1D))
BATTERY_7100 = bytes((0x55, 0x55, 0x04, 0x0F, 0xBC, 0x1B))
STOP = bytes((0x55, 0x55, 0x02, 0x07))


def ports():
    """(port, world, bus) for each port model, the driver on the world's clock."""
    for port in wire.PORTS:
        w = wire.World(port)
        busservo.time = w.clock
        yield port, w, busservo.BusServo(w.uart)


def settle(w, bus, ms=200):
    """Let ms of simulated time pass with a control loop polling every ms;
    return the commands of the frames that came."""
    got = []
    for _ in range(ms):
        w.clock.advance_ms(1)
        while True:
            cmd = bus.poll()
            if cmd is None:
                break
            got.append(cmd)
    return got


def late_then(w, bus, behind):
    """A battery query whose request is on the wire, begun once an earlier request's
    reply was given up on: that reply (7100 mV) comes 3 ms before the query's request has
    gone, with behind right after it. The controller answers nothing of its own (the test
    writes what comes)."""
    w.sim.silent = True
    bus.request_battery()
    w.clock.advance_ms(10)
    query = bus.ask(None, 50)  # gives up on that reply after 150 ms, then asks
    for ms in range(200):
        next(query)
        if bus.wire_ms():  # its request is on the wire
            return query
        if ms == 147:
            w.noise(BATTERY_7100 + behind)
        w.clock.advance_ms(1)
    raise AssertionError("the query never asked")


def moves(frames):
    return [f for f in frames if f[3] == busservo.CMD_SERVO_MOVE]


class UnixTicks(wire.Clock):
    """The unix port's ticks: they count from the machine's boot and run to 2**62, so after
    12.4 days up they are past 2**30, where a 32-bit port's come round. Here: 25 days up."""

    MASK = (1 << 62) - 1

    def __init__(self):
        super().__init__(start=(2 << 30, 0))

    def ticks_ms(self):
        t = self._ms0 + self.now_us // 1000
        self.now_us += self.cost_us
        return t

    def ticks_diff(self, end, start):
        return ((end - start + (1 << 61)) & self.MASK) - (1 << 61)

    def ticks_add(self, ticks, delta):
        return (ticks + delta) & self.MASK


class Wire(unittest.TestCase):
    def tearDown(self):
        busservo.time = time

    # 1. Cut frames: write() may take part of a frame, or none of it.

    def test_back_to_back_moves_all_reach_the_controller_whole(self):
        for port, w, bus in ports():
            for i in range(300):
                bus.move(1 + i % 6, 100 + i, 200)
            settle(w, bus, 1000)
            self.assertEqual(len(moves(w.frames())), 300, port)
            self.assertEqual((w.garbled, w.sim.beeps), (0, 0), port)
            self.assertEqual(w.sim.position(6), 100 + 299, port)

    def test_back_to_back_18_servo_moves_all_reach_the_controller_whole(self):
        for port, w, bus in ports():
            for i in range(20):
                bus.move_many([(s, 100 + 10 * i + s) for s in range(1, 19)], 100)
            settle(w, bus, 1200)
            self.assertEqual(len(moves(w.frames())), 20, port)
            self.assertEqual((w.garbled, w.sim.beeps), (0, 0), port)
            self.assertEqual(w.sim.position(18), 100 + 190 + 18, port)

    def test_a_uart_that_stops_taking_bytes_raises_and_the_frame_is_finished_later(self):
        for port, w, bus in ports():
            bus.move_many([(s, 600) for s in range(1, 31)], 100)  # 97 bytes, 101 ms of wire
            w.uart.stall(True)
            try:
                for _ in range(40):  # fills the transmit buffer, then cannot go on
                    bus.move_many([(s, 600) for s in range(1, 31)], 100)
                error = None
            except OSError as e:
                error = e.args[0]
            self.assertEqual(error, errno.EIO, port)  # not ETIMEDOUT: that means "no reply"
            w.uart.stall(False)
            bus.move(1, 900, 0)  # sends the cut frame's rest first, then itself
            settle(w, bus, 2000)
            self.assertEqual(w.garbled, 0, port)
            self.assertEqual(w.sim.beeps, 0, port)
            self.assertEqual(w.sim.position(1), 900, port)

    # 2. Noise must not swallow the good frames behind it.

    def test_three_bytes_of_noise_before_a_reply_lose_nothing(self):
        for port, w, bus in ports():
            for length in (3, 5, 21, 60, 255):
                w.noise(bytes((0x55, 0x55, length)))
                self.assertEqual(bus.read_battery(), 7500, "%s, Length %d" % (port, length))
            self.assertEqual(bus.noise, 15, port)

    def test_a_power_on_glitch_is_forgotten_at_once(self):
        for port, w, bus in ports():
            w.noise(b"\x55\x55\xff\x63")
            self.assertEqual(bus.read_battery(), 7500, port)

    def test_four_bytes_of_noise_are_no_position_reply(self):
        # 55 55 02 15: a positions header with a Length no reply has (3n + 3, n >= 1). Read
        # alone, it was once taken for a whole frame, decoded from the last reply's bytes.
        for port, w, bus in ports():
            self.assertEqual(bus.read_positions([1]), {1: 500}, port)
            w.noise(b"\x55\x55\x02\x15")
            w.sim.silent = True
            self.assertTrue(timed_out(lambda b=bus: b.read_positions([1])), port)
            self.assertEqual(bus.noise, 4, port)

    def test_a_positions_header_nobody_asked_for_holds_nothing_back(self):
        # 55 55 FF 15 54: the start of a reply for 84 servos, with no request in flight.
        # Taken for a frame, it held the frames behind it until 252 bytes had come, then
        # ate them as a nonsense positions event.
        for port, w, bus in ports():
            w.noise(b"\x55\x55\xff\x15\x54" + STOP * 70)  # 285 bytes: 297 ms of line
            got = settle(w, bus, 20)  # STOPs are in by 9.4, 13.5 and 17.7 ms
            self.assertTrue(got[:2] == [CMD_ACTION_GROUP_STOP] * 2, (port, got))
            got += settle(w, bus, 300)
            self.assertEqual(got, [CMD_ACTION_GROUP_STOP] * 70, port)
            self.assertEqual((bus.positions, bus.noise), ({}, 5), port)

    def test_a_positions_frame_no_request_in_flight_asked_for_is_noise(self):
        # Positions come only in reply. Once read_positions([1, 2]) has had its answer,
        # 55 55 09 15 02 ... again (noise, a reply given up on and forgotten) is noise and
        # moves no position; so it is while a request for 3 servos is in flight.
        two = b"\x55\x55\x09\x15\x02\x01\x6f\x00\x02\xde\x00"  # 1: 111, 2: 222
        for port, w, bus in ports():
            self.assertEqual(bus.read_positions([1, 2]), {1: 500, 2: 500}, port)
            w.noise(two + STOP)
            self.assertEqual(settle(w, bus, 30), [CMD_ACTION_GROUP_STOP], port)
            bus.request_positions([1, 2, 3])
            w.noise(two + STOP)  # before the reply, which comes behind it
            got = settle(w, bus, 60)
            self.assertEqual(got, [CMD_ACTION_GROUP_STOP, CMD_MULT_SERVO_POS_READ], port)
            self.assertEqual(bus.positions, {1: 500, 2: 500, 3: 500}, port)
            self.assertEqual(bus.noise, 2 * len(two), port)

    def test_a_frame_whose_rest_came_while_the_loop_was_away_is_read_not_dropped(self):
        # A reply is half in; poll() asks any() for more: none yet. Then the loop is away
        # (a garbage collection, a callback, another task) for 40 ms, and the rest comes
        # meanwhile. The line looks quiet since the last read, but it is not: once, the
        # frame's start was taken for noise, the whole reply lost (seen on a busy machine).
        for half in (14, 16, 18, 20, 22):  # ms after the request: part of the reply is in
            for port, w, bus in ports():
                why = (port, half)
                bus.request_positions([1, 2, 3, 4])  # 8 bytes out, 17 back: in by 26 ms
                w.clock.advance_ms(half)
                self.assertIsNone(bus.poll(), why)  # the reply's first bytes are read
                w.uart.during("any", lambda w=w: w.clock.advance_ms(40), when="after")
                got = settle(w, bus, 5)
                self.assertEqual((got, bus.noise), ([CMD_MULT_SERVO_POS_READ], 0), why)
                self.assertEqual(bus.positions, {1: 500, 2: 500, 3: 500, 4: 500}, why)

    def test_a_frame_cut_short_holds_nothing_hostage(self):
        for port, w, bus in ports():
            w.cut_reply(4)  # the battery reply stops after 55 55 04 0F
            self.assertTrue(timed_out(bus.read_battery), port)
            bus.run_group(1)  # the RUN that comes back is decoded, however quiet the line
            self.assertEqual(settle(w, bus, 100), [CMD_ACTION_GROUP_RUN], port)
            self.assertEqual(bus.noise, 4, port)

    # 3. A reply answers only the question it matches.

    def test_a_late_reply_is_not_the_answer_to_the_next_query(self):
        for port, w, bus in ports():
            w.late(150)
            self.assertTrue(timed_out(bus.read_battery), port)
            w.sim.battery = 7100
            self.assertEqual(bus.read_battery(), 7100, port)
            self.assertIn(CMD_GET_BATTERY_VOLTAGE, settle(w, bus, 10), port)

    def test_a_late_position_reply_is_not_the_answer_to_other_ids(self):
        for port, w, bus in ports():
            w.sim.write(b"\x55\x55\x0b\x03\x02\x00\x00\x01\x6f\x00\x02\xde\x00")  # 1: 111, 2: 222
            w.late(150)
            self.assertTrue(timed_out(lambda b=bus: b.read_positions([1, 2])), port)
            self.assertEqual(bus.read_positions([3]), {3: 500}, port)
            self.assertEqual(bus.positions[1], 111, port)  # the late reply, as an event

    def test_after_a_very_late_reply_queries_back_to_back_catch_up_at_once(self):
        # A reply 400 ms late comes after the next query has waited for it (100 + 100 ms)
        # and asked: that query takes it, and cannot know. Its own reply comes next; the
        # query after it waits for that one, so no further answer is one behind.
        for port, w, bus in ports():
            w.late(400)
            self.assertTrue(timed_out(bus.read_battery), port)
            got = []
            for mv in (7100, 6900, 6800, 6700):
                w.sim.battery = mv
                got.append(bus.read_battery())
            self.assertEqual(got[1:], [6900, 6800, 6700], port)

            w.late(400)
            self.assertTrue(timed_out(lambda b=bus: b.read_positions([1])), port)
            got = []
            for position in (600, 700, 800):  # servo 1 goes there at once (time 0)
                w.sim.write(
                    b"\x55\x55\x08\x03\x01\x00\x00\x01" + bytes((position & 0xFF, position >> 8))
                )
                got.append(bus.read_positions([1])[1])
            self.assertEqual(got[1:], [700, 800], port)

    def test_a_reply_over_half_a_second_late_makes_one_answer_wrong_at_most(self):
        # The controller answers one read_battery() late, then every later one at once,
        # each with its own value, while the program asks back to back. The protocol
        # numbers no replies: where the late one lands just when a fresh one could, that
        # answer is wrong. No other may be: a reply that comes before its request can
        # have been answered (the request still on the wire, or its reply's own bytes
        # not yet come) is not its answer. Once, every later answer was the one before.
        for port in wire.PORTS:
            for late, clock in (
                (300, None),
                (450, None),
                (600, None),
                (800, None),
                (1500, None),
                (3000, None),
                (600, UnixTicks()),  # on ticks past 2**30, as the unix port's after 12.4 days
            ):
                wrong, asked = self.battery_after_a_late_reply(port, late, clock)
                self.assertTrue(len(wrong) <= 1 and asked > 30, (port, late, wrong))

    def test_a_reply_seconds_late_on_ticks_past_2_to_the_30_makes_one_answer_wrong_at_most(self):
        # As above, on the unix port's ticks after 12.4 days up. When the requests given up
        # on left the wire is kept modulo 2**30, as the wire's times are, and must be
        # compared alike: compared unmasked, it looks ages old, they are forgotten at once,
        # and the replies on their way behind the late one answer the wrong queries.
        for port in wire.PORTS:
            for late in (1500, 3000):
                wrong, asked = self.battery_after_a_late_reply(port, late, UnixTicks())
                self.assertTrue(len(wrong) <= 1 and asked > 30, (port, late, wrong))

    def test_a_reply_seconds_late_after_a_pause_makes_one_answer_wrong_at_most(self):
        # As above, with a pause of 1.5 s after the first query timed out: queries stop
        # listening first for its reply a second after it, but go on counting it. Forgotten,
        # the replies behind the late one came one too many: the last of them, too soon for
        # the query just asked, was taken for its answer, and so on, each answer one behind.
        for port in wire.PORTS:
            wrong, asked = self.battery_after_a_late_reply(port, 3000, pause_ms=1500)
            self.assertTrue(len(wrong) <= 1 and asked > 30, (port, wrong))

    def battery_after_a_late_reply(self, port, late, clock=None, pause_ms=0):
        """The controller answers one read_battery() late ms late, then every one at once,
        each with its own value, for late + 600 ms of queries back to back (after pause_ms):
        ([(query, the wrong answer it got)], queries asked)."""
        w = wire.World(port, clock=clock)
        busservo.time = w.clock
        bus = busservo.BusServo(w.uart)
        w.late(late)
        self.assertTrue(timed_out(bus.read_battery), port)
        w.run_ms(pause_ms)
        wrong = []
        asked = 0
        while w.clock.now_us < (late + 600) * 1000:
            asked += 1
            w.sim.battery = 7000 + asked
            try:
                got = bus.read_battery()
            except OSError:  # the late reply is waited for, or in the way
                continue
            if got != 7000 + asked:
                wrong.append((asked, got))
        return wrong, asked

    def test_a_position_reply_over_half_a_second_late_makes_one_answer_wrong_at_most(self):
        for port in wire.PORTS:
            for late in (600, 1500):
                w = wire.World(port)
                busservo.time = w.clock
                bus = busservo.BusServo(w.uart)
                w.late(late)
                self.assertTrue(timed_out(lambda b=bus: b.read_positions([1])), port)
                wrong = []
                asked = 0
                while w.clock.now_us < (late + 600) * 1000:
                    asked += 1
                    position = 100 + asked
                    w.sim.write(b"\x55\x55\x08\x03\x01\x00\x00\x01" + bytes((position, 0)))
                    try:
                        got = bus.read_positions([1])[1]
                    except OSError:
                        continue
                    if got != position:
                        wrong.append((asked, got))
                self.assertTrue(len(wrong) <= 1 and asked > 30, (port, late, wrong))

    def test_a_reply_that_never_came_is_waited_for_once_then_listened_for_a_second(self):
        for port, w, bus in ports():
            w.sim.silent = True
            self.assertTrue(timed_out(bus.read_battery), port)
            w.sim.silent = False
            took = []
            while w.clock.now_us < 1500000:
                start = w.clock.now_us
                self.assertEqual(bus.read_battery(), 7500, port)
                took.append((w.clock.now_us - start) // 1000)
            # The first waits out the missing reply (its timeout and 100 ms more). For a
            # second after its request, each query first listens 20 ms for it (a burst of
            # late replies may come); then a round trip is about 10.4 ms again.
            self.assertTrue(200 <= took[0] <= 230, (port, took))
            self.assertTrue(all(ms <= 35 for ms in took[1:]), (port, took))
            self.assertTrue(all(ms <= 15 for ms in took[-10:]), (port, took))
            self.assertTrue(sum(ms > 15 for ms in took) < 40, (port, took))

    def test_every_request_in_flight_is_answered_before_a_query_asks(self):
        for port, w, bus in ports():
            bus.request_battery()
            bus.request_battery()
            w.clock.advance_ms(13)
            w.sync()  # both requests are in: two replies that say 7500 are on their way
            w.sim.battery = 7100
            self.assertEqual(bus.read_battery(), 7100, port)

            bus.request_positions([1])
            bus.request_positions([1])
            w.clock.advance_ms(15)
            w.sync()  # both requests are in: two replies that say 500 are on their way
            w.sim.write(b"\x55\x55\x08\x03\x01\x00\x00\x01\x20\x03")  # servo 1 to 800
            self.assertEqual(bus.read_positions([1]), {1: 800}, port)

    def test_a_request_behind_a_long_move_is_waited_for_until_it_is_answered(self):
        for port, _, bus in ports():
            bus.move_many([(s, 500) for s in range(1, 84)], 0)  # 254 bytes: 265 ms of wire
            bus.request_positions([1])  # behind it: answered in about 280 ms
            self.assertEqual(bus.read_positions([1]), {1: 500}, port)
            bus.move(1, 900, 0)
            self.assertEqual(bus.read_positions([1]), {1: 900}, port)  # not the one before

    def test_requests_for_other_ids_answered_in_turn_leave_nothing_to_wait_for(self):
        for port, w, bus in ports():
            bus.request_positions([1, 2, 3])
            bus.request_positions([4, 5, 6])
            self.assertEqual(len(settle(w, bus, 100)), 2, port)  # both replies, as events
            start = w.clock.now_us
            self.assertEqual(bus.read_positions([1]), {1: 500}, port)
            self.assertTrue(w.clock.now_us - start < 30000, port)  # asked at once

    def test_a_cut_request_finished_by_the_next_query_is_answered_once(self):
        w = wire.World("rp2")  # esp32's write() takes a 6-byte frame whole, or waits
        busservo.time = w.clock
        bus = busservo.BusServo(w.uart)
        w.uart.stall(True)  # the transmitter stops: its ring (256) and FIFO (32) fill up
        bus.unload(list(range(1, 11)))  # 15 bytes
        for _ in range(27):
            bus.move(1, 500, 0)  # 270 bytes: 3 left
        try:
            bus.request_battery()  # 3 of its 6 bytes go
            error = None
        except OSError as e:
            error = e.args[0]
        self.assertEqual(error, errno.EIO)
        w.uart.stall(False)
        settle(w, bus, 400)  # what the UART held has left
        self.assertEqual(bus.read_battery(), 7500)  # sends the cut request's rest, then its own
        w.sim.battery = 7100
        self.assertEqual(bus.read_battery(), 7100)
        settle(w, bus, 50)
        requests = [f for f in w.frames() if f[3] == CMD_GET_BATTERY_VOLTAGE]
        self.assertEqual((len(requests), w.garbled, w.sim.beeps), (3, 0, 0))

    def three_bytes_of_room(self):
        """(world, bus): an rp2 world whose UART stalls with 3 bytes of room left."""
        w = wire.World("rp2")
        busservo.time = w.clock
        bus = busservo.BusServo(w.uart)
        w.uart.stall(True)
        bus.unload(list(range(1, 11)))
        for _ in range(27):
            bus.move(1, 500, 0)
        return w, bus

    def test_a_cut_positions_request_finished_by_the_next_command_is_answered(self):
        # Its reply is a positions event, not noise: the request was counted once finished.
        w, bus = self.three_bytes_of_room()
        try:
            bus.request_positions([1, 2])  # 3 of its 7 bytes go
            error = None
        except OSError as e:
            error = e.args[0]
        self.assertEqual(error, errno.EIO)
        w.uart.stall(False)
        settle(w, bus, 400)
        bus.set_group_speed(1, 100)  # sends the cut request's rest first
        self.assertEqual(settle(w, bus, 100), [CMD_MULT_SERVO_POS_READ])
        self.assertEqual((bus.positions, bus.noise, w.garbled), ({1: 500, 2: 500}, 0, 0))

    def test_every_command_sends_a_cut_frames_rest_before_its_own(self):
        # The rest of a frame the UART took part of waits in the transmit buffer that every
        # command writes its own frame into: each must send that rest first.
        commands = {
            "move": lambda bus: bus.move(3, 800, 0),
            "move_many": lambda bus: bus.move_many([(3, 800)], 0),
            "run_group": lambda bus: bus.run_group(1),
            "stop_group": lambda bus: bus.stop_group(),
            "set_group_speed": lambda bus: bus.set_group_speed(1, 100),
            "unload": lambda bus: bus.unload([3]),
            "request_battery": lambda bus: bus.request_battery(),
            "request_positions": lambda bus: bus.request_positions([3]),
        }
        for name, command in commands.items():
            w, bus = self.three_bytes_of_room()
            with self.assertRaises(OSError):
                bus.move_many([(1, 700), (2, 700)], 0)  # 3 of its 13 bytes go
            w.uart.stall(False)
            settle(w, bus, 400)
            command(bus)
            settle(w, bus, 400)
            self.assertEqual((w.garbled, w.sim.beeps), (0, 0), name)
            self.assertEqual((w.sim.position(1), w.sim.position(2)), (700, 700), name)

    def test_the_longest_reply_handed_over_120_bytes_at_a_time_is_read_whole(self):
        # An esp32 UART made with timeout_char > 0 keeps ESP-IDF's RX threshold of 120
        # bytes: the 257-byte reply to 84 ids comes in parts 125 ms apart. The quiet
        # between them is no cut frame: its missing bytes are still on the wire.
        w = wire.World("esp32", timeout_char=10)
        busservo.time = w.clock
        bus = busservo.BusServo(w.uart)
        ids = list(range(1, 85))
        self.assertEqual(bus.read_positions(ids), {i: 500 for i in ids})
        bus.request_positions(ids)  # and through poll()
        self.assertEqual(settle(w, bus, 400), [CMD_MULT_SERVO_POS_READ])
        self.assertEqual(bus.noise, 0)

    def test_a_late_reply_read_together_with_the_answer_is_not_taken_for_it(self):
        # The reply to a request given up on ends just after the query's own request has
        # gone, too soon to answer it, and the answer comes right behind it; one read
        # brings the two. The first came before that read by the answer's 6 bytes: it is
        # not the answer, though it was read after the answer could have come.
        for port, w, bus in ports():
            query = late_then(w, bus, BATTERY_7500)
            w.clock.advance_ms(11)  # both in (12.5 ms of line), unread
            for _ in query:
                pass
            self.assertEqual(bus.battery, 7500, port)

    def test_a_late_reply_read_with_frames_behind_it_is_not_taken_for_the_answer(self):
        # As above, but what comes right behind the late reply is two STOPs (events of the
        # controller's own), and the answer a few ms later. The read that brings the late
        # reply and the STOPs comes after the answer could have begun to come, but the late
        # reply came before that read by the STOPs' 8 bytes: too soon to answer. The query
        # waits on, and takes the answer.
        for port, w, bus in ports():
            query = late_then(w, bus, STOP + STOP)
            w.clock.advance_ms(12)  # all in (14.6 ms of line), unread
            for ms in range(100):
                if ms == 5:
                    w.noise(BATTERY_7500)  # the answer
                if next(query, True):
                    break
                w.clock.advance_ms(1)
            self.assertEqual(bus.battery, 7500, port)
            self.assertEqual(settle(w, bus, 10).count(CMD_ACTION_GROUP_STOP), 2, port)

    def test_a_position_reply_with_other_ids_is_an_event(self):
        for port, w, bus in ports():
            w.noise(b"\x55\x55\x06\x15\x01\x07\xf4\x01")  # servo 7, unasked
            self.assertEqual(bus.read_positions([3], timeout_ms=200), {3: 500}, port)
            self.assertEqual(bus.poll(), CMD_MULT_SERVO_POS_READ, port)
            self.assertEqual(bus.positions[7], 500, port)

    # 4. A query's timeout counts from when its request has left the wire.

    def test_a_query_behind_a_long_move_waits_for_the_wire(self):
        for port, w, bus in ports():
            bus.move_many([(s, 500) for s in range(1, 41)], 100)  # 127 bytes, 132 ms of wire
            self.assertEqual(bus.read_battery(), 7500, port)
            bus.move_many([(s, 500) for s in range(1, 41)], 100)
            self.assertTrue(bus.wire_ms() > 100, port)
            w.clock.advance_ms(140)
            self.assertEqual(bus.wire_ms(), 0, port)

    def test_wire_ms_counts_the_last_bytes_part_of_a_ms(self):
        # A move is 10 bytes, 10.42 ms at 9600 baud: 10 ms on, its last byte is still on the
        # wire, and wire_ms() must not say 0 (a query's timeout would start too soon).
        for port, w, bus in ports():
            bus.move(1, 500, 0)
            self.assertEqual(bus.wire_ms(), 11, port)
            w.clock.advance_ms(10)
            self.assertEqual(bus.wire_ms(), 1, port)
            w.clock.advance_ms(1)
            self.assertEqual(bus.wire_ms(), 0, port)

    def test_seconds_of_bytes_ahead_are_counted_whole(self):
        # A UART with a 16 KB transmit buffer (rp2 allows 32766 bytes: 34 s): 17 s of bytes
        # ahead, all counted (once, more than 10 s was taken for the ticks coming round).
        for port in wire.PORTS:
            w = wire.World(port, txbuf=16384)
            busservo.time = w.clock
            bus = busservo.BusServo(w.uart)
            for i in range(129):  # 129 x 127 bytes
                bus.move_many([(s, 500 + i) for s in range(1, 41)], 100)
            ahead = w.tx_backlog_us() // 1000
            # The driver counts a byte's 1041.67 us exactly (in 1/9600 ms): all it adds is
            # the rounding to whole ms.
            more = bus.wire_ms() - ahead
            self.assertTrue(0 <= more <= 2, (port, bus.wire_ms(), ahead))
            self.assertEqual(bus.read_battery(), 7500, port)

    def test_back_to_back_moves_are_all_counted_and_a_query_behind_them_waits(self):
        # move() counts its bytes inline, not through _sent(). Read as an idle wire, a busy
        # one once left wire_ms() 10 ms behind 20 moves, and the query timed out.
        for port, w, bus in ports():
            for start in (0, 50):  # at once, then after the wire has been idle
                w.clock.advance_ms(start)
                for i in range(20):
                    bus.move(1 + i % 6, 500, 0)  # 200 bytes: 208 ms of wire
                ahead = bus.wire_ms() - w.tx_backlog_us() // 1000
                self.assertTrue(0 <= ahead <= 2, (port, start, ahead))
                self.assertEqual(bus.read_battery(), 7500, (port, start))

    def test_a_frame_the_uart_took_part_of_is_counted_whole(self):
        # The transmit buffer (256 bytes) holds a 67-byte move; of the next, 253 bytes, an
        # rp2 takes what fits at once and the rest as room comes. All of it is on the wire,
        # and all counted: were the part taken at once left out, wire_ms() would be 230 ms
        # short, and the query behind would time out.
        for port, w, bus in ports():
            bus.move_many([(s, 500) for s in range(1, 21)], 100)  # 67 bytes
            bus.move_many([(s, 500) for s in range(1, 84)], 100)  # 253 bytes
            ahead = bus.wire_ms() - w.tx_backlog_us() // 1000
            self.assertTrue(0 <= ahead <= 2, (port, bus.wire_ms(), ahead))
            self.assertEqual(bus.read_battery(), 7500, port)

    def test_wire_ms_counts_10_bits_a_byte(self):
        for port, w, bus in ports():
            self.assertEqual(bus.wire_ms(), 0, port)
            bus.move(1, 500, 0)
            self.assertIn(bus.wire_ms(), (10, 11), port)
            w.clock.advance_ms(11)
            self.assertEqual(bus.wire_ms(), 0, port)

    # 5. An exception from the UART loses nothing and leaves nothing half done.

    def test_an_exception_from_the_uart_loses_no_byte(self):
        # A 185-byte reply, read in parts; the UART raises (an unplugged
        # adapter's EIO, a Ctrl-C) at each point of the reading in turn.
        ids = range(1, 61)
        for method in ("any", "readinto"):
            for skip in range(3):
                for port, w, bus in ports():
                    why = "%s, %s, call %d" % (port, method, skip + 1)
                    bus.request_positions(ids)
                    w.clock.advance_ms(200)  # the reply is partway here
                    self.assertIsNone(bus.poll(), why)  # its first part is read
                    w.uart.fail(method, KeyboardInterrupt(), skip)
                    with self.assertRaises(KeyboardInterrupt):
                        settle(w, bus, 100)
                    self.assertEqual(settle(w, bus, 100), [CMD_MULT_SERVO_POS_READ], why)
                    self.assertEqual(bus.positions, {i: 500 for i in ids}, why)
                    self.assertEqual(getattr(bus, "noise", 0), 0, why)

    def test_a_command_from_a_callback_in_the_middle_of_poll(self):
        ids = range(1, 61)
        for port, w, bus in ports():
            bus.request_positions(ids)
            w.clock.advance_ms(200)
            self.assertIsNone(bus.poll())  # the first part of the reply is read
            # The next read brings more of it, and a timer callback sends a command.
            w.uart.during("readinto", lambda b=bus: b.set_group_speed(1, 150), "after")
            self.assertEqual(settle(w, bus, 100), [CMD_MULT_SERVO_POS_READ], port)
            self.assertEqual(bus.positions, {i: 500 for i in ids}, port)
            self.assertEqual(getattr(bus, "noise", 0), 0, port)
            self.assertEqual(w.sim.speed(1), 150, port)

    def test_a_poll_from_a_callback_in_the_middle_of_poll(self):
        got = []

        def callback():
            got.append(bus.poll())

        for port, w, bus in ports():
            got.clear()
            bus.request_battery()
            w.clock.advance_ms(20)
            w.uart.during("readinto", callback, when="after")
            self.assertEqual(settle(w, bus, 10), [CMD_GET_BATTERY_VOLTAGE], port)
            self.assertEqual(got, [None], port)

    # 7. The smaller ones.

    def test_the_wire_is_idle_after_any_time_idle(self):
        # Ticks wrap: us after 17.9 minutes, ms after 12.4 days on a 32-bit port.
        for port, w, bus in ports():
            bus.move(1, 500, 0)
            for minutes in (17.87, 17.9, 35.8, 60):
                w.clock.advance_us(int(minutes * 60000000))
                self.assertEqual(bus.wire_ms(), 0, (port, minutes))
                start = w.clock.now_us
                self.assertEqual(bus.read_battery(), 7500, port)
                self.assertTrue(w.clock.now_us - start < 15000, (port, minutes))

    def test_a_query_long_after_one_timed_out_waits_no_longer_than_its_own(self):
        for port, w, bus in ports():
            w.sim.silent = True
            self.assertTrue(timed_out(bus.read_battery), port)
            w.sim.silent = False
            # 12.4 days less 50 s: the ms ticks came round, and a stamp that old looks 50 s
            # ahead. The driver takes up to 40 s ahead for bytes still on the wire (a
            # UART's transmit buffer can hold 34 s of them), and anything more for a stamp
            # from before the ticks came round: it cannot tell in the 40 s before that.
            w.clock.advance_ms((1 << 30) - 50000)
            start = w.clock.now_us
            self.assertEqual(bus.read_battery(), 7500, port)
            self.assertTrue(w.clock.now_us - start < 250000, port)  # not 50 s

    def test_the_queries_defaults(self):
        for port, _, bus in ports():
            self.assertEqual(bus.read_battery(timeout_ms=None), 7500, port)
            bus.battery = None
            steps = len(list(bus.ask()))  # the battery, by default; a step a wait
            self.assertEqual(bus.battery, 7500, port)
            self.assertTrue(steps > 0, port)
            self.assertEqual(bus.read_positions([2, 1]), {2: 500, 1: 500}, port)

    def test_readinto_is_never_asked_for_more_than_its_buffer(self):
        from fakeuart import FakeUART

        class Strict(FakeUART):
            def readinto(self, buf, nbytes=None):
                assert nbytes is None or nbytes <= len(buf), (nbytes, len(buf))
                return FakeUART.readinto(self, buf, nbytes)

        uart = Strict()
        bus = busservo.BusServo(uart)
        uart.feed(b"\x55\x55")  # a frame's start, then a long run of noise
        self.assertIsNone(bus.poll())
        uart.feed(bytes(600) + STOP)
        while uart.any():
            bus.poll()
        self.assertEqual(bus.noise, 602)

    def test_positions_are_signed(self):
        for port, w, bus in ports():
            w.sim.silent = True  # the reply is ours: servo 1 at -3, servo 2 at 0
            bus.request_positions([1, 2])
            w.noise(b"\x55\x55\x09\x15\x02\x01\xfd\xff\x02\x00\x00")
            settle(w, bus, 20)
            self.assertEqual((bus.positions[1], bus.positions[2]), (-3, 0), port)

    def test_a_reply_that_comes_just_before_the_deadline_is_taken(self):
        for port, w, bus in ports():
            w.late(20)  # the round trip is about 10.4 ms: 30.4 ms, 26.2 after the request
            self.assertEqual(bus.read_battery(timeout_ms=27), 7500, port)

    def test_a_query_times_out_under_a_stream_of_other_frames(self):
        for port, w, bus in ports():
            w.sim.silent = True
            for _ in range(200):
                w.noise(STOP)  # a STOP every 4.2 ms, for 840 ms
            start = w.clock.now_us
            self.assertTrue(timed_out(bus.read_battery), port)
            self.assertTrue(w.clock.now_us - start < 150000, port)
            self.assertIn(CMD_ACTION_GROUP_STOP, settle(w, bus, 20), port)


if __name__ == "__main__":
    unittest.main()


class SimAsyncio:
    """asyncio for busservo_async in the world: sleeping advances the world's
    clock, then lets the other tasks run."""

    def __init__(self, clock):
        self.clock = clock
        self.Lock = asyncio.Lock

    async def sleep_ms(self, ms):
        self.clock.advance_ms(ms)
        await asyncio.sleep_ms(0)


def async_ports():
    """(port, world, AsyncBusServo) for each port model, on the world's clock."""
    for port, w, bus in ports():
        busservo_async.time = w.clock
        busservo_async.asyncio = SimAsyncio(w.clock)
        yield port, w, busservo_async.AsyncBusServo(bus, poll_ms=1)


class Async(unittest.TestCase):
    def tearDown(self):
        busservo.time = busservo_async.time = time
        busservo_async.asyncio = asyncio

    def test_a_cancelled_query_leaves_its_reply_to_events(self):
        async def main(w, bus):
            w.late(150)
            task = asyncio.create_task(bus.read_battery())
            await busservo_async.asyncio.sleep_ms(50)
            task.cancel()
            w.sim.battery = 7100
            return await bus.read_battery()

        for port, w, bus in async_ports():
            self.assertEqual(asyncio.run(main(w, bus)), 7100, port)
            self.assertEqual(bus.poll(), CMD_GET_BATTERY_VOLTAGE, port)  # the late one

    def test_wait_group_done_waits_for_the_group_run_group_started(self):
        async def main(w, bus):
            bus.run_group(1)  # 500 ms
            await busservo_async.asyncio.sleep_ms(495)  # its COMPLETE is on its way
            bus.run_group(2)  # 2000 ms
            start = w.clock.now_us
            how = await bus.wait_group_done()
            return how, bus.group, w.clock.now_us - start

        for port, w, bus in async_ports():
            how, group, took = asyncio.run(main(w, bus))
            self.assertEqual((how, group), (CMD_ACTION_GROUP_COMPLETE, 2), port)
            self.assertTrue(1990000 < took < 2100000, (port, took))

    def test_wait_group_done_tells_two_runs_of_one_group_apart_by_their_times(self):
        async def main(w, bus):
            bus.run_group(1, 1)  # 500 ms
            bus.run_group(1, 2)  # at once, before the first RUN is back: 1000 ms
            start = w.clock.now_us
            how = await bus.wait_group_done()  # not the STOP of the first run
            return how, bus.times, w.clock.now_us - start

        for port, w, bus in async_ports():
            how, times, took = asyncio.run(main(w, bus))
            self.assertEqual((how, times), (CMD_ACTION_GROUP_COMPLETE, 2), port)
            self.assertTrue(990000 < took < 1100000, (port, took))

    def test_wait_group_done_after_the_same_run_again_waits_for_the_new_one(self):
        async def main(w, bus, gap):
            bus.run_group(1)  # 500 ms
            await busservo_async.asyncio.sleep_ms(gap)  # no task reads the bus meanwhile
            bus.run_group(1)  # the frames of the first run are in, unread
            start = w.clock.now_us
            how = await bus.wait_group_done()
            return how, w.clock.now_us - start

        for gap in (100, 600):
            for port, w, bus in async_ports():
                how, took = asyncio.run(main(w, bus, gap))
                self.assertEqual(how, CMD_ACTION_GROUP_COMPLETE, (port, gap))
                self.assertTrue(490000 < took < 600000, (port, gap, took))

    def test_wait_group_done_after_a_run_that_stops_the_running_group(self):
        async def main(w, bus):
            bus.run_group(2, 0)  # forever
            await busservo_async.asyncio.sleep_ms(100)
            bus.run_group(1)  # the controller stops group 2 (STOP), then runs 1
            return await bus.wait_group_done(), bus.group

        for port, w, bus in async_ports():
            self.assertEqual(asyncio.run(main(w, bus)), (CMD_ACTION_GROUP_COMPLETE, 1), port)

    def test_a_querys_reply_is_never_an_event_for_another_task(self):
        async def main(w, bus):
            got = []

            async def listen():
                while True:
                    cmd = bus.poll()
                    if cmd is not None:
                        got.append(cmd)
                    await busservo_async.asyncio.sleep_ms(1)

            listener = asyncio.create_task(listen())
            await busservo_async.asyncio.sleep_ms(0)
            volts = await bus.read_battery()
            await busservo_async.asyncio.sleep_ms(20)
            listener.cancel()
            return volts, got

        for port, w, bus in async_ports():
            self.assertEqual(asyncio.run(main(w, bus)), (7500, []), port)

    def test_another_tasks_request_for_other_ids_does_not_hide_a_querys_reply(self):
        async def main(w, bus):
            async def other():
                await busservo_async.asyncio.sleep_ms(3)
                bus.request_positions([2])  # while the query below waits for [1]

            task = asyncio.create_task(other())
            got = await bus.read_positions([1])
            await task
            return got

        for port, w, bus in async_ports():
            self.assertEqual(asyncio.run(main(w, bus)), {1: 500}, port)

    def test_wait_group_done_when_its_run_echo_is_lost(self):
        # A byte of the RUN that comes back is lost on the line: the COMPLETE,
        # which names the group, still ends the wait (it used to hang for ever).
        async def main(w, bus):
            w.drop(1, skip=3)
            bus.run_group(1)
            return await bus.wait_group_done(timeout_ms=2000)

        for port, w, bus in async_ports():
            self.assertEqual(asyncio.run(main(w, bus)), CMD_ACTION_GROUP_COMPLETE, port)

    def test_a_bad_timeout_writes_nothing(self):
        for port, w, bus in async_ports():
            for bad in (-1, 60001, 1.5, "100"):
                with self.assertRaises((ValueError, TypeError)):
                    asyncio.run(bus.read_battery(timeout_ms=bad))
                with self.assertRaises((ValueError, TypeError)):
                    asyncio.run(bus.read_positions([1], timeout_ms=bad))
            w.clock.advance_ms(20)
            self.assertEqual(w.received(), b"", port)
