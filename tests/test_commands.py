# What the driver writes, byte for byte against the worked examples of
# section I of the protocol document (see docs/protocol.md), and what it refuses to write.
import io
import os
import sys
import unittest

import busservo
from fakeuart import FakeUART, SimulatedTime


class Commands(unittest.TestCase):
    def setUp(self):
        self.uart = FakeUART()
        self.bus = busservo.BusServo(self.uart)

    def assertSent(self, *frame):
        self.assertEqual(self.uart.written(), bytes(frame))
        self.assertEqual(self.uart.writes, 1)  # one write() per command

    # 1. CMD_SERVO_MOVE

    def test_move_servo_1_to_800_in_1000ms(self):
        self.bus.move(1, 800, 1000)
        self.assertSent(0x55, 0x55, 0x08, 0x03, 0x01, 0xE8, 0x03, 0x01, 0x20, 0x03)

    def test_move_many_servos_2_and_9_to_800_in_800ms(self):
        self.bus.move_many([(2, 800), (9, 800)], 800)
        self.assertSent(
            0x55, 0x55, 0x0B, 0x03, 0x02, 0x20, 0x03, 0x02, 0x20, 0x03, 0x09, 0x20, 0x03
        )

    def test_move_many_takes_a_dict(self):
        self.bus.move_many({9: 800}, 800)
        self.assertSent(0x55, 0x55, 0x08, 0x03, 0x01, 0x20, 0x03, 0x09, 0x20, 0x03)

    def test_move_many_83_servos_fills_the_length_byte(self):
        self.bus.move_many([(i, 0x1234) for i in range(83)], 0xABCD)
        sent = self.uart.written()
        self.assertEqual(len(sent), 256)
        self.assertEqual(sent[:7], bytes((0x55, 0x55, 254, 0x03, 83, 0xCD, 0xAB)))
        self.assertEqual(sent[-3:], bytes((82, 0x34, 0x12)))

    def test_move_many_sends_the_pairs_it_read_with_their_count(self):
        # servos that change while move_many() reads them (here a pair's __iter__; on a board
        # with two cores, another thread), or a sequence whose len() is not what it holds:
        # the frame carries the pairs read, and their count. (The controller drops a frame
        # whose Length is not 3 * count + 5, and looks for frames in its bytes; a count it
        # believes beyond the pairs sent takes stale bytes for servos.)
        def grow(servos):
            servos.append((9, 900))

        def shrink(servos):
            servos.pop()

        class Pair:
            def __init__(self, servos, change):
                self.servos = servos
                self.change = change

            def __iter__(self):
                if self.change:
                    self.change(self.servos)
                    self.change = None  # once
                return iter((1, 500))

        class Sized:  # says 2, holds 3
            def __len__(self):
                return 2

            def __iter__(self):
                return iter([(1, 500), (2, 600), (3, 700)])

        for change, read in (
            (grow, [(1, 500), (2, 600), (3, 700), (9, 900)]),
            (shrink, [(1, 500), (2, 600)]),
            (None, [(1, 500), (2, 600), (3, 700)]),
        ):
            uart = FakeUART()
            bus = busservo.BusServo(uart)
            bus.move_many(read, 100)
            want = uart.written()
            uart.clear()
            bus.move_many([(5, 555), (6, 666), (7, 777)], 100)  # tx holds their bytes
            uart.clear()
            servos = Sized()
            if change:
                servos = []
                servos += [Pair(servos, change), (2, 600), (3, 700)]
            bus.move_many(servos, 100)
            self.assertEqual(uart.written(), want, change)

    def test_move_extremes(self):
        self.bus.move(255, 65535, 65535)
        self.assertSent(0x55, 0x55, 0x08, 0x03, 0x01, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF)

    # 2. CMD_ACTION_GROUP_RUN

    def test_run_group_8_once(self):
        self.bus.run_group(8)
        self.assertSent(0x55, 0x55, 0x05, 0x06, 0x08, 0x01, 0x00)

    def test_run_group_2_forever(self):
        self.bus.run_group(2, 0)
        self.assertSent(0x55, 0x55, 0x05, 0x06, 0x02, 0x00, 0x00)

    # 3. CMD_ACTION_GROUP_STOP

    def test_stop_group(self):
        self.bus.stop_group()
        self.assertSent(0x55, 0x55, 0x02, 0x07)

    # 4. CMD_ACTION_GROUP_SPEED

    def test_group_8_at_50_percent(self):
        self.bus.set_group_speed(8, 50)
        self.assertSent(0x55, 0x55, 0x05, 0x0B, 0x08, 0x32, 0x00)

    def test_all_groups_at_300_percent(self):
        self.bus.set_group_speed(busservo.ALL_GROUPS, 300)
        self.assertSent(0x55, 0x55, 0x05, 0x0B, 0xFF, 0x2C, 0x01)

    # 5. CMD_GET_BATTERY_VOLTAGE

    def test_request_battery(self):
        self.bus.request_battery()
        self.assertSent(0x55, 0x55, 0x02, 0x0F)

    # 6. CMD_MULT_SERVO_UNLOAD

    def test_unload_1_2_3(self):
        self.bus.unload([1, 2, 3])
        self.assertSent(0x55, 0x55, 0x06, 0x14, 0x03, 0x01, 0x02, 0x03)

    def test_unload_1_to_6(self):
        self.bus.unload((1, 2, 3, 4, 5, 6))
        self.assertSent(0x55, 0x55, 0x09, 0x14, 0x06, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06)

    def test_unload_252_servos_fills_the_length_byte(self):
        self.bus.unload(bytes(range(252)))
        sent = self.uart.written()
        self.assertEqual(len(sent), 257)
        self.assertEqual(sent[:6], bytes((0x55, 0x55, 255, 0x14, 252, 0)))

    # 7. CMD_MULT_SERVO_POS_READ

    def test_request_positions_1_to_6(self):
        self.bus.request_positions([1, 2, 3, 4, 5, 6])
        self.assertSent(0x55, 0x55, 0x09, 0x15, 0x06, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06)

    def test_request_84_positions(self):
        self.bus.request_positions(range(84))
        self.assertEqual(self.uart.written()[:5], bytes((0x55, 0x55, 87, 0x15, 84)))

    def test_a_frame_the_uart_takes_in_parts_leaves_whole_and_once(self):
        # A full transmit buffer: write() takes 3 bytes, then none, then 4, then the rest.
        with SimulatedTime():  # (the driver's deadline is the wire's, not a busy machine's)
            uart = FakeUART()
            uart.takes = [3, None, None, 4]
            busservo.BusServo(uart).move(1, 800, 1000)
        self.assertEqual(
            uart.written(),
            bytes((0x55, 0x55, 0x08, 0x03, 0x01, 0xE8, 0x03, 0x01, 0x20, 0x03)),
        )

    def test_a_uart_that_takes_nothing_raises_eio_and_the_cut_frame_goes_first_next(self):
        import errno

        move_1 = bytes((0x55, 0x55, 0x08, 0x03, 0x01, 0xE8, 0x03, 0x01, 0x20, 0x03))
        self.uart.takes = [4] + [None] * 100000
        with self.assertRaises(OSError):
            self.bus.move(1, 800, 1000)
        try:
            self.bus.stop_group()  # still nothing taken: it cannot start, and says so
        except OSError as e:
            self.assertEqual(e.args[0], errno.EIO)
        else:
            self.fail("a frame started after a cut one")
        self.uart.takes = None
        self.bus.stop_group()  # the rest of the move first, then the STOP
        self.assertEqual(self.uart.written(), move_1 + bytes((0x55, 0x55, 0x02, 0x07)))

    def test_constants_have_the_protocol_numbers(self):
        self.assertEqual(
            (
                busservo.CMD_SERVO_MOVE,
                busservo.CMD_ACTION_GROUP_RUN,
                busservo.CMD_ACTION_GROUP_STOP,
                busservo.CMD_ACTION_GROUP_COMPLETE,
                busservo.CMD_ACTION_GROUP_SPEED,
                busservo.CMD_GET_BATTERY_VOLTAGE,
                busservo.CMD_MULT_SERVO_UNLOAD,
                busservo.CMD_MULT_SERVO_POS_READ,
                busservo.ALL_GROUPS,
            ),
            (3, 6, 7, 8, 11, 15, 20, 21, 0xFF),
        )


class ModuleUnderTest(unittest.TestCase):
    def test_the_suite_tests_the_module_it_says(self):
        # tests/run.sh runs everything twice: on lib/busservo.py, then with
        # BUSSERVO_LIB=.venv/mpy on the compiled busservo.mpy alone.
        lib = os.getenv("BUSSERVO_LIB") or "lib"
        kind = "py" if lib == "lib" else "mpy"
        path = busservo.__file__
        if sys.implementation.name != "micropython":  # tests/cpython.py: an absolute path
            path = path[len(os.getcwd()) + 1 :]
        self.assertEqual(path, "%s/busservo.%s" % (lib, kind))

    def test_a_traceback_from_inside_the_driver_names_its_line(self):
        # In the .mpy pass busservo is the .mpy that `sh boards/unix.sh --mpy` makes: with
        # mpy-cross's default optimisation it keeps its line numbers (-O3 dropped them).
        try:
            busservo.BusServo(FakeUART()).move(300, 500, 0)
        except ValueError as e:
            out = io.StringIO()
            if hasattr(sys, "print_exception"):
                sys.print_exception(e, out)
            else:  # CPython (tests/cpython.py)
                import traceback

                traceback.print_exception(type(e), e, e.__traceback__, file=out)
            text = out.getvalue()
        with open("lib/busservo.py") as f:  # the line that raised, in the source
            lines = f.read().split("\n")
        line = [i + 1 for i, s in enumerate(lines) if "must be an int in" in s]
        self.assertIn('busservo.py", line %d, in _check' % line[0], text)
        self.assertIn("servo_id must be an int in 0..255, got 300", text)


# (method, arguments, exception, words the message must contain)
BAD_INPUT = (
    ("move", (256, 0, 0), ValueError, ("servo_id", "0..255")),
    ("move", (-1, 0, 0), ValueError, ("servo_id", "0..255")),
    ("move", (1, 65536, 0), ValueError, ("position", "0..65535")),
    ("move", (1, -5, 0), ValueError, ("position", "0..65535")),
    ("move", (1, 0, 65536), ValueError, ("time_ms", "0..65535")),
    ("move", (1.0, 0, 0), TypeError, ("servo_id", "0..255")),
    ("move", (True, 0, 0), TypeError, ("servo_id", "0..255")),
    ("move", (1, "500", 0), TypeError, ("position", "0..65535")),
    ("move", (1, 500.5, 100), TypeError, ("position", "0..65535")),
    ("move", (1, 500, None), TypeError, ("time_ms", "0..65535")),
    ("move_many", ([], 0), ValueError, ("servos", "1..83")),
    ("move_many", ([(1, 0)] * 84, 0), ValueError, ("servos", "1..83")),
    ("move_many", (5, 0), TypeError, ("servos", "a list")),
    ("move_many", ([(1, 0), (2, 70000)], 0), ValueError, ("position", "0..65535")),
    ("move_many", ([(1, 0), (300, 0)], 0), ValueError, ("servo_id", "0..255")),
    ("move_many", ([(1, 0), (2,)], 0), TypeError, ("servos", "pairs")),
    ("move_many", ([(1, 0), 5], 0), TypeError, ("servos", "pairs")),
    ("move_many", ({1: 2.0}, 100), TypeError, ("position", "0..65535")),
    ("move_many", ([(1, 0)], -1), ValueError, ("time_ms", "0..65535")),
    ("move_many", ([(1, 0)], 1.5), TypeError, ("time_ms", "0..65535")),
    ("run_group", (256,), ValueError, ("group", "0..255")),
    ("run_group", ("1",), TypeError, ("group", "0..255")),
    ("run_group", (1, 65536), ValueError, ("times", "0..65535")),
    ("run_group", (1, -1), ValueError, ("times", "0..65535")),
    ("run_group", (1, 1.0), TypeError, ("times", "0..65535")),
    ("set_group_speed", (256, 100), ValueError, ("group", "0..255")),
    ("set_group_speed", (None, 100), TypeError, ("group", "0..255")),
    ("set_group_speed", (1, 65536), ValueError, ("percent", "0..65535")),
    ("set_group_speed", (1, 50.0), TypeError, ("percent", "0..65535")),
    ("unload", ([],), ValueError, ("ids", "1..252")),
    ("unload", (list(range(253)),), ValueError, ("ids", "1..252")),
    ("unload", (1,), TypeError, ("ids", "a list", "such as [1]", "got 1")),
    ("unload", ([1, 256],), ValueError, ("ids", "0..255")),
    ("unload", (["1"],), TypeError, ("ids", "0..255")),
    ("request_positions", ([],), ValueError, ("ids", "1..84")),
    ("request_positions", (list(range(85)),), ValueError, ("ids", "1..84")),
    ("request_positions", (None,), TypeError, ("ids", "a list")),
    ("read_positions", (3,), TypeError, ("ids", "a list", "such as [3]")),
    ("request_positions", ([3, 300],), ValueError, ("ids", "0..255")),
    ("read_positions", ([],), ValueError, ("ids", "1..84")),
    ("read_positions", ([1, 999],), ValueError, ("ids", "0..255")),
    ("read_positions", ([1], "x"), TypeError, ("timeout_ms",)),
    ("read_battery", (-1,), ValueError, ("timeout_ms",)),
    ("read_battery", (1.5,), TypeError, ("timeout_ms",)),
    ("read_battery", (60001,), ValueError, ("timeout_ms", "0..60000", "60001")),
    ("read_positions", ([1], 1.5), TypeError, ("timeout_ms", "1.5")),
    ("unload", (list(range(300)),), ValueError, ("ids", "1..252", "got 300")),
)


class BadInput(unittest.TestCase):
    def test_a_path_is_not_a_uart(self):
        try:
            busservo.BusServo("/dev/ttyUSB0")
        except TypeError as e:
            for word in ("uart", "any", "readinto", "write", "/dev/ttyUSB0"):
                self.assertIn(word, str(e))
        else:
            self.fail("BusServo('/dev/ttyUSB0') did not raise TypeError")

    def test_bad_input_is_refused_and_nothing_is_written(self):
        for method, args, error, words in BAD_INPUT:
            uart = FakeUART()
            bus = busservo.BusServo(uart)
            call = "%s%r" % (method, args)
            try:
                getattr(bus, method)(*args)
            except error as e:
                for word in words:
                    self.assertIn(word, str(e), "%s: %r lacks %r" % (call, str(e), word))
            else:
                self.fail("%s did not raise %s" % (call, error.__name__))
            self.assertEqual(uart.written(), b"", call + " wrote")
            self.assertEqual(uart.writes, 0, call + " wrote")


if __name__ == "__main__":
    unittest.main()
