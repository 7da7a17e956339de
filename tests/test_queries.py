# Blocking queries: read_battery() and read_positions() against a fake
# controller that answers (or not) what the driver writes.
import errno
import time
import unittest

import busservo
from busservo import (
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_RUN,
    CMD_ACTION_GROUP_STOP,
    CMD_GET_BATTERY_VOLTAGE,
    CMD_MULT_SERVO_POS_READ,
)
from fakeuart import FakeUART, SimulatedTime
from test_frames import ALL_500, BATTERY_7500, COMPLETE_8_ONCE, POSITIONS_ALL_500, RUN_8_ONCE, STOP

GET_BATTERY = bytes((0x55, 0x55, 0x02, 0x0F))
READ_1_TO_6 = bytes((0x55, 0x55, 0x09, 0x15, 0x06, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06))
BATTERY_7400 = bytes((0x55, 0x55, 0x04, 0x0F, 0xE8, 0x1C))


def timed_out(call):
    try:
        call()
    except OSError as e:
        return e.args[0] == errno.ETIMEDOUT
    return False


class Queries(unittest.TestCase):
    def setUp(self):
        self.uart = FakeUART()
        self.bus = busservo.BusServo(self.uart)

    def test_read_battery(self):
        self.uart.reply(GET_BATTERY, BATTERY_7500)
        self.assertEqual(self.bus.read_battery(), 7500)
        self.assertEqual(self.uart.written(), GET_BATTERY)
        self.assertEqual(self.bus.battery, 7500)
        self.assertIsNone(self.bus.poll())  # the reply was the query's, not poll()'s

    def test_read_positions(self):
        self.uart.reply(READ_1_TO_6, POSITIONS_ALL_500)
        self.assertEqual(self.bus.read_positions([1, 2, 3, 4, 5, 6]), ALL_500)
        self.assertEqual(self.uart.written(), READ_1_TO_6)
        self.assertEqual(self.bus.positions, ALL_500)
        self.assertIsNone(self.bus.poll())

    def test_read_positions_returns_this_reply_only(self):
        self.bus.positions[9] = 321
        self.uart.reply(READ_1_TO_6, POSITIONS_ALL_500)
        self.assertEqual(self.bus.read_positions([1, 2, 3, 4, 5, 6]), ALL_500)
        self.assertEqual(self.bus.positions[9], 321)

    def test_a_reply_in_time_with_other_ids_is_not_the_answer(self):
        # Asked for servos 1 and 2, the controller answers with 3 and 4 (another task's
        # request, say): the query waits on for its own, and times out; the reply is an event.
        read_1_2 = bytes((0x55, 0x55, 0x05, 0x15, 0x02, 0x01, 0x02))
        positions_3_4 = bytes((0x55, 0x55, 0x09, 0x15, 0x02, 0x03, 0xF4, 0x01, 0x04, 0xF4, 0x01))
        self.uart.reply(read_1_2, positions_3_4)
        self.assertTrue(timed_out(lambda: self.bus.read_positions([1, 2])))
        self.assertEqual(self.bus.poll(), CMD_MULT_SERVO_POS_READ)
        self.assertEqual(self.bus.positions, {3: 500, 4: 500})

    def test_a_reply_that_takes_its_time(self):
        self.uart.chunks = [1]
        self.uart.reply(GET_BATTERY, BATTERY_7500, delay_ms=30)
        self.assertEqual(self.bus.read_battery(timeout_ms=2000), 7500)

    def test_returns_as_soon_as_the_reply_is_complete(self):
        # No fixed sleep: with the reply there at once, a 5 s timeout is not waited out.
        self.uart.reply(GET_BATTERY, BATTERY_7500)
        start = time.ticks_ms()
        self.bus.read_battery(timeout_ms=5000)
        self.assertTrue(time.ticks_diff(time.ticks_ms(), start) < 1000)

    def test_no_reply_times_out(self):
        start = time.ticks_ms()
        self.assertTrue(timed_out(lambda: self.bus.read_battery(timeout_ms=30)))
        self.assertTrue(time.ticks_diff(time.ticks_ms(), start) >= 30)
        self.assertTrue(timed_out(lambda: self.bus.read_positions([1, 2], timeout_ms=10)))
        self.assertTrue(timed_out(lambda: self.bus.read_battery(timeout_ms=0)))

    def test_a_timeout_has_its_errno_on_every_python(self):
        # OSError(110) made with one argument has errno None on CPython: `e.errno ==
        # errno.ETIMEDOUT` would never match there, and the busservo command printed "110".
        for call in (
            lambda: self.bus.read_battery(timeout_ms=10),
            lambda: self.bus.read_positions([1], timeout_ms=10),
        ):
            try:
                call()
            except OSError as e:
                self.assertEqual(e.errno, errno.ETIMEDOUT)
                self.assertIn("no reply", str(e))
            else:
                self.fail("no timeout")

    def test_a_half_reply_times_out(self):
        self.uart.reply(GET_BATTERY, BATTERY_7500[:5])
        self.assertTrue(timed_out(lambda: self.bus.read_battery(timeout_ms=20)))
        self.assertIsNone(self.bus.battery)

    def test_a_reply_coming_in_at_the_deadline_is_taken_whole(self):
        # Its first bytes (up to its command) come 5 ms before the deadline (40 ms, and the
        # request's 4 bytes on the wire), its last 10 ms after it: it came in time, and is
        # the answer, not a timeout (a process busy elsewhere may look in between the two).
        self.uart.feed_later(BATTERY_7500[:4], 40)
        self.uart.feed_later(BATTERY_7500[4:], 55)
        self.assertEqual(self.bus.read_battery(timeout_ms=40), 7500)
        self.uart.feed_later(POSITIONS_ALL_500[:9], 50)
        self.uart.feed_later(POSITIONS_ALL_500[9:], 65)
        self.assertEqual(self.bus.read_positions([1, 2, 3, 4, 5, 6], timeout_ms=40), ALL_500)
        self.assertIsNone(self.bus.poll())

    def test_the_default_timeouts(self):
        start = time.ticks_ms()
        self.assertTrue(timed_out(self.bus.read_battery))
        battery = time.ticks_diff(time.ticks_ms(), start)
        start = time.ticks_ms()
        self.assertTrue(timed_out(lambda: self.bus.read_positions([1, 2, 3, 4, 5, 6])))
        positions = time.ticks_diff(time.ticks_ms(), start)
        self.assertTrue(battery >= 100, battery)
        self.assertTrue(positions >= 160, positions)  # 100 ms + 10 ms per servo

    def test_a_status_frame_during_a_query_waits_for_poll(self):
        self.uart.reply(GET_BATTERY, COMPLETE_8_ONCE + BATTERY_7500)
        self.assertEqual(self.bus.read_battery(), 7500)
        self.assertEqual(self.bus.group, 8)  # applied to the state at once
        self.assertEqual(self.bus.poll(), CMD_ACTION_GROUP_COMPLETE)
        self.assertIsNone(self.bus.poll())

    def test_frames_waiting_before_a_query_keep_their_order(self):
        self.uart.feed(RUN_8_ONCE)
        self.uart.feed_later(STOP, 0)
        self.uart.reply(READ_1_TO_6, COMPLETE_8_ONCE + POSITIONS_ALL_500)
        self.bus.read_positions(range(1, 7))
        got = [self.bus.poll(), self.bus.poll(), self.bus.poll(), self.bus.poll()]
        self.assertEqual(
            got, [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_STOP, CMD_ACTION_GROUP_COMPLETE, None]
        )

    def test_a_stale_reply_is_not_taken_for_the_answer(self):
        # A reply to an earlier request_battery() that nobody polled yet.
        self.bus.request_battery()
        self.uart.feed(BATTERY_7500)
        self.uart.reply(GET_BATTERY, BATTERY_7400)
        self.assertEqual(self.bus.read_battery(), 7400)
        self.assertEqual(self.bus.poll(), CMD_GET_BATTERY_VOLTAGE)
        self.assertIsNone(self.bus.poll())
        self.assertEqual(self.bus.battery, 7400)

    def test_requests_answered_through_poll(self):
        self.uart.reply(GET_BATTERY, BATTERY_7500, delay_ms=5)
        self.uart.reply(READ_1_TO_6, POSITIONS_ALL_500, delay_ms=5)
        self.bus.request_battery()
        self.bus.request_positions([1, 2, 3, 4, 5, 6])
        got = []
        start = time.ticks_ms()
        while len(got) < 2 and time.ticks_diff(time.ticks_ms(), start) < 2000:
            cmd = self.bus.poll()
            if cmd is not None:
                got.append(cmd)
        self.assertEqual(got, [CMD_GET_BATTERY_VOLTAGE, CMD_MULT_SERVO_POS_READ])
        self.assertEqual((self.bus.battery, self.bus.positions), (7500, ALL_500))

    def test_more_frames_than_the_queue_holds_are_counted_not_hidden(self):
        with SimulatedTime():  # (the wire's 173 ms, not a busy machine's)
            uart = FakeUART()
            bus = busservo.BusServo(uart)
            uart.reply(GET_BATTERY, STOP * 40 + BATTERY_7500)  # 173 ms on the wire
            self.assertEqual(bus.read_battery(timeout_ms=300), 7500)
            held = 0
            while bus.poll() is not None:
                held += 1
        self.assertEqual(held, 32)
        self.assertEqual(bus.lost, 8)

    def test_queries_on_ticks_past_2_to_the_30(self):
        # The unix port's ticks run to 2**62 (its clock counts from the machine's boot): after
        # 12.4 days up they pass 2**30, where a 32-bit port's come round. The driver's wire
        # times are ticks modulo 2**30; a reply's must be compared with them alike.
        class Later:
            def ticks_ms(self):
                return time.ticks_ms() + (3 << 30)

            ticks_add = staticmethod(time.ticks_add)
            ticks_diff = staticmethod(time.ticks_diff)
            sleep_us = staticmethod(time.sleep_us)

        busservo.time = Later()
        try:
            bus = busservo.BusServo(self.uart)
            self.uart.reply(GET_BATTERY, BATTERY_7500)
            self.uart.reply(READ_1_TO_6, POSITIONS_ALL_500)
            self.assertEqual(bus.read_battery(), 7500)
            self.assertEqual(bus.read_positions([1, 2, 3, 4, 5, 6]), ALL_500)
            bus.move(1, 500, 0)
            self.assertIn(bus.wire_ms(), (10, 11))
        finally:
            busservo.time = time

    def test_a_query_made_once_asks_again_and_again(self):
        # ask(again=True), for a loop that reads for ever: made once, it yields None while it
        # waits, True once the reply has come, and asks anew at its next step; once no reply
        # comes in time it yields False rather than raising, and goes on.
        bus = self.bus
        for request, replies, kind in (
            (GET_BATTERY, [BATTERY_7500, BATTERY_7400], None),
            (READ_1_TO_6, [POSITIONS_ALL_500, POSITIONS_ALL_500], [1, 2, 3, 4, 5, 6]),
        ):
            self.uart.clear()
            self.uart.reply(request, replies)  # one a request, then none
            query = bus.ask(kind, 60, again=True)
            said = []
            while len(said) < 4:
                step = next(query)
                if step is not None:
                    said.append((step, bus.battery if kind is None else bus.positions == ALL_500))
                time.sleep_ms(1)
            if kind is None:
                self.assertEqual(said, [(True, 7500), (True, 7400), (False, 7400), (False, 7400)])
            else:
                self.assertEqual([s[0] for s in said], [True, True, False, False])
                self.assertTrue(said[0][1])
            self.assertEqual(self.uart.written(), request * 4)
            self.assertIsNone(bus.poll())  # the replies were the query's

    def test_a_query_with_bad_arguments_reads_nothing_away(self):
        self.uart.feed(STOP)
        with self.assertRaises(ValueError):
            self.bus.read_positions([1, 300])
        self.assertEqual(self.bus.poll(), CMD_ACTION_GROUP_STOP)
        self.assertEqual(self.uart.writes, 0)


class UsersFake:
    """The fake UART a user writes first, to try a program with no controller: it answers
    each request inside write(), as fast as a computer can, whatever the baud rate."""

    def __init__(self):
        self.out = bytearray()

    def any(self):
        return len(self.out)

    def readinto(self, buf, n=None):
        n = min(len(buf), len(self.out), len(buf) if n is None else n)
        buf[:n] = self.out[:n]
        self.out = self.out[n:]
        return n or None

    def write(self, buf, off=None, n=None):
        frame = bytes(buf[: len(buf) if off is None else off] if n is None else buf[off : off + n])
        if frame[3] == 0x0F:  # the battery: 7500 mV
            self.out += BATTERY_7500
        elif frame[3] == 0x15:  # positions: every servo at 500
            count = frame[4]
            self.out += bytes((0x55, 0x55, 3 * count + 3, 0x15, count))
            for servo_id in frame[5 : 5 + count]:
                self.out += bytes((servo_id, 0xF4, 0x01))
        return len(frame)


class APeerFasterThanTheWire(unittest.TestCase):
    # A peer may answer sooner than 9600 baud allows: the user's own fake, a simulator on a
    # pty, a controller set to another speed, one on USB HID. Where no request of that kind
    # was given up on, nothing else can be the reply's answer: it answers, and is counted.
    def setUp(self):
        self.uart = FakeUART(at_once=True)
        self.uart.reply(GET_BATTERY, BATTERY_7500)
        self.uart.reply(READ_1_TO_6, POSITIONS_ALL_500)
        self.bus = busservo.BusServo(self.uart)

    def test_read_battery(self):
        self.assertEqual(self.bus.read_battery(), 7500)
        self.assertEqual(self.bus.read_battery(), 7500)
        self.assertEqual(self.bus.early, 2)
        self.assertIsNone(self.bus.poll())

    def test_read_positions(self):
        self.assertEqual(self.bus.read_positions([1, 2, 3, 4, 5, 6]), ALL_500)
        self.assertEqual(self.bus.read_positions([1, 2, 3, 4, 5, 6]), ALL_500)
        self.assertEqual(self.bus.early, 2)
        self.assertIsNone(self.bus.poll())

    def test_requests_answered_through_poll_leave_nothing_to_wait_for(self):
        self.bus.request_positions([1, 2, 3, 4, 5, 6])
        self.bus.request_battery()
        self.assertEqual([self.bus.poll(), self.bus.poll(), self.bus.poll()], [21, 15, None])
        self.assertEqual((self.bus.positions, self.bus.battery), (ALL_500, 7500))
        start = time.ticks_ms()  # both were answered: a query waits for neither
        self.assertEqual(self.bus.read_positions([1, 2, 3, 4, 5, 6]), ALL_500)
        self.assertEqual(self.bus.read_battery(), 7500)
        self.assertTrue(time.ticks_diff(time.ticks_ms(), start) < 100)

    def test_the_fake_a_user_writes_first(self):
        bus = busservo.BusServo(UsersFake())
        self.assertEqual(bus.read_battery(), 7500)
        self.assertEqual(bus.read_positions([3, 1]), {3: 500, 1: 500})
        bus.request_positions([2])
        self.assertEqual((bus.poll(), bus.positions[2]), (CMD_MULT_SERVO_POS_READ, 500))

    def test_after_a_query_timed_out_one_waits_its_timeout_then_every_one_is_answered(self):
        # A reply that comes too soon while one given up on may still come is taken for that
        # one; if the query's own never comes, it was the query's after all.
        uart = FakeUART(at_once=True)
        bus = busservo.BusServo(uart)
        with SimulatedTime() as clock:  # (the driver's waits, not a busy machine's)
            self.assertTrue(timed_out(lambda: bus.read_battery(timeout_ms=20)))  # unplugged
            uart.reply(GET_BATTERY, BATTERY_7500)  # and plugged in again
            self.assertEqual(bus.read_battery(timeout_ms=20), 7500)
            start = clock.ticks_ms()
            for _ in range(5):
                self.assertEqual(bus.read_battery(timeout_ms=20), 7500)
            self.assertTrue(clock.ticks_diff(clock.ticks_ms(), start) < 100)

    def test_a_query_ends_at_its_time_while_frames_come_faster_than_they_are_read(self):
        # A peer at USB speed that sends frames back to back (STOPs here), with a request in
        # flight that nothing answers: the query first waits for that one's reply, then asks
        # and gives up on its own. Once, it waited for a pause in the frames before it asked.
        class Flood(FakeUART):
            left = 200000  # frames still to come: some 20 s of this loop's work at least

            def any(self):
                if self.left and len(self._in) - self._head < 64:
                    self.left -= 16
                    self.feed(STOP * 16)
                return FakeUART.any(self)

        uart = Flood(at_once=True)
        bus = busservo.BusServo(uart)
        bus.request_battery()
        self.assertTrue(timed_out(lambda: bus.read_battery(timeout_ms=20)))
        self.assertTrue(uart.left > 0, "it waited for the frames to end")

    def test_a_peer_as_slow_as_the_wire_is_never_early(self):
        uart = FakeUART()
        uart.reply(GET_BATTERY, BATTERY_7500)
        uart.reply(READ_1_TO_6, POSITIONS_ALL_500)
        bus = busservo.BusServo(uart)
        for _ in range(3):
            self.assertEqual(bus.read_battery(), 7500)
            self.assertEqual(bus.read_positions([1, 2, 3, 4, 5, 6]), ALL_500)
        self.assertEqual(bus.early, 0)


if __name__ == "__main__":
    unittest.main()
