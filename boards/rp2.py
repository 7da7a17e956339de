# Raspberry Pi Pico (rp2): UART0 on GP0 (TX) and GP1 (RX), 9600 baud.
# Copy to the board as board.py: mpremote cp boards/rp2.py :board.py
#
# Wiring: GP0 (pin 1, TX) to the controller's RX, GP1 (pin 2, RX) to its TX, GND
# (pin 3) to GND. The servos take their power from the controller's supply, never
# from the Pico. The REPL is on USB, so UART0 is free.
# GP1 is 3.3 V and not 5 V tolerant: if the controller's TX measures about 5 V, put
# a divider (1k in series, 2k to GND) on it. boards/README.md and wiring-pico.svg.
from machine import UART, Pin

# examples/web_panel.py joins this Wi-Fi network (a Pico W or an ESP32); without WIFI it
# starts an access point of its own, "busservo".
# WIFI = ("network name", "its password")


def uart():
    return UART(0, baudrate=9600, tx=Pin(0), rx=Pin(1))


def button():
    # The BOOTSEL button, which every Pico has: examples/teach.py captures a pose at each
    # press. It reads as a Pin with a pull-up does, 0 while pressed.
    import rp2  # MicroPython's own (this file is board.py on the board)

    return _Pressed(rp2.bootsel_button)


class _Pressed:
    def __init__(self, pressed):
        self._pressed = pressed  # 1 while the button is down

    def value(self):
        return 0 if self._pressed() else 1
