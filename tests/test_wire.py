# The test world itself (tests/wire.py): the wire, the ports' UARTs and the
# faults do what MicroPython's ports and a 9600-baud line do. Driven by hand,
# with the protocol document's own frames; no driver involved.
import unittest

import wire

MOVE_1_TO_800 = bytes((0x55, 0x55, 0x08, 0x03, 0x01, 0xE8, 0x03, 0x01, 0x20, 0x03))
GET_BATTERY = bytes((0x55, 0x55, 0x02, 0x0F))
BATTERY_7500 = bytes((0x55, 0x55, 0x04, 0x0F, 0x4C, 0x1D))
BYTE_US = 1041.67  # 10 bits at 9600 baud


def wait_for(w, n, limit_ms=1000):
    """Step 0.1 ms at a time until the UART holds n bytes; the us it took."""
    start = w.clock.now_us
    while w.uart.any() < n and w.clock.now_us - start < limit_ms * 1000:
        w.clock.advance_us(100)
    return w.clock.now_us - start


class Clock(unittest.TestCase):
    def test_ticks_wrap_at_2_to_the_30_as_on_a_32_bit_port(self):
        clock = wire.World("rp2").clock
        before = clock.ticks_us()
        clock.advance_ms(1500)  # ticks_us wraps 1 s in
        after = clock.ticks_us()
        self.assertTrue(after < before)
        self.assertTrue(1500000 <= clock.ticks_diff(after, before) < 1500100)
        self.assertEqual(clock.ticks_add(clock.ticks_add(5, -10), 10), 5)
        self.assertEqual(clock.ticks_diff(0, (1 << 30) - 1), 1)
        with self.assertRaises(OverflowError):
            clock.ticks_add(0, 1 << 29)

    def test_reads_cost_time_so_busy_loops_move_on(self):
        clock = wire.World("rp2").clock
        start = clock.ticks_ms()
        spins = 0
        while clock.ticks_diff(clock.ticks_ms(), start) < 5:
            spins += 1
        self.assertTrue(4000 < spins < 6000)


class Wire(unittest.TestCase):
    def test_bytes_take_10_bits_each(self):
        for port in wire.PORTS:
            w = wire.World(port)
            self.assertEqual(w.uart.write(MOVE_1_TO_800), 10)
            w.clock.advance_us(int(9.9 * BYTE_US))
            self.assertEqual(w.frames(), [], port)  # 9 bytes have arrived
            w.clock.advance_us(int(0.2 * BYTE_US))
            self.assertEqual(w.frames(), [MOVE_1_TO_800], port)
            self.assertEqual(w.sim.position(1), 500, port)  # it has 1000 ms to get there

    def test_a_battery_round_trip_takes_about_10_4_ms(self):
        for port in wire.PORTS:
            w = wire.World(port)
            w.uart.write(GET_BATTERY)
            took = wait_for(w, 6)
            self.assertTrue(10 * BYTE_US <= took <= 12 * BYTE_US, (port, took))
            buf = bytearray(8)
            self.assertEqual(w.uart.readinto(buf), 6)
            self.assertEqual(bytes(buf[:6]), BATTERY_7500)

    def test_write_takes_the_stream_protocols_forms(self):
        for port in wire.PORTS:
            w = wire.World(port)
            frame = b"xx" + MOVE_1_TO_800 + b"yy"
            self.assertEqual(w.uart.write(frame, 2, 10), 10)
            self.assertEqual(w.uart.write(MOVE_1_TO_800 + b"zz", 10), 10)
            self.assertEqual(w.uart.write(MOVE_1_TO_800[:5]), 5)
            self.assertEqual(w.uart.write(MOVE_1_TO_800, 5, 100), 5)  # clamped to the buffer
            w.clock.advance_ms(40)
            self.assertEqual(w.frames(), [MOVE_1_TO_800] * 3, port)

    def test_readinto_is_clamped_to_its_buffer_and_gives_none_when_empty(self):
        for port in wire.PORTS:
            w = wire.World(port)
            buf = bytearray(3)
            self.assertIsNone(w.uart.readinto(buf))
            w.uart.write(GET_BATTERY)
            wait_for(w, 6)
            self.assertEqual(w.uart.readinto(buf, 100), 3)
            self.assertEqual(len(buf), 3)
            self.assertEqual(w.uart.read(), BATTERY_7500[3:])
            self.assertIsNone(w.uart.read())

    def test_rp2_write_returns_what_fit_or_none_when_its_ring_is_full(self):
        # 288 bytes of room (the ring, and the FIFO): then write() waits for room
        # until the millisecond turns (timeout=0), and if a byte leaves meanwhile,
        # goes on a byte at a time as room comes (timeout_char: 2 ms).
        w = wire.World("rp2")
        self.assertEqual(w.uart.write(bytes(288)), 288)
        short = 0
        for _ in range(40):
            start = w.clock.now_us
            took = w.uart.write(MOVE_1_TO_800)
            if took is None or took < 10:
                short += 1
                self.assertTrue(w.clock.now_us - start <= 1100)
            else:
                self.assertEqual(took, 10)
        self.assertTrue(5 < short < 35, short)
        w.clock.advance_ms(800)
        self.assertTrue(w.garbled >= 288)  # the zeros; the frames cut by short writes are
        self.assertTrue(len(w.frames()) >= 40 - short)  # garbled too, but none is lost

    def test_esp32_write_blocks_until_all_is_in_its_buffer(self):
        w = wire.World("esp32")
        for _ in range(5):
            self.assertEqual(w.uart.write(bytes(100)), 100)
        # 500 bytes, room for 384: it waited for about 116 bytes to leave.
        self.assertTrue(110 * BYTE_US < w.clock.now_us < 125 * BYTE_US, w.clock.now_us)

    def test_a_full_receive_side_drops_and_counts(self):
        for port in wire.PORTS:
            w = wire.World(port)
            w.noise(bytes(400))
            w.clock.advance_ms(450)
            self.assertEqual(w.uart.any() + w.uart.overrun, 400, port)
            self.assertTrue(w.uart.overrun > 0, port)

    def test_esp32_with_a_timeout_char_keeps_bytes_in_its_fifo(self):
        w = wire.World("esp32", timeout_char=10)
        w.noise(bytes(60))
        w.clock.advance_ms(50)
        self.assertEqual(w.uart.any(), 0)  # 48 arrived, all in the FIFO
        w.clock.advance_ms(30)
        self.assertEqual(w.uart.any(), 60)  # the line has been idle for 10 characters


class Faults(unittest.TestCase):
    def test_noise_goes_onto_the_line_at_the_baud_rate(self):
        w = wire.World("rp2")
        w.noise(b"\x55\x55\x05")
        self.assertEqual(w.uart.any(), 0)
        self.assertTrue(2 * BYTE_US < wait_for(w, 3) < 4 * BYTE_US)
        self.assertEqual(w.uart.read(), b"\x55\x55\x05")

    def test_drop_cut_and_late_replies(self):
        w = wire.World("rp2")
        w.drop(1, skip=2)
        w.uart.write(GET_BATTERY)
        wait_for(w, 5)
        w.clock.advance_ms(5)
        self.assertEqual(w.uart.read(), BATTERY_7500[:2] + BATTERY_7500[3:])
        w.cut_reply(4)
        w.uart.write(GET_BATTERY)
        w.clock.advance_ms(20)
        self.assertEqual(w.uart.read(), BATTERY_7500[:4])
        w.late(50)
        w.uart.write(GET_BATTERY)
        self.assertTrue(59000 < wait_for(w, 6) < 62000)

    def test_a_silent_controller(self):
        w = wire.World("rp2")
        w.sim.silent = True
        w.uart.write(GET_BATTERY)
        w.clock.advance_ms(100)
        self.assertEqual(w.uart.any(), 0)
        self.assertEqual(w.frames(), [GET_BATTERY])

    def test_a_failing_call_raises_and_consumes_nothing(self):
        w = wire.World("rp2")
        w.noise(b"\x01\x02")
        w.clock.advance_ms(3)
        w.uart.fail("readinto", OSError(5), skip=1)
        buf = bytearray(1)
        self.assertEqual(w.uart.readinto(buf), 1)
        with self.assertRaises(OSError):
            w.uart.readinto(buf)
        self.assertEqual(w.uart.readinto(buf), 1)
        self.assertEqual(buf[0], 2)

    def test_a_callback_runs_inside_a_call(self):
        w = wire.World("rp2")
        seen = []
        w.uart.during("any", lambda: seen.append(w.uart.any()), when="before")
        w.noise(b"\x01")
        w.clock.advance_ms(2)
        self.assertEqual(w.uart.any(), 1)
        self.assertEqual(seen, [1])

    def test_a_stalled_uart_sends_nothing_until_it_is_freed(self):
        for port in wire.PORTS:
            w = wire.World(port)
            w.uart.stall(True)
            w.uart.write(MOVE_1_TO_800)
            w.clock.advance_ms(50)
            self.assertEqual(w.received(), b"", port)
            w.uart.stall(False)
            w.clock.advance_ms(11)
            self.assertEqual(w.frames(), [MOVE_1_TO_800], port)

    def test_it_is_deterministic(self):
        def run():
            w = wire.World("rp2")
            for _ in range(30):
                w.uart.write(MOVE_1_TO_800)
                w.uart.write(GET_BATTERY)
            w.clock.advance_ms(900)
            return w.clock.now_us, w.received(), w.uart.read()

        self.assertEqual(run(), run())


if __name__ == "__main__":
    unittest.main()
