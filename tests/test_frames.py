# What the driver makes of the frames the controller sends (section II of
# the protocol document, and the replies of section I), however they arrive.
import unittest

import busservo
from busservo import (
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_RUN,
    CMD_ACTION_GROUP_STOP,
    CMD_GET_BATTERY_VOLTAGE,
    CMD_MULT_SERVO_POS_READ,
)
from fakeuart import FakeUART

# The document's own examples.
RUN_8_ONCE = bytes((0x55, 0x55, 0x05, 0x06, 0x08, 0x01, 0x00))
STOP = bytes((0x55, 0x55, 0x02, 0x07))
COMPLETE_8_ONCE = bytes((0x55, 0x55, 0x05, 0x08, 0x08, 0x01, 0x00))
BATTERY_7500 = bytes((0x55, 0x55, 0x04, 0x0F, 0x4C, 0x1D))
POSITIONS_ALL_500 = bytes(
    (0x55, 0x55, 0x15, 0x15, 0x06)
    + (0x01, 0xF4, 0x01, 0x02, 0xF4, 0x01, 0x03, 0xF4, 0x01)
    + (0x04, 0xF4, 0x01, 0x05, 0xF4, 0x01, 0x06, 0xF4, 0x01)
)
ALL_500 = {1: 500, 2: 500, 3: 500, 4: 500, 5: 500, 6: 500}
POSITIONS_1_500 = bytes((0x55, 0x55, 0x06, 0x15, 0x01, 0x01, 0xF4, 0x01))

# Made by the same rules: group 2 forever, and the longest frame there is
# (Length 255): 84 servo positions, servo i at 1000 + i.
RUN_2_FOREVER = bytes((0x55, 0x55, 0x05, 0x06, 0x02, 0x00, 0x00))
POSITIONS_84 = bytearray((0x55, 0x55, 255, 0x15, 84))
for i in range(84):
    POSITIONS_84 += bytes((i, (1000 + i) & 0xFF, (1000 + i) >> 8))
POSITIONS_84 = bytes(POSITIONS_84)
UNKNOWN_255 = bytes((0x55, 0x55, 255, 0x63)) + bytes(range(1, 254))

# (frame, its command, the state it leaves behind a fresh BusServo)
FRAMES = (
    (RUN_8_ONCE, CMD_ACTION_GROUP_RUN, {"running": True, "group": 8, "times": 1}),
    (RUN_2_FOREVER, CMD_ACTION_GROUP_RUN, {"running": True, "group": 2, "times": 0}),
    (STOP, CMD_ACTION_GROUP_STOP, {"running": False, "group": None}),
    (COMPLETE_8_ONCE, CMD_ACTION_GROUP_COMPLETE, {"running": False, "group": 8, "times": 1}),
    (BATTERY_7500, CMD_GET_BATTERY_VOLTAGE, {"battery": 7500}),
    (POSITIONS_ALL_500, CMD_MULT_SERVO_POS_READ, {"positions": ALL_500}),
    (POSITIONS_84, CMD_MULT_SERVO_POS_READ, {"positions": {i: 1000 + i for i in range(84)}}),
)


def fresh(chunks=None, frames=()):
    """A fake UART and a BusServo on it, which has asked for the positions each
    positions reply among frames carries (the controller sends none unasked)."""
    uart = FakeUART(chunks)
    bus = busservo.BusServo(uart)
    for frame in frames:
        if frame[3] == CMD_MULT_SERVO_POS_READ:
            bus.request_positions([frame[5 + 3 * i] for i in range(frame[4])])
    uart.clear()
    return uart, bus


def drain(bus):
    cmds = []
    while True:
        cmd = bus.poll()
        if cmd is None:
            return cmds
        cmds.append(cmd)


class Frames(unittest.TestCase):
    def assertState(self, bus, state, why=""):
        for name, value in state.items():
            self.assertEqual(getattr(bus, name), value, "%s %s" % (name, why))

    def test_each_frame_is_decoded_and_applied(self):
        for frame, cmd, state in FRAMES:
            uart, bus = fresh(frames=[frame])
            self.assertIsNone(bus.poll())
            uart.feed(frame)
            self.assertEqual(bus.poll(), cmd)
            self.assertState(bus, state)
            self.assertIsNone(bus.poll())

    def test_initial_state(self):
        uart, bus = fresh()
        self.assertState(
            bus, {"running": False, "group": None, "times": 0, "battery": None, "positions": {}}
        )

    def test_each_frame_split_at_every_byte(self):
        for frame, cmd, state in FRAMES:
            for cut in range(1, len(frame)):
                uart, bus = fresh(frames=[frame])
                uart.feed(frame[:cut])
                self.assertIsNone(bus.poll(), "cut at %d" % cut)
                self.assertEqual(bus.running, False)
                uart.feed(frame[cut:])
                self.assertEqual(bus.poll(), cmd, "cut at %d" % cut)
                self.assertState(bus, state, "cut at %d" % cut)
                self.assertIsNone(bus.poll())

    def test_each_frame_read_in_chunks_of_every_size(self):
        # poll() reads all the UART holds before it gives up, however it comes.
        for frame, cmd, state in FRAMES:
            for size in (1, 2, 3, 5, 7, 63, 64, 100):
                uart, bus = fresh([size], [frame])
                uart.feed(frame)
                self.assertEqual(bus.poll(), cmd, "chunks of %d" % size)
                self.assertState(bus, state)
                self.assertIsNone(bus.poll())

    def test_many_frames_in_one_read_one_per_poll(self):
        uart, bus = fresh()
        uart.feed(RUN_8_ONCE + BATTERY_7500 + COMPLETE_8_ONCE + RUN_2_FOREVER + STOP)
        # The state is that of the frame just returned, not of the last one read.
        self.assertEqual(bus.poll(), CMD_ACTION_GROUP_RUN)
        self.assertState(bus, {"running": True, "group": 8, "battery": None})
        self.assertEqual(bus.poll(), CMD_GET_BATTERY_VOLTAGE)
        self.assertState(bus, {"running": True, "battery": 7500})
        self.assertEqual(bus.poll(), CMD_ACTION_GROUP_COMPLETE)
        self.assertState(bus, {"running": False, "group": 8, "times": 1})
        self.assertEqual(bus.poll(), CMD_ACTION_GROUP_RUN)
        self.assertState(bus, {"running": True, "group": 2, "times": 0})
        self.assertEqual(bus.poll(), CMD_ACTION_GROUP_STOP)
        self.assertState(bus, {"running": False, "group": 2, "times": 0})
        self.assertIsNone(bus.poll())

    def test_a_stream_of_every_frame_split_anywhere(self):
        stream = b"".join(f[0] for f in FRAMES)
        expect = [f[1] for f in FRAMES]
        for cut in range(0, len(stream), 7):
            for size in (1, 4, 63):
                uart, bus = fresh([size], [f[0] for f in FRAMES])
                uart.feed(stream[:cut])
                got = drain(bus)
                uart.feed(stream[cut:])
                got += drain(bus)
                self.assertEqual(got, expect, "cut at %d, chunks of %d" % (cut, size))
        self.assertEqual(bus.positions[83], 1083)

    def test_state_changes(self):
        uart, bus = fresh()
        for frame, running, group, times in (
            (RUN_8_ONCE, True, 8, 1),
            (COMPLETE_8_ONCE, False, 8, 1),
            (RUN_2_FOREVER, True, 2, 0),
            (STOP, False, 2, 0),  # STOP names no group: the last one stays
            (STOP, False, 2, 0),
            (RUN_8_ONCE, True, 8, 1),
            (STOP, False, 8, 1),
        ):
            uart.feed(frame)
            bus.poll()
            self.assertEqual((bus.running, bus.group, bus.times), (running, group, times))

    def test_commands_after_reading_behind_a_partial_frame(self):
        # Bytes read behind a partial frame pass through the idle transmit
        # buffer; what is sent next must not carry any of them.
        uart, bus = fresh([5], [POSITIONS_84])
        uart.feed(b"\x55" * 40 + POSITIONS_84[:100])
        self.assertIsNone(bus.poll())
        bus.stop_group()
        bus.run_group(8)
        self.assertEqual(uart.written(), STOP + RUN_8_ONCE)
        uart.feed(POSITIONS_84[100:])
        self.assertEqual(bus.poll(), CMD_MULT_SERVO_POS_READ)
        self.assertEqual(bus.positions[83], 1083)

    def test_a_servo_that_does_not_answer_reads_none(self):
        # The controller reads 65535 (FF FF) for a servo unpowered or not on the bus: that is
        # no position. (A servo truly at -1 reads the same.)
        reply = bytes((0x55, 0x55, 0x09, 0x15, 0x02, 0x01, 0xFF, 0xFF, 0x02, 0xFE, 0xFF))
        uart, bus = fresh(frames=[reply])
        uart.feed(reply)
        self.assertEqual(bus.poll(), CMD_MULT_SERVO_POS_READ)
        self.assertEqual(bus.positions, {1: None, 2: -2})

    def test_positions_are_updated_in_place(self):
        uart, bus = fresh(frames=[POSITIONS_ALL_500])
        positions = bus.positions
        positions[7] = 123
        uart.feed(POSITIONS_ALL_500)
        bus.poll()
        self.assertIs(bus.positions, positions)
        self.assertEqual(positions[7], 123)
        self.assertEqual(positions[6], 500)


class Resync(unittest.TestCase):
    def assertFrames(self, data, expect, state=None, asked=()):
        for size in (1, 3, 64):
            uart, bus = fresh([size], asked)
            uart.feed(data)
            self.assertEqual(drain(bus), expect, "chunks of %d" % size)
            if state:
                for name, value in state.items():
                    self.assertEqual(getattr(bus, name), value, name)

    def test_noise_before_between_and_after_frames(self):
        noise = bytes((0x00, 0xFF, 0x12, 0x07, 0x05))
        self.assertFrames(
            noise + RUN_8_ONCE + noise + BATTERY_7500 + noise,
            [CMD_ACTION_GROUP_RUN, CMD_GET_BATTERY_VOLTAGE],
            {"battery": 7500, "group": 8},
        )

    def test_lone_0x55_bytes(self):
        self.assertFrames(
            b"\x55\x12\x55" + STOP + b"\x55" + BATTERY_7500 + b"\x01\x55",
            [CMD_ACTION_GROUP_STOP, CMD_GET_BATTERY_VOLTAGE],
        )

    def test_runs_of_0x55_end_in_the_header(self):
        for run in range(3, 9):
            self.assertFrames(
                b"\x55" * (run - 2) + RUN_8_ONCE + b"\x55" * (run - 2) + BATTERY_7500,
                [CMD_ACTION_GROUP_RUN, CMD_GET_BATTERY_VOLTAGE],
                {"group": 8, "times": 1, "battery": 7500},
            )

    def test_impossible_lengths_do_not_swallow_the_frames_behind(self):
        for bad in (
            b"\x55\x55\xff\x06",  # RUN must have Length 5
            b"\x55\x55\x09\x08",  # COMPLETE must have Length 5
            b"\x55\x55\x05\x07",  # STOP must have Length 2
            b"\x55\x55\x40\x0f",  # battery must have Length 4
            b"\x55\x55\x09\x15\x06",  # 6 positions need Length 21
            b"\x55\x55\x02\x15",  # positions need Length 6 or more (3n + 3, n >= 1) ...
            b"\x55\x55\x03\x15",  # ... which 4 bytes read alone must already show
            b"\x55\x55\x04\x15\x01",
            b"\x55\x55\x00",  # no frame has Length 0 or 1
            b"\x55\x55\x01",
        ):
            self.assertFrames(
                bad + RUN_8_ONCE + STOP + BATTERY_7500,
                [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_STOP, CMD_GET_BATTERY_VOLTAGE],
                {"battery": 7500, "group": 8},
                asked=[POSITIONS_1_500, POSITIONS_ALL_500],  # so the Length is what tells
            )

    def test_positions_nobody_asked_for_are_noise(self):
        # The controller sends positions only in reply. Unasked, 55 55 FF 15 54 (84
        # servos) would hold the frames behind it until 252 bytes had come, and eat them.
        for unasked, asked in (
            (POSITIONS_ALL_500, ()),
            (POSITIONS_84[:5], ()),
            (POSITIONS_84[:4], ()),
            (POSITIONS_ALL_500, [POSITIONS_1_500]),  # a count that no request asked for
            (POSITIONS_84[:5], [POSITIONS_1_500, POSITIONS_ALL_500]),
        ):
            self.assertFrames(
                unasked + RUN_8_ONCE + STOP * 70,
                [CMD_ACTION_GROUP_RUN] + [CMD_ACTION_GROUP_STOP] * 70,
                {"noise": len(unasked), "positions": {}},
                asked,
            )

    def test_a_reply_to_any_request_in_flight_is_a_frame(self):
        # Two requests in flight, for 1 and for 6 servos: either reply is a frame.
        self.assertFrames(
            POSITIONS_ALL_500 + POSITIONS_1_500,
            [CMD_MULT_SERVO_POS_READ] * 2,
            {"noise": 0, "positions": ALL_500},
            [POSITIONS_1_500, POSITIONS_ALL_500],
        )

    def test_a_rejected_frame_can_hide_the_next_header(self):
        # 55 55 05 07 is no STOP; the 55 55 02 07 inside it is.
        self.assertFrames(b"\x55\x55\x05\x07\x55\x55\x02\x07", [CMD_ACTION_GROUP_STOP])

    def test_one_0x55_starts_no_frame(self):
        # Two 0x55 start a frame: 55 00 02 07 is no STOP, nor 55 54 04 0F 4C 1D (a bit of
        # the header flipped) a battery reply.
        self.assertFrames(
            b"\x55\x00\x02\x07" + b"\x55\x54\x04\x0f\x4c\x1d" + RUN_8_ONCE,
            [CMD_ACTION_GROUP_RUN],
            {"noise": 10, "battery": None, "running": True},
        )

    def test_frames_of_commands_the_controller_does_not_send_are_noise(self):
        # Only RUN, STOP, COMPLETE, battery and positions come from the
        # controller. Trusting another command's Length would let three bytes
        # of noise (55 55 L) swallow the good frames behind them.
        unknown = bytes((0x55, 0x55, 0x06, 0x63, 0x55, 0x55, 0x02, 0x07))
        uart, bus = fresh()
        uart.feed(unknown + BATTERY_7500 + UNKNOWN_255 + RUN_8_ONCE)
        self.assertEqual(
            drain(bus), [CMD_ACTION_GROUP_STOP, CMD_GET_BATTERY_VOLTAGE, CMD_ACTION_GROUP_RUN]
        )
        self.assertEqual(bus.noise, 4 + len(UNKNOWN_255))

    def test_a_length_4_frame_of_another_command_is_no_battery_reply(self):
        # The battery reply's Length is 4; so is that of unload([1, 2]) (55 55 04 14 01 02),
        # the driver's own frame read back, and of noise that looks like a frame. Only
        # the command makes a battery reply.
        self.assertFrames(
            b"\x55\x55\x04\x14\x01\x02" + b"\x55\x55\x04\x63\x01\x02" + BATTERY_7500,
            [CMD_GET_BATTERY_VOLTAGE],
            {"noise": 12, "battery": 7500},
        )

    def test_commands_the_driver_sends_are_frames_too(self):
        # The RUN and STOP the driver sends are the frames the controller sends
        # back, at every cut; the other commands are frames the controller
        # never sends, so to the parser they are noise, and swallow nothing.
        out = FakeUART()
        sender = busservo.BusServo(out)
        sender.move(1, 800, 1000)
        sender.move_many([(i, 500) for i in range(1, 84)], 50)
        sender.run_group(8)
        sender.stop_group()
        sender.set_group_speed(busservo.ALL_GROUPS, 300)
        sender.request_battery()
        sender.unload(range(1, 253))
        sender.request_positions([1, 2, 3, 4, 5, 6])
        expect = [6, 7]
        stream = out.written()
        for cut in range(len(stream)):
            uart, bus = fresh([17])
            uart.feed(stream[:cut])
            got = drain(bus)
            uart.feed(stream[cut:])
            self.assertEqual(got + drain(bus), expect, "cut at %d" % cut)
            self.assertEqual((bus.running, bus.group), (False, 8))

    def test_noise_that_forms_a_frame_start_is_known_cut_by_the_frame_inside_it(self):
        # 55 55 04 0F is a battery frame's start, and no checksum tells it from one; but
        # the RUN that starts where its reading would be shows it was cut short: its four
        # bytes are noise, and the RUN and the STOP behind it come, whatever the pause
        # between them (a USB link's hand-over). It was taken for a battery of 0x5555 mV
        # once, swallowing the RUN, when the RUN came within 20 ms.
        self.assertFrames(
            b"\x55\x55\x04\x0f" + RUN_8_ONCE + STOP,
            [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_STOP],
            {"battery": None, "group": 8, "noise": 4},
        )

    def test_a_flood_of_noise_holds_one_poll_for_about_a_kilobyte(self):
        # A control loop's poll() returns after reading about 1 KB, whatever is waiting;
        # the frame behind 4000 bytes of noise comes a few calls later.
        uart, bus = fresh()
        uart.feed(bytes(4000) + STOP)
        self.assertEqual(bus.poll(), None)
        self.assertTrue(2800 <= uart.any() <= 3000, uart.any())
        got = [bus.poll() for _ in range(4)]
        self.assertEqual((got[:2], CMD_ACTION_GROUP_STOP in got), ([None, None], True))

    def test_memory_stays_bounded_under_endless_noise(self):
        import gc

        if not hasattr(gc, "mem_alloc"):
            self.skipTest("the heap: MicroPython's gc.mem_alloc() (not on CPython)")
        junk = bytearray()
        for i in range(4000):
            junk.append((i * 37) & 0xFF)
            if i % 97 == 0:
                junk += b"\x55\x55"  # headers that come to nothing
        uart, bus = fresh([50])
        gc.collect()
        before = gc.mem_alloc()
        for _ in range(5):
            uart.feed(junk)
            gc.collect()
            while uart.any():  # poll() reads about 1 KB a call at most
                drain(bus)
        uart.feed(STOP)
        self.assertEqual(drain(bus), [CMD_ACTION_GROUP_STOP])
        gc.collect()
        self.assertTrue(gc.mem_alloc() - before < 2048, "heap grew with the input")


if __name__ == "__main__":
    unittest.main()
