# The simulated controller, driven by the real driver, on a clock the tests step:
# with no line (baudrate=None), so what it says is there at once and its replies
# are read straight from it; then its line, which makes a reply come no sooner
# than over a 9600-baud wire.
import time
import unittest

import busservo
import busservo_sim
from busservo import (
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_RUN,
    CMD_ACTION_GROUP_STOP,
)
from busservo_sim import SimController
from fakeuart import FakeUART
from test_frames import drain as events

RUN_8 = bytes((0x55, 0x55, 0x05, 0x06, 0x08, 0x01, 0x00))
BATTERY = bytes((0x55, 0x55, 0x02, 0x0F))
BATTERY_7500 = bytes((0x55, 0x55, 0x04, 0x0F, 0x4C, 0x1D))


def read_positions(sim, ids):
    """CMD_MULT_SERVO_POS_READ, straight to a simulator with no line: {id: position}."""
    sim.write(bytes((0x55, 0x55, len(ids) + 3, 0x15, len(ids)) + tuple(ids)))
    r = sim.read()
    assert r[:5] == bytes((0x55, 0x55, 3 * len(ids) + 3, 0x15, len(ids))), r
    return {r[i]: r[i + 1] | r[i + 2] << 8 for i in range(5, len(r), 3)}


def read_battery(sim):
    """CMD_GET_BATTERY_VOLTAGE, straight to a simulator with no line: mV."""
    sim.write(BATTERY)
    r = sim.read()
    assert r[:4] == BATTERY_7500[:4], r
    return r[4] | r[5] << 8


class Clock:
    def __init__(self):
        self.now = 1000

    def __call__(self):
        return self.now

    def step(self, ms):
        self.now += ms


class BoardTime:
    """time as on a board, for busservo_sim.time: ticks wrap at 2**30 ms and
    ticks_add() refuses half that (the unix port's wrap at 2**62). Starts a
    second before the wrap."""

    PERIOD = 1 << 30

    def __init__(self):
        self.now = self.PERIOD - 1000

    def ticks_ms(self):
        return self.now

    def step(self, ms):
        self.now = (self.now + ms) % self.PERIOD

    def ticks_diff(self, end, start):
        half = self.PERIOD // 2
        return (end - start + half) % self.PERIOD - half

    def ticks_add(self, ticks, delta):
        if not -self.PERIOD // 2 < delta < self.PERIOD // 2:
            raise OverflowError("ticks interval overflow")
        return (ticks + delta) % self.PERIOD


class Simulator(unittest.TestCase):
    def setUp(self):
        self.clock = Clock()
        self.sim = SimController(
            groups={1: 500, 2: 2000, 8: 1500}, ticks_ms=self.clock, baudrate=None
        )
        self.bus = busservo.BusServo(self.sim)

    def test_servos_move_linearly_to_their_targets(self):
        self.bus.move_many([(1, 900), (2, 100)], 1000)
        self.assertEqual(read_positions(self.sim, [1, 2]), {1: 500, 2: 500})
        self.clock.step(250)
        self.assertEqual(read_positions(self.sim, [1, 2]), {1: 600, 2: 400})
        self.clock.step(750)
        self.assertEqual(read_positions(self.sim, [1, 2]), {1: 900, 2: 100})
        self.clock.step(5000)
        self.assertEqual(read_positions(self.sim, [2]), {2: 100})

    def test_a_new_move_starts_from_where_the_servo_is(self):
        self.bus.move(3, 1000, 1000)
        self.clock.step(500)  # at 750
        self.bus.move(3, 250, 500)
        self.clock.step(250)
        self.assertEqual(read_positions(self.sim, [3]), {3: 500})

    def test_move_with_no_time_is_there_at_once(self):
        self.bus.move(4, 42, 0)
        self.assertEqual(self.sim.position(4), 42)

    def test_a_target_beyond_1000_stops_at_1000_and_is_counted(self):
        # The wire carries 0..65535; a servo turns 0..1000 and stops at its end.
        self.bus.move_many([(1, 1001), (2, 65535), (3, 1000)], 0)
        self.assertEqual(read_positions(self.sim, [1, 2, 3]), {1: 1000, 2: 1000, 3: 1000})
        self.assertEqual(self.sim.clamped, 2)
        self.bus.move(1, 0, 0)
        self.assertEqual((self.sim.position(1), self.sim.clamped), (0, 2))

    def test_a_pwm_servo_turns_to_2500_and_stops_there(self):
        self.sim.pwm.add(6)  # a PWM servo on an LSC board: 500..2500 us
        self.bus.move_many([(6, 2400), (1, 2400)], 0)
        self.assertEqual(read_positions(self.sim, [6, 1]), {6: 2400, 1: 1000})
        self.bus.move(6, 3000, 0)
        self.assertEqual((self.sim.position(6), self.sim.clamped), (2500, 2))

    def test_a_group_runs_then_completes(self):
        self.bus.run_group(8, 2)
        self.assertEqual(events(self.bus), [CMD_ACTION_GROUP_RUN])
        self.assertEqual((self.bus.running, self.bus.group, self.bus.times), (True, 8, 2))
        self.clock.step(2999)
        self.assertEqual(events(self.bus), [])
        self.clock.step(1)
        self.assertEqual(events(self.bus), [CMD_ACTION_GROUP_COMPLETE])
        self.assertEqual((self.bus.running, self.bus.group, self.bus.times), (False, 8, 2))

    def test_a_forever_group_runs_until_stopped(self):
        self.bus.run_group(2, 0)
        self.clock.step(10**6)
        self.assertEqual(events(self.bus), [CMD_ACTION_GROUP_RUN])
        self.assertEqual(self.sim.running, 2)
        self.bus.stop_group()
        self.assertEqual(events(self.bus), [CMD_ACTION_GROUP_STOP])
        self.assertIsNone(self.sim.running)
        self.assertFalse(self.bus.running)

    def test_stop_with_nothing_running_does_nothing(self):
        self.bus.stop_group()
        self.assertEqual(events(self.bus), [])

    def test_a_run_stops_the_group_before(self):
        self.bus.run_group(2, 0)
        self.bus.run_group(1, 1)
        self.assertEqual(
            events(self.bus), [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_STOP, CMD_ACTION_GROUP_RUN]
        )
        self.assertEqual(self.bus.group, 1)

    def test_speed_scales_a_group(self):
        self.bus.set_group_speed(1, 200)  # 500 ms at 200 %: 250 ms
        self.bus.run_group(1)
        self.clock.step(250)
        self.assertEqual(events(self.bus), [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_COMPLETE])
        self.assertEqual(self.sim.speed(2), 100)

    def test_speed_for_all_groups_is_lost_at_power_off(self):
        self.bus.set_group_speed(busservo.ALL_GROUPS, 50)
        self.assertEqual([self.sim.speed(g) for g in (1, 2, 8)], [50, 50, 50])
        self.sim.power_cycle()
        self.assertEqual([self.sim.speed(g) for g in (1, 2, 8)], [100, 100, 100])

    def test_unload_lets_servos_go_limp_where_they_are(self):
        self.bus.move(5, 900, 1000)
        self.clock.step(500)
        self.bus.unload([5, 6])
        self.assertEqual(self.sim.limp, {5, 6})
        self.clock.step(1000)
        self.assertEqual(read_positions(self.sim, [5]), {5: 700})
        self.bus.move(5, 100, 0)
        self.assertEqual(self.sim.limp, {6})

    def test_battery(self):
        self.assertEqual(read_battery(self.sim), 7500)
        self.sim.battery = 6800
        self.assertEqual(read_battery(self.sim), 6800)

    def test_malformed_frames_beep(self):
        self.sim.write(bytes((0x55, 0x55, 0x09, 0x07)))  # STOP of the wrong length
        self.sim.write(bytes((0x55, 0x55, 0x05, 0x06, 0x63, 0x01, 0x00)))  # no group 99
        self.assertEqual(self.sim.beeps, 2)
        self.bus.request_battery()  # and the controller still answers
        self.assertEqual(events(self.bus), [busservo.CMD_GET_BATTERY_VOLTAGE])
        self.assertEqual(self.sim.beeps, 2)

    def test_commands_split_across_writes(self):
        sent = bytes((0x55, 0x55, 0x05, 0x06, 0x08, 0x01, 0x00))
        for b in sent:
            self.sim.write(bytes((b,)))
        self.assertEqual(self.sim.running, 8)

    def test_silent_answers_nothing(self):
        self.sim.write(bytes((0x55, 0x55, 0x03, 0xF0, 0x01)))
        self.assertTrue(self.sim.silent)
        try:
            self.bus.read_battery(timeout_ms=0)
        except OSError:
            pass
        else:
            self.fail("a silent simulator answered")
        self.sim.silent = False
        self.assertEqual(read_battery(self.sim), 7500)

    # As a UART: the stream protocol's forms, and no surprises for the caller.

    def test_readinto_never_resizes_the_callers_buffer(self):
        self.sim.write(bytes((0x55, 0x55, 0x02, 0x0F)))  # 6 bytes come back
        buf = bytearray(2)
        self.assertEqual(self.sim.readinto(buf, 10), 2)
        self.assertEqual(len(buf), 2)
        self.assertEqual(self.sim.any(), 4)

    def test_write_takes_the_stream_protocols_forms(self):
        run_8 = bytes((0x55, 0x55, 0x05, 0x06, 0x08, 0x01, 0x00))
        self.assertEqual(self.sim.write(b"xx" + run_8, 2, 3), 3)
        self.assertEqual(self.sim.write(run_8, 3, 100), 4)  # clamped to the buffer
        self.assertEqual(self.sim.running, 8)
        self.assertEqual(self.sim.write(run_8 + b"zz", 7), 7)
        self.assertEqual(self.sim.beeps, 0)

    def test_write_clamps_an_offset_past_the_end(self):
        self.assertEqual(self.sim.write(RUN_8, 50, 3), 0)
        self.assertEqual(self.sim.write(RUN_8, 7, 1), 0)
        self.assertEqual(self.sim.write(RUN_8, 0), 0)
        self.assertIsNone(self.sim.running)
        self.assertEqual(self.sim.beeps, 0)

    def test_a_run_longer_than_ticks_add_can_span_ends_on_time(self):
        # 65535 runs of a 2 s group at 1 %: 200 s a run, 152 days in all, where
        # a board's ticks_add() takes 6 days at most.
        board = BoardTime()
        busservo_sim.time = board
        try:
            sim = SimController(ticks_ms=board.ticks_ms, baudrate=None)
            bus = busservo.BusServo(sim)
            bus.set_group_speed(2, 1)
            bus.run_group(2, 65535)
            self.assertEqual(events(bus), [CMD_ACTION_GROUP_RUN])
            left = 65535 * 200000
            while left > 1 << 28:  # 3 days a look
                board.step(1 << 28)
                left -= 1 << 28
                self.assertEqual(sim.running, 2)
            board.step(left - 1)
            self.assertEqual(sim.running, 2)
            self.assertEqual(events(bus), [])
            board.step(1)
            self.assertIsNone(sim.running)
            self.assertEqual(events(bus), [CMD_ACTION_GROUP_COMPLETE])
            self.assertEqual((bus.group, bus.times), (2, 65535))
        finally:
            busservo_sim.time = time

    def test_a_long_run_is_stopped_and_the_next_runs(self):
        board = BoardTime()
        busservo_sim.time = board
        try:
            sim = SimController(ticks_ms=board.ticks_ms, baudrate=None)
            bus = busservo.BusServo(sim)
            bus.set_group_speed(2, 1)
            bus.run_group(2, 65535)
            board.step(1 << 29)
            self.assertEqual(sim.running, 2)
            bus.stop_group()
            self.assertIsNone(sim.running)
            bus.run_group(8)
            self.assertEqual(sim.running, 8)
            board.step(1500)
            self.assertIsNone(sim.running)
            self.assertEqual(
                events(bus),
                [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_STOP]
                + [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_COMPLETE],
            )
        finally:
            busservo_sim.time = time

    def test_a_frame_that_raises_is_gone_and_the_frames_after_it_are_done(self):
        # A battery set in volts, not mV, by mistake: its frame raises, once.
        self.sim.battery = 7.5
        with self.assertRaises(TypeError):
            self.sim.write(BATTERY + RUN_8)
        self.sim.battery = 7500
        self.assertEqual(self.sim.write(BATTERY), 4)  # the RUN first, then this
        self.assertEqual(self.sim.running, 8)
        self.assertEqual(self.sim.read(), RUN_8 + BATTERY_7500)
        self.assertEqual(self.sim.beeps, 0)


class UartForms(unittest.TestCase):
    # Every UART-like object here takes the stream protocol's write(buf),
    # write(buf, n) and write(buf, off, n), off clamped to len(buf) and n to what
    # is left; readinto(buf, n) clamps n to len(buf) and never resizes buf.

    def test_the_fake_uart_writes_the_forms(self):
        uart = FakeUART()
        self.assertEqual(uart.write(b"ab" + BATTERY + b"cd", 2, 4), 4)
        self.assertEqual(uart.write(RUN_8, 3), 3)
        self.assertEqual(uart.write(RUN_8, 3, 100), 4)
        self.assertEqual(uart.write(RUN_8, 50, 2), 0)
        self.assertEqual(uart.write(RUN_8), 7)
        self.assertEqual(uart.written(), BATTERY + RUN_8 + RUN_8)

    def test_the_fake_uart_takes_what_takes_says(self):
        uart = FakeUART()
        uart.takes = [3, None, 10]
        data = bytes(range(20))
        self.assertEqual(uart.write(data), 3)
        self.assertIsNone(uart.write(data, 3, 17))
        self.assertEqual(uart.write(data, 3, 17), 10)
        self.assertEqual(uart.write(data, 13, 7), 7)  # the list is used up: all
        self.assertEqual(uart.written(), data)
        uart.takes = []
        self.assertEqual(uart.write(data), 20)

    def test_the_fake_uart_reply_comes_to_a_whole_write(self):
        uart = FakeUART()
        uart.reply(BATTERY, BATTERY_7500)
        self.assertEqual(uart.write(b"x" + BATTERY, 1, 4), 4)
        self.assertIsNone(uart.read())  # not before the wire could bring it: 10 bytes
        time.sleep_ms(12)
        self.assertEqual(uart.read(), BATTERY_7500)

    def test_the_fake_uart_answers_a_request_written_in_parts(self):
        uart = FakeUART()
        uart.reply(BATTERY, [BATTERY_7500, BATTERY_7500[:4] + b"\x00\x00"])
        uart.takes = [1, None, 2]
        self.assertEqual(uart.write(BATTERY), 1)
        self.assertIsNone(uart.write(BATTERY, 1, 3))
        self.assertEqual(uart.write(BATTERY, 1, 3), 2)
        self.assertEqual(uart.any(), 0)
        self.assertEqual(uart.write(BATTERY, 3, 1), 1)
        time.sleep_ms(12)
        self.assertEqual(uart.read(), BATTERY_7500)
        self.assertEqual(uart.write(BATTERY, 2), 2)  # a part, never finished
        self.assertEqual(uart.write(BATTERY), 4)  # a whole one is still answered
        time.sleep_ms(14)
        self.assertEqual(uart.read(), BATTERY_7500[:4] + b"\x00\x00")

    def test_readinto_clamps_to_the_buffer(self):
        sim = SimController(baudrate=None)
        sim.write(BATTERY)
        fake = FakeUART()
        fake.feed(BATTERY_7500)
        for uart in (sim, fake):
            buf = bytearray(4)
            self.assertEqual(uart.readinto(buf, 100), 4)
            self.assertEqual(buf, BATTERY_7500[:4])
            self.assertEqual(uart.readinto(buf, 1), 1)
            self.assertEqual(uart.readinto(buf), 1)
            self.assertEqual(buf, bytes((0x1D, 0x55, 0x04, 0x0F)))  # still 4 long
            self.assertIsNone(uart.readinto(buf, 100))


class Board(unittest.TestCase):
    def test_busservo_board_falls_back_to_the_simulator_without_a_board_py(self):
        import busservo_board

        bus = busservo_board.bus()  # no board.py on the tests' path
        self.assertTrue(busservo_board.simulated)
        self.assertIsInstance(bus, busservo.BusServo)
        self.assertEqual(bus.read_battery(), 7500)


class Line(unittest.TestCase):
    # By default the simulator is at the far end of a 9600-baud line: 10 bits, 1.04 ms
    # a byte, each way. A reply comes no sooner than over a real wire.

    def setUp(self):
        self.clock = Clock()
        self.sim = SimController(ticks_ms=self.clock)

    def test_a_reply_comes_once_the_request_and_its_own_bytes_have_crossed(self):
        # 4 bytes in by 4.17 ms, then 6 back, a byte every 1.042 ms: by 5.21, 6.25, ...
        # 10.42 ms, each seen at the next whole ms.
        self.sim.write(BATTERY)
        got = []
        for _ in range(13):
            got.append(self.sim.any())
            self.clock.step(1)
        self.assertEqual(got, [0, 0, 0, 0, 0, 0, 1, 2, 3, 4, 5, 6, 6])
        self.assertEqual(self.sim.read(), BATTERY_7500)

    def test_what_it_says_queues_on_the_line(self):
        # The RUN is in by 7.29 ms and comes back by 14.58 (4 of its bytes by 11.46); the
        # battery's request is in by 11.46 ms, and its reply waits for the line: back by
        # 20.83 (5 of its bytes by 19.79).
        self.sim.write(RUN_8 + BATTERY)
        self.clock.step(12)
        self.assertEqual(self.sim.read(), RUN_8[:4])
        self.clock.step(3)
        self.assertEqual(self.sim.read(), RUN_8[4:])
        self.clock.step(5)
        self.assertEqual(self.sim.read(), BATTERY_7500[:5])
        self.clock.step(1)
        self.assertEqual(self.sim.read(), BATTERY_7500[5:])
        self.assertIsNone(self.sim.read())

    def test_the_line_runs_at_9600_baud_however_its_bytes_are_written(self):
        # 100 bytes a byte a write (as serve() writes what a pty brings), or in one write:
        # in by 104.17 ms either way, the reply to the last 4 back by 110.42. Each byte's
        # time was once rounded up to a whole ms (2 ms a byte a write: half the wire's pace).
        for chunk in (1, 100):
            clock = Clock()
            sim = SimController(ticks_ms=clock)
            data = bytes(96) + BATTERY
            for at in range(0, 100, chunk):
                sim.write(data[at : at + chunk])
            clock.step(110)
            self.assertEqual(sim.any(), 5, chunk)
            clock.step(1)
            self.assertEqual(sim.read(), BATTERY_7500, chunk)

    def test_a_request_behind_others_is_in_when_they_are(self):
        self.sim.write(bytes(96))  # 100 ms of bytes that make no frame
        self.sim.write(BATTERY)  # in by 104.2 ms, answered by 110.4
        self.clock.step(105)
        self.assertEqual(self.sim.any(), 0)
        self.clock.step(8)
        self.assertEqual(self.sim.read(), BATTERY_7500)

    def test_the_driver_reads_it_on_real_time(self):
        bus = busservo.BusServo(SimController())
        start = time.ticks_ms()
        self.assertEqual(bus.read_battery(), 7500)
        self.assertEqual(bus.read_positions([1, 2]), {1: 500, 2: 500})
        # No sooner than the wire allows: 10 bytes, then 7 + 11 bytes.
        self.assertTrue(time.ticks_diff(time.ticks_ms(), start) >= 28)

    def test_with_no_line_it_answers_at_once_and_the_driver_takes_it(self):
        # baudrate=None, as the header offers it: every byte at once.
        sim = SimController(baudrate=None)
        sim.write(BATTERY)
        self.assertEqual(sim.read(), BATTERY_7500)
        bus = busservo.BusServo(sim)
        self.assertEqual(bus.read_battery(), 7500)
        self.assertEqual(bus.read_positions([1, 2]), {1: 500, 2: 500})
        bus.request_positions([3])
        self.assertEqual((bus.poll(), bus.positions[3]), (busservo.CMD_MULT_SERVO_POS_READ, 500))
        self.assertEqual(bus.early, 3)


class Hands(unittest.TestCase):
    # SimController.turn(): a person's hand. It turns a limp servo, as a hand turns a servo
    # unloaded by CMD_MULT_SERVO_UNLOAD; a servo under power holds, and the call says so.

    def setUp(self):
        self.clock = Clock()
        self.sim = SimController(ticks_ms=self.clock, baudrate=None)
        self.bus = busservo.BusServo(self.sim)

    def test_a_limp_servo_goes_where_the_hand_puts_it(self):
        self.bus.unload([1, 2])  # 55 55 05 14 02 01 02
        self.assertTrue(self.sim.turn(1, 250))
        self.assertTrue(self.sim.turn(2, 1000))
        self.assertEqual(read_positions(self.sim, [1, 2]), {1: 250, 2: 1000})
        self.assertEqual(self.sim.limp, {1, 2})  # still limp: the hand let go
        self.assertTrue(self.sim.turn(1, 0))
        self.assertEqual(read_positions(self.sim, [1]), {1: 0})

    def test_a_servo_under_power_holds_and_the_call_says_so(self):
        self.assertFalse(self.sim.turn(1, 250))  # never unloaded: it holds 500
        self.bus.unload([2])
        self.bus.move(2, 800, 1000)  # a move gives it its torque back
        self.clock.step(500)
        self.assertFalse(self.sim.turn(2, 100))
        self.assertEqual(read_positions(self.sim, [1, 2]), {1: 500, 2: 650})
        self.clock.step(500)
        self.assertEqual(read_positions(self.sim, [2]), {2: 800})

    def test_a_move_after_the_hand_starts_from_where_it_left_the_servo(self):
        self.bus.unload([3])
        self.sim.turn(3, 100)
        self.bus.move(3, 500, 1000)
        self.clock.step(500)
        self.assertEqual(read_positions(self.sim, [3]), {3: 300})

    def test_no_hand_turns_a_servo_beyond_its_range(self):
        self.sim.pwm.add(6)
        self.bus.unload([1, 6])
        for servo_id, position in ((1, 1001), (1, -1), (1, 500.0), (6, 2501)):
            with self.assertRaises(ValueError):
                self.sim.turn(servo_id, position)
        self.assertTrue(self.sim.turn(6, 2500))  # a PWM servo's, in us
        self.assertEqual(read_positions(self.sim, [1, 6]), {1: 500, 6: 2500})


if __name__ == "__main__":
    unittest.main()
