# The test world itself (tests/wire.py): the clock, the wire and the ports'
# UARTs do what MicroPython's ports and a 9600-baud line do, and each fault
# does what it says. Driven by hand with the protocol document's own frames;
# no driver involved.
import asyncio
import gc
import unittest

import wire

PERIOD = 1 << 30
HALF = PERIOD >> 1

MOVE_1_TO_800 = bytes((0x55, 0x55, 0x08, 0x03, 0x01, 0xE8, 0x03, 0x01, 0x20, 0x03))
GET_BATTERY = bytes((0x55, 0x55, 0x02, 0x0F))
BATTERY_7500 = bytes((0x55, 0x55, 0x04, 0x0F, 0x4C, 0x1D))
RUN_8_ONCE = bytes((0x55, 0x55, 0x05, 0x06, 0x08, 0x01, 0x00))
COMPLETE_8_ONCE = bytes((0x55, 0x55, 0x05, 0x08, 0x08, 0x01, 0x00))
STOP = bytes((0x55, 0x55, 0x02, 0x07))
UNLOAD_1_2_3 = bytes((0x55, 0x55, 0x06, 0x14, 0x03, 0x01, 0x02, 0x03))
READ_1_TO_6 = bytes((0x55, 0x55, 0x09, 0x15, 0x06, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06))
SIM_SILENT = bytes((0x55, 0x55, 0x03, 0xF0, 0x01))  # the simulator's own: no protocol frame


def wire_us(n):
    """When the n-th byte of a burst at 9600 baud has arrived, from its start."""
    return n * 10000000 // 9600


def world(port, **kw):
    """A world whose clock starts at 0, so that times are easy to read."""
    kw.setdefault("start", None)
    return wire.World(port, **kw)


class Clock(unittest.TestCase):
    def test_ticks_ms_wraps_3_s_in_and_ticks_us_1_s_in(self):
        clock = wire.World("rp2").clock
        self.assertEqual(clock.ticks_ms(), PERIOD - 3000)
        self.assertEqual(clock.ticks_us(), PERIOD - 1000000 + 1)  # the ms read cost 1 us
        clock.advance_ms(1000)
        self.assertEqual(clock.ticks_us(), 2)  # wrapped
        clock.advance_ms(2000)
        self.assertEqual(clock.ticks_ms(), 0)  # wrapped

    def test_start_none_or_where_asked(self):
        clock = wire.Clock(start=None)
        self.assertEqual((clock.ticks_ms(), clock.ticks_us()), (0, 1))
        clock = wire.Clock(start=(PERIOD - 1, 5))
        self.assertEqual((clock.ticks_ms(), clock.ticks_us()), (PERIOD - 1, 6))

    def test_ticks_diff_is_signed_modulo_2_to_the_30(self):
        clock = wire.Clock()
        self.assertEqual(clock.ticks_diff(5, PERIOD - 5), 10)
        self.assertEqual(clock.ticks_diff(PERIOD - 5, 5), -10)
        self.assertEqual(clock.ticks_diff(HALF - 1, 0), HALF - 1)
        self.assertEqual(clock.ticks_diff(HALF, 0), -HALF)  # half way is "before"

    def test_ticks_add_wraps_and_refuses_half_the_period(self):
        clock = wire.Clock()
        self.assertEqual(clock.ticks_add(PERIOD - 1, 2), 1)
        self.assertEqual(clock.ticks_add(0, -1), PERIOD - 1)
        for delta in (1, -1, 1000, HALF - 1, -(HALF - 1)):
            t = clock.ticks_add(PERIOD - 3, delta)
            self.assertEqual(clock.ticks_diff(t, PERIOD - 3), delta)
        # extmod/modtime.c: so that ticks_diff(ticks_add(T, d), T) == d, always.
        for delta in (HALF, -HALF, PERIOD):
            with self.assertRaises(OverflowError):
                clock.ticks_add(0, delta)
        with self.assertRaises(TypeError):
            clock.ticks_add(0, 1.5)

    def test_each_ticks_read_costs_cost_us_so_busy_loops_move_on(self):
        clock = wire.Clock(start=None, cost_us=3)
        self.assertEqual(clock.ticks_us() - clock.ticks_us(), -3)
        clock = wire.Clock()
        start = clock.ticks_ms()
        spins = 0
        while clock.ticks_diff(clock.ticks_ms(), start) < 5:
            spins += 1
        self.assertTrue(4990 <= spins <= 5000, spins)

    def test_sleeps_as_micropython_does(self):
        clock = wire.Clock()
        clock.sleep_ms(-5)  # extmod/modtime.c: a negative sleep does nothing
        clock.sleep_us(0)
        clock.sleep_us(-1)
        self.assertEqual(clock.now_us, 0)
        clock.sleep_ms(2)
        clock.sleep_us(7)
        clock.advance_us(3)
        self.assertEqual(clock.now_us, 2010)

    def test_a_uart_call_costs_call_us(self):
        for port in wire.PORTS:
            w = world(port, call_us=7)
            w.uart.any()
            w.uart.any()
            self.assertEqual(w.clock.now_us, 14, port)
            w = world(port, call_us=0)
            w.uart.any()
            self.assertEqual(w.clock.now_us, 0, port)


class Wire(unittest.TestCase):
    def test_bytes_take_10_bits_each(self):
        for port in wire.PORTS:
            w = world(port)
            self.assertEqual(w.uart.write(MOVE_1_TO_800), 10)  # at 5 us: the call's cost
            w.run_ms(20)
            self.assertEqual(w.sent_at, [5 + wire_us(i) for i in range(1, 11)], port)
            self.assertEqual(w.sent_at[-1] - 5, 10416, port)  # 10.4 ms to the controller

    def test_the_controller_has_a_frame_when_its_last_bit_is_in(self):
        for port in wire.PORTS:
            w = world(port)
            w.uart.write(MOVE_1_TO_800)
            w.clock.now_us = 5 + wire_us(10) - 1
            self.assertEqual(w.frames(), [], port)
            self.assertEqual(w.received(), MOVE_1_TO_800[:9], port)
            w.clock.advance_us(1)
            self.assertEqual(w.frames(), [MOVE_1_TO_800], port)
            self.assertEqual(w.sim.position(1), 500, port)  # it has 1000 ms to get there
            w.run_ms(1000)
            self.assertEqual(w.sim.position(1), 800, port)

    def test_a_battery_round_trip_takes_10_4_ms(self):
        for port in wire.PORTS:
            w = world(port)
            w.uart.write(GET_BATTERY)
            # The reply starts as the request's last bit is in: 4 bytes, then 6.
            while w.uart.any() < 6:
                w.clock.advance_us(100)
            self.assertEqual(w.arrived[-1][0], 5 + wire_us(4) + wire_us(6), port)
            self.assertTrue(10416 <= w.clock.now_us - 5 < 10416 + 110, port)
            self.assertEqual(w.uart.read(6), BATTERY_7500, port)

    def test_esp32_sees_a_lone_last_byte_one_character_later(self):
        # RUN comes back as it went: 7 bytes. esp32's RX interrupt comes when its
        # FIFO holds more than 1 byte, or after 1 character of quiet line.
        last = 2 * wire_us(7)
        for port, seen in (("rp2", 7), ("esp32", 6)):
            w = world(port, call_us=0)
            w.uart.write(RUN_8_ONCE)
            w.clock.now_us = last - 1
            self.assertEqual(w.uart.any(), 6, port)
            w.clock.now_us = last
            self.assertEqual(w.uart.any(), seen, port)
            w.clock.now_us = last + wire_us(1)
            self.assertEqual(w.uart.any(), 7, port)
            self.assertEqual(w.uart.read(7), RUN_8_ONCE, port)

    def test_esp32_with_a_timeout_char_sees_bytes_by_120_or_after_a_quiet_line(self):
        # timeout_char=10 at 9600: rx timeout 10 // 2 = 5 characters, and the
        # rx-full threshold stays at ESP-IDF's 120.
        w = world("esp32", call_us=0, timeout_char=10)
        w.noise(bytes(130))
        w.clock.now_us = wire_us(121) - 1
        self.assertEqual(w.uart.any(), 0)
        w.clock.now_us = wire_us(121)
        self.assertEqual(w.uart.any(), 121)
        w.clock.now_us = wire_us(130) + wire_us(5) - 1
        self.assertEqual(w.uart.any(), 121)
        w.clock.advance_us(1)
        self.assertEqual(w.uart.any(), 130)

    def test_complete_comes_when_the_group_ends(self):
        for port in wire.PORTS:
            w = world(port)
            w.uart.write(RUN_8_ONCE)  # group 8: 1500 ms; in at 7.296 ms
            w.run_ms(1600)
            self.assertEqual(w.uart.read(), RUN_8_ONCE + COMPLETE_8_ONCE, port)
            # It ends 1500 ms after ms 7; the controller says so at once.
            self.assertEqual(w.arrived[7][0], 1507000 + wire_us(1), port)

    def test_a_direct_word_to_the_controller_is_answered_on_the_wire(self):
        for port in wire.PORTS:
            w = world(port)
            w.sim.write(GET_BATTERY)  # not over the wire: the answer still is
            w.run_ms(10)
            self.assertEqual(w.uart.read(), BATTERY_7500, port)
            self.assertEqual(w.received(), b"", port)


class Writing(unittest.TestCase):
    def test_rp2_write_returns_what_fit_after_its_wait_then_none(self):
        w = world("rp2")
        w.uart.stall(True)
        # 256 in the ring and 32 in the FIFO; then a wait for room of
        # timeout_char (2 ms at 9600: until the ms counter has moved past 2).
        self.assertEqual(w.uart.write(bytes(300)), 288)
        self.assertEqual(w.clock.now_us, 3000)
        # Now nothing fits, and timeout is 0: until the ms counter moves.
        self.assertIsNone(w.uart.write(bytes(10)))
        self.assertEqual(w.clock.now_us, 4000)
        self.assertEqual(w.received(), b"")
        self.assertIsNone(w.tx_backlog_us())
        w.uart.stall(False)
        w.run_ms(310)
        self.assertEqual(w.received(), bytes(288))

    def test_rp2_write_then_takes_what_the_fifo_gave_up(self):
        w = world("rp2")
        # The ring, the FIFO and the byte on the wire; then 2 ms and a bit.
        self.assertEqual(w.uart.write(bytes(400)), 289)
        self.assertEqual(w.clock.now_us, 3000)
        # Ring room comes when the FIFO is refilled: by the next write, which
        # finds 2 bytes gone from it, or by the TX interrupt at 4 bytes left.
        self.assertEqual(w.uart.write(bytes(111)), 2)
        self.assertEqual(w.clock.now_us, 6000)

    def test_rp2_tx_interrupt_refills_the_fifo_at_4_bytes(self):
        w = world("rp2", call_us=0)
        w.uart.write(bytes(289))  # all in: ring full, FIFO full, one on the wire
        ring = w.uart._tx_ring
        w.clock.now_us = wire_us(28) - 1
        w.sync()
        self.assertEqual(ring.n, 256)  # 28 bytes gone, the FIFO down to 5
        w.clock.now_us = wire_us(28)
        w.sync()
        self.assertEqual(ring.n, 256 - 28)  # down to 4: refilled to 32

    def test_esp32_write_blocks_until_all_is_in_its_buffer(self):
        w = world("esp32")
        self.assertEqual(w.uart.write(MOVE_1_TO_800), 10)
        self.assertEqual(w.clock.now_us, 5)  # room: no wait
        w.run_ms(20)
        start = w.clock.now_us
        self.assertEqual(w.uart.write(bytes(600)), 600)
        took = w.clock.now_us - start
        left = w.tx_backlog_us()
        # It returned when its last chunk found room: what the wire has not
        # taken yet is in the ring, the FIFO and the transmitter.
        self.assertEqual(len(w.received()) - 10 + w.uart._tx_pending() + 1, 600)
        self.assertTrue(wire_us(600 - 256 - 128 - 1) <= took < wire_us(600), took)
        self.assertTrue(abs(took + left - wire_us(600)) < 2000, (took, left))

    def test_a_stalled_esp32_write_blocks_hang_ms_then_returns_what_it_put(self):
        w = world("esp32")
        w.uart.stall(True)
        got = w.uart.write(bytes(600))
        self.assertTrue(0 < got < 600, got)
        self.assertEqual(w.clock.now_us, 5 + 1000000)
        w = world("esp32", hang="raise", hang_ms=50)
        w.uart.stall(True)
        with self.assertRaises(wire.Hang):
            w.uart.write(bytes(600))
        self.assertEqual(w.clock.now_us, 5 + 50000)

    def test_write_takes_the_stream_protocols_forms(self):
        for port in wire.PORTS:
            w = world(port)
            uart = w.uart
            self.assertEqual(uart.write(b"xx" + MOVE_1_TO_800 + b"yy", 2, 10), 10)
            self.assertEqual(uart.write(MOVE_1_TO_800 + b"zz", 10), 10)
            self.assertEqual(uart.write(MOVE_1_TO_800[:5]), 5)
            self.assertEqual(uart.write(MOVE_1_TO_800, 5, 100), 5)  # n clamped to the rest
            self.assertEqual(uart.write(bytearray(MOVE_1_TO_800), -1), 10)  # size_t: no limit
            self.assertEqual(uart.write(memoryview(MOVE_1_TO_800)), 10)
            self.assertEqual(uart.write(b"abc", 5, 1), 0)  # off clamped to the end
            self.assertEqual(uart.write(b"abc", -1, 1), 0)  # size_t: past the end
            self.assertEqual(uart.write(b""), 0)
            w.run_ms(60)
            self.assertEqual(w.frames(), [MOVE_1_TO_800] * 5, port)
            self.assertEqual(w.garbled, 0, port)

    def test_tx_backlog_counts_10_bits_a_byte(self):
        for port in wire.PORTS:
            w = world(port)
            self.assertEqual(w.tx_backlog_us(), 0, port)
            w.uart.write(MOVE_1_TO_800)
            self.assertEqual(w.tx_backlog_us(), wire_us(10), port)
            w.clock.advance_us(3000)
            self.assertEqual(w.tx_backlog_us(), wire_us(10) - 3000, port)
            w.run_ms(8)
            self.assertEqual(w.tx_backlog_us(), 0, port)

    def test_flush_waits_for_the_wire_or_times_out(self):
        w = world("rp2")
        w.uart.write(MOVE_1_TO_800)
        w.uart.flush()
        self.assertEqual(w.clock.now_us, 5 + wire_us(10))
        self.assertTrue(w.uart.txdone())
        w.uart.write(MOVE_1_TO_800)
        w.uart.stall(True)
        with self.assertRaises(OSError):
            w.uart.flush()  # rp2: (33 + 257) * 13 bit times * 2
        self.assertTrue(w.clock.now_us > 785000)


class Reading(unittest.TestCase):
    def test_readinto_is_clamped_to_its_buffer_and_gives_none_when_empty(self):
        for port in wire.PORTS:
            w = world(port)
            buf = bytearray(4)
            self.assertIsNone(w.uart.readinto(buf))
            # rp2 waits for a byte until its ms counter moves (timeout=0); esp32 not.
            self.assertEqual(w.clock.now_us, 1000 if port == "rp2" else 5, port)
            self.assertEqual(w.uart.readinto(buf, 0), 0)
            w.uart.write(GET_BATTERY)
            w.run_ms(20)
            self.assertEqual(w.uart.readinto(buf, 10), 4, port)
            self.assertEqual(bytes(buf), BATTERY_7500[:4], port)
            self.assertEqual(w.uart.readinto(buf, -1), 2, port)  # size_t: no limit
            self.assertEqual(bytes(buf[:2]), BATTERY_7500[4:], port)
            self.assertIsNone(w.uart.readinto(buf), port)
            with self.assertRaises(TypeError):
                w.uart.readinto(b"1234")  # no room to write

    def test_read_takes_its_forms(self):
        for port in wire.PORTS:
            w = world(port)
            self.assertEqual(w.uart.read(0), b"")
            self.assertIsNone(w.uart.read())
            self.assertIsNone(w.uart.read(3))
            w.uart.write(GET_BATTERY)
            w.run_ms(20)
            self.assertEqual(w.uart.read(3), BATTERY_7500[:3], port)
            self.assertEqual(w.uart.read(), BATTERY_7500[3:], port)

    def test_rp2_timeout_bounds_the_wait_for_the_first_byte(self):
        w = world("rp2", timeout=50)
        self.assertIsNone(w.uart.read(1))
        self.assertEqual(w.clock.now_us, 51000)  # until the ms counter is past 50
        w.uart.write(GET_BATTERY)  # at 51005; the reply's first byte 5 bytes later
        self.assertEqual(w.uart.read(1), BATTERY_7500[:1])
        self.assertEqual(w.clock.now_us, 51005 + wire_us(4) + wire_us(1))

    def test_rp2_read_waits_timeout_char_for_each_further_byte(self):
        w = world("rp2")
        w.uart.write(GET_BATTERY)
        w.clock.now_us = 5300  # the reply's first byte is in (5212)
        buf = bytearray(64)
        self.assertEqual(w.uart.readinto(buf), 6)
        self.assertEqual(bytes(buf[:6]), BATTERY_7500)
        # Each byte came within 2 ms of the one before; after the last (10421),
        # until the ms counter has moved past 2 more.
        self.assertEqual(w.clock.now_us, 13000)

    def test_esp32_read_takes_what_is_in_its_buffer_and_waits_not(self):
        w = world("esp32")
        w.uart.write(GET_BATTERY)
        w.clock.now_us = 5300  # the reply's first byte is in its FIFO, alone
        buf = bytearray(64)
        self.assertIsNone(w.uart.readinto(buf))
        w.clock.now_us = 7300  # two more in: the first two in the buffer
        self.assertEqual(w.uart.readinto(buf), 2)
        self.assertEqual(w.clock.now_us, 7305)

    def test_rp2_keeps_288_bytes_and_loses_the_newest(self):
        w = world("rp2")
        data = bytes(i & 0xFF for i in range(300))
        w.noise(data)
        w.run_ms(330)
        self.assertEqual(w.uart.any(), 256)  # the FIFO's 32 are not counted
        self.assertEqual(w.overrun, 12)
        self.assertEqual(w.uart.read(400), data[:288])

    def test_esp32_overflow_loses_the_whole_fifo(self):
        w = world("esp32")
        data = bytes(i & 0xFF for i in range(500))
        w.noise(data)
        w.run_ms(530)
        # The buffer took 256; 2 more wait aside; the FIFO filled with 128 and
        # was reset when the 129th came; the last 113 are in the FIFO.
        self.assertEqual(w.uart.any(), 256)
        self.assertEqual(w.overrun, 129)
        self.assertEqual(w.uart.read(600), data[:258] + data[387:])


class Faults(unittest.TestCase):
    def test_noise_goes_onto_the_line_next_at_the_baud_rate(self):
        for port in wire.PORTS:
            w = world(port)
            w.noise(b"\xaa\xbb")
            w.run_ms(5)
            self.assertEqual(w.arrived, [(wire_us(1), 0xAA), (wire_us(2), 0xBB)], port)
            w.uart.read()
            w.uart.write(GET_BATTERY)
            w.clock.advance_us(wire_us(4) + 500)  # the reply's first byte is on the line
            w.noise(b"\xee")
            w.noise(b"\xff")  # behind the noise before it
            w.run_ms(20)
            got = w.uart.read()
            self.assertEqual(got, BATTERY_7500[:1] + b"\xee\xff" + BATTERY_7500[1:], port)

    def test_drop_skips_then_loses(self):
        for port in wire.PORTS:
            w = world(port)
            w.drop(2, skip=1)
            for _ in range(2):
                w.uart.write(GET_BATTERY)
                w.run_ms(20)
            self.assertEqual(w.uart.read(), BATTERY_7500[:1] + BATTERY_7500[3:] + BATTERY_7500)

    def test_cut_reply_keeps_the_first_bytes_of_the_next_frame_only(self):
        for port in wire.PORTS:
            w = world(port)
            w.cut_reply(4)
            for _ in range(2):
                w.uart.write(GET_BATTERY)
                w.run_ms(20)
            self.assertEqual(w.uart.read(), BATTERY_7500[:4] + BATTERY_7500, port)

    def test_late_delays_the_next_replies(self):
        for port in wire.PORTS:
            w = world(port, call_us=0)
            w.late(50, count=2)
            took = []
            for _ in range(3):
                start = w.clock.now_us
                w.uart.write(GET_BATTERY)
                w.run_ms(80)
                took.append(w.arrived[-1][0] - start)
                self.assertEqual(w.uart.read(), BATTERY_7500, port)
            round_trip = wire_us(4) + wire_us(6)
            self.assertEqual(took, [round_trip + 50000] * 2 + [round_trip], port)

    def test_a_silent_controller_says_nothing(self):
        for port in wire.PORTS:
            w = world(port)
            w.sim.silent = True
            w.uart.write(GET_BATTERY)
            w.run_ms(50)
            self.assertEqual(w.uart.any(), 0, port)
            self.assertEqual(w.frames(), [GET_BATTERY], port)

    def test_fail_raises_on_the_chosen_calls_and_takes_nothing(self):
        for port in wire.PORTS:
            w = world(port)
            w.uart.write(GET_BATTERY)
            w.run_ms(20)
            buf = bytearray(2)
            w.uart.fail("readinto", OSError(5), skip=1, times=2)
            self.assertEqual(w.uart.readinto(buf), 2)
            for _ in range(2):
                with self.assertRaises(OSError):
                    w.uart.readinto(buf)
            self.assertEqual(w.uart.readinto(buf), 2)  # nothing was lost
            self.assertEqual(bytes(buf), BATTERY_7500[2:4], port)
            w.uart.fail("write", KeyboardInterrupt)
            with self.assertRaises(KeyboardInterrupt):
                w.uart.write(STOP)
            w.uart.fail("any", OSError(5))
            with self.assertRaises(OSError):
                w.uart.any()
            self.assertEqual(w.uart.any(), 2)
            w.run_ms(10)
            self.assertEqual(w.frames(), [GET_BATTERY], port)  # the failed write sent nothing

    def test_during_runs_a_callback_inside_the_call(self):
        for port in wire.PORTS:
            w = world(port)
            w.uart.write(GET_BATTERY)
            # A 20 ms timer callback, before any() counts: the reply is in by then.
            w.uart.during("any", lambda w=w: w.clock.sleep_ms(20))
            self.assertEqual(w.uart.any(), 6, port)
            w.uart.read()
            w.uart.write(GET_BATTERY)
            # The same after it has counted; the second call of any() this time.
            w.uart.during("any", lambda w=w: w.clock.sleep_ms(20), "after", skip=1)
            self.assertEqual((w.uart.any(), w.uart.any(), w.uart.any()), (0, 0, 6), port)
            # A soft IRQ that reads the first 2 bytes inside the driver's read.
            got = []
            w.uart.during("readinto", lambda w=w, got=got: got.append(w.uart.read(2)))
            buf = bytearray(6)
            self.assertEqual(w.uart.readinto(buf, 4), 4, port)
            self.assertEqual((got[0], bytes(buf[:4])), (BATTERY_7500[:2], BATTERY_7500[2:]))

    def test_a_stalled_transmitter_sends_nothing_more(self):
        for port in wire.PORTS:
            w = world(port)
            w.uart.write(MOVE_1_TO_800)
            w.uart.stall(True)  # the first byte is on the wire: it arrives
            w.run_ms(50)
            self.assertEqual(w.received(), MOVE_1_TO_800[:1], port)
            self.assertIsNone(w.tx_backlog_us(), port)
            w.uart.stall(False)
            w.run_ms(10)
            self.assertEqual(w.frames(), [MOVE_1_TO_800], port)


class Observations(unittest.TestCase):
    def test_frames_are_parsed_strictly_by_the_protocols_lengths(self):
        for port in wire.PORTS:
            w = world(port)
            w.uart.write(b"\x00\x55" + MOVE_1_TO_800 + SIM_SILENT + UNLOAD_1_2_3)
            w.uart.write(READ_1_TO_6 + STOP + RUN_8_ONCE[:3])
            w.run_ms(60)
            want = [MOVE_1_TO_800, UNLOAD_1_2_3, READ_1_TO_6, STOP]
            self.assertEqual(w.frames(), want, port)
            self.assertEqual(w.garbled, 7, port)
            self.assertEqual(w.garbage(), b"\x00\x55" + SIM_SILENT, port)
        # A frame still arriving is neither a frame nor garbage.
        self.assertEqual(wire.parse(STOP + b"\x55\x55\x05"), ([STOP], b"", b"\x55\x55\x05"))
        self.assertEqual(wire.parse(b"\x55\x55\x05\x07"), ([], b"\x55\x55\x05\x07", b""))

    def test_arrivals_say_when_each_frames_last_byte_was_in(self):
        for port in wire.PORTS:
            w = world(port)
            w.uart.write(b"\x00" + MOVE_1_TO_800 + STOP[:3])  # noise, a frame, a cut one
            w.run_ms(40)
            w.uart.write(STOP)  # at 40.010 ms (each write costs 5 us), on an idle line
            w.run_ms(20)
            # The noise byte first: the move's last byte is the 11th of the burst.
            want = [(5 + wire_us(11), MOVE_1_TO_800), (40010 + wire_us(4), STOP)]
            self.assertEqual(w.arrivals(), want, port)
            self.assertEqual([f for _, f in w.arrivals()], w.frames(), port)
        ends = []
        self.assertEqual(wire.parse(b"\x00" + STOP + STOP, ends)[0], [STOP, STOP])
        self.assertEqual(ends, [5, 9])

    def test_the_same_run_gives_the_same_bytes_at_the_same_times(self):
        def run(port):
            w = wire.World(port)  # ticks that wrap, calls that cost
            w.drop(1, skip=3)
            w.late(7)
            w.noise(b"\x55\x01")
            w.uart.during("readinto", lambda: w.clock.sleep_us(333), skip=2)
            reads = []
            for i in range(30):
                w.uart.write(GET_BATTERY if i % 3 else RUN_8_ONCE)
                for _ in range(8):
                    w.clock.advance_us(700 + 37 * i)
                    n = w.uart.any()
                    if n:
                        buf = bytearray(n)
                        reads.append((w.clock.ticks_us(), w.uart.readinto(buf), bytes(buf)))
            return w.received(), w.arrived, reads, w.clock.now_us, w.uart.overrun

        for port in wire.PORTS:
            self.assertEqual(run(port), run(port), port)

    def test_async_sleep_ms_moves_the_clock_and_lets_others_run(self):
        w = world("rp2")
        ran = []

        async def other():
            ran.append(w.clock.now_us)

        async def main():
            task = asyncio.create_task(other())
            w.uart.write(GET_BATTERY)
            while w.uart.any() < 6:
                await w.async_sleep_ms(1)
            await task
            return w.clock.now_us

        # The reply is in at 10.421 ms: the first look after that sees it.
        self.assertTrue(10421 < asyncio.run(main()) < 11100)
        self.assertEqual(ran, [1010])  # in the first sleep: write, any(), then 1 ms
        self.assertEqual(w.uart.read(6), BATTERY_7500)


class Keeping(unittest.TestCase):
    # What the world keeps is bounded, so that it can run for days (test_soak.py).

    def test_it_keeps_the_last_frames_and_bytes_and_counts_them_all(self):
        for port in wire.PORTS:
            w = world(port, keep=3)
            for _ in range(5):
                w.uart.write(b"\x00" + GET_BATTERY)  # a byte of noise, then a frame
                w.run_ms(10)
            w.run_ms(10)  # the last reply too
            self.assertEqual(w.frames_total, 5, port)
            self.assertEqual(w.frames(), [GET_BATTERY] * 3, port)
            self.assertEqual(w.frames(3), [GET_BATTERY] * 2, port)  # from the 4th on
            self.assertEqual(w.frames(5), [], port)
            self.assertEqual([f for _, f in w.arrivals()], w.frames(), port)
            self.assertEqual(w.arrivals(4), [(40025 + wire_us(5), GET_BATTERY)], port)  # 5th write
            self.assertEqual((w.garbled, w.garbage()), (5, bytes(5)), port)
            self.assertEqual(w.received_total, 25, port)
            self.assertEqual(w.arrived_total, 30, port)  # the five replies
            w = world(port, keep=2000)
            for _ in range(1700):  # 17000 bytes: more than it keeps of them
                w.uart.write(MOVE_1_TO_800)
                w.run_ms(11)
            self.assertEqual(w.received_total, 17000, port)
            self.assertEqual(wire.KEEP_BYTES, 16384)
            self.assertEqual(w.received(), MOVE_1_TO_800[6:] + MOVE_1_TO_800 * 1638, port)
            self.assertEqual(len(w.sent_at), wire.KEEP_LOG, port)
            self.assertEqual(w.sent_at[-1], w.arrivals()[-1][0], port)
            self.assertEqual(w.frames_total, 1700, port)
            self.assertEqual(w.frames(), [MOVE_1_TO_800] * 1638, port)  # whose bytes it has

    def test_frames_are_parsed_as_the_bytes_come_as_parse_has_them(self):
        # Noise, frames, frames cut short and frames' starts mixed, a byte at a time.
        pieces = (b"\x55", b"\x55\x55", b"\x00", STOP, MOVE_1_TO_800, STOP[:3], UNLOAD_1_2_3)
        pieces += (READ_1_TO_6, SIM_SILENT, b"\x55\x55\x55\x05", RUN_8_ONCE, RUN_8_ONCE[:5])
        data = bytearray()
        seed = 7
        for _ in range(400):
            seed = (seed * 1103515245 + 12345) & 0x7FFFFFFF
            data += pieces[seed % len(pieces)]
        w = world("rp2", keep=100)
        seen = []
        w.on_frame = lambda us, frame: seen.append((us, frame))
        w.sim.silent = True  # its replies have nothing to do here
        for i in range(0, len(data), 200):
            w.uart.write(data[i : i + 200])
            w.run_ms(220)
        frames, garbage, rest = wire.parse(data)
        self.assertTrue(len(frames) > 150 and len(garbage) > 500, (len(frames), len(garbage)))
        self.assertEqual(w.frames_total, len(frames))
        self.assertEqual(w.frames(), frames[-100:])
        self.assertEqual((w.garbled, w.garbage()), (len(garbage), garbage[-wire.KEEP_LOG :]))
        self.assertEqual(w.rest(), rest)
        self.assertEqual(seen[-100:], w.arrivals())

    def test_what_it_keeps_does_not_grow_with_traffic(self):
        # A minute of queries and moves, then another: the heap is where it was.
        for port in wire.PORTS:
            w = world(port)
            for minute in range(2):
                for _ in range(600):
                    w.uart.write(GET_BATTERY)
                    w.uart.write(MOVE_1_TO_800)
                    w.run_ms(100)
                    w.uart.read()
                gc.collect()
                if minute == 0:
                    before = gc.mem_alloc()
            grew = gc.mem_alloc() - before
            self.assertTrue(grew < 1024, (port, grew))


if __name__ == "__main__":
    unittest.main()
