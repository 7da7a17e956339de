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
