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
