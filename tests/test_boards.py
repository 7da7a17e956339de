# Each board file's uart(), with a stand-in machine module that records what
# it is asked to make, since the unix port has no UART.
import unittest

from shell import fresh_import


class StandIn:
    def __init__(self):
        self.calls = []

    def UART(self, *args, **kwargs):
        self.calls.append(("UART", args, kwargs))
        return ("UART", args, kwargs)

    def Pin(self, *args):
        return ("Pin",) + args

    def dupterm(self, *args):
        self.calls.append(("dupterm",) + args)


def load(name, machine, os=None):
    """Import boards/<name>.py afresh against the stand-ins."""
    return fresh_import(name, machine=machine, **({"os": os} if os else {}))


class Boards(unittest.TestCase):
    def test_esp32_uses_uart2_on_gpio17_and_16(self):
        machine = StandIn()
        load("esp32", machine).uart()
        self.assertEqual(machine.calls, [("UART", (2,), {"baudrate": 9600, "tx": 17, "rx": 16})])

    def test_rp2_uses_uart0_on_gp0_and_gp1(self):
        machine = StandIn()
        load("rp2", machine).uart()
        self.assertEqual(
            machine.calls,
            [("UART", (0,), {"baudrate": 9600, "tx": ("Pin", 0), "rx": ("Pin", 1)})],
        )

    def test_esp32_refuses_pins_its_chip_cannot_have_before_opening_anything(self):
        class Implementation:
            _machine = ""

        class Sys:
            implementation = Implementation()

        class Gc:
            heap = 110000

            def mem_free(self):
                return self.heap

            def mem_alloc(self):
                return 0

        machine = StandIn()
        board = load("esp32", machine)
        board.sys = Sys()
        board.gc = gc = Gc()
        for name, heap, words in (
            ("Generic ESP32 module with ESP32", 110000, None),
            ("ESP32S3 module with ESP32S3", 8000000, None),  # its PSRAM has other pins
            ("Generic ESP32 module with SPIRAM with ESP32", 4000000, ("PSRAM", "25, 26")),
            ("ESP32 module (WROVER) with ESP32", 4000000, ("PSRAM", "ESP32-CAM")),
            ("ESP32C3 module with ESP32C3", 110000, ("no UART2", "UART_ID = 1")),
            ("ESP32S2 module with ESP32S2", 110000, ("no UART2",)),
        ):
            Implementation._machine = name
            gc.heap = heap
            machine.calls = []
            try:
                board.uart()
                error = None
            except ValueError as e:
                error = str(e)
            if words is None:
                self.assertIsNone(error, name)
                self.assertEqual(len(machine.calls), 1, name)
            else:
                self.assertEqual(machine.calls, [], name)  # nothing opened
                for word in words:
                    self.assertIn(word, error or "", name)
        # The fix it names works: other pins on the WROVER, UART1 on the C3.
        Implementation._machine = "Generic ESP32 module with SPIRAM with ESP32"
        board.TX, board.RX = 25, 26
        board.uart()
        Implementation._machine = "ESP32C3 module with ESP32C3"
        board.UART_ID, board.TX, board.RX = 1, 5, 4
        board.uart()
        self.assertEqual(machine.calls[-1], ("UART", (1,), {"baudrate": 9600, "tx": 5, "rx": 4}))

    def test_rp2_offers_the_bootsel_button_as_a_pin_that_reads_0_while_pressed(self):
        import sys

        board = load("rp2", StandIn())

        class Rp2:
            down = False

            def bootsel_button(self):
                return 1 if self.down else 0

        rp2 = Rp2()
        sys.modules["rp2"] = rp2  # MicroPython's own rp2 module, on a Pico
        try:
            pin = board.button()
        finally:
            sys.modules.pop("rp2")
        self.assertEqual(pin.value(), 1)
        rp2.down = True
        self.assertEqual(pin.value(), 0)

    def test_stm32_uses_uart6(self):
        machine = StandIn()
        load("stm32", machine).uart()
        self.assertEqual(machine.calls, [("UART", (6,), {"baudrate": 9600})])

    def test_esp8266_detaches_the_repl_from_uart0_and_gives_it_back(self):
        machine = StandIn()
        os = StandIn()
        board = load("esp8266", machine, os)
        board.uart()
        self.assertEqual(os.calls, [("dupterm", None, 1)])
        self.assertEqual(machine.calls, [("UART", (0,), {"baudrate": 9600})])
        board.repl()
        uart = ("UART", (0,), {"baudrate": 115200})
        self.assertEqual(os.calls[-1], ("dupterm", uart, 1))

    def test_unix_names_a_device_it_cannot_open(self):
        from unix import uart

        try:
            uart("/nonexistent/ttyUSB9")
        except OSError as e:
            self.assertIn("/nonexistent/ttyUSB9", str(e))
        else:
            self.fail("no OSError")

    def test_every_board_file_says_how_to_wire_it(self):
        for name in ("esp32", "rp2", "stm32", "esp8266", "unix"):
            with open("boards/%s.py" % name) as f:
                text = f.read()
            for word in ("TX", "RX", "GND"):
                self.assertIn(word, text, "boards/%s.py" % name)


if __name__ == "__main__":
    unittest.main()
