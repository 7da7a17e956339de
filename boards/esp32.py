# ESP32: UART2 on GPIO17 (TX) and GPIO16 (RX), 9600 baud.
# Copy to the board as board.py: mpremote cp boards/esp32.py :board.py
#
# Wiring: GPIO17 (TX) to the controller's RX, GPIO16 (RX) to its TX, GND to GND.
# The servos take their power from the controller's supply, never from the ESP32.
# GPIO16 is 3.3 V and not 5 V tolerant: if the controller's TX measures about 5 V,
# put a divider (1k in series, 2k to GND) on it. boards/README.md, wiring-esp32.svg.
# (UART0 is the REPL's; UART1's default pins are the flash's on most modules.)
from machine import UART, Pin

# examples/web_panel.py joins this Wi-Fi network (a Pico W or an ESP32); without WIFI it
# starts an access point of its own, "busservo".
# WIFI = ("network name", "its password")


def uart():
    return UART(2, baudrate=9600, tx=17, rx=16)


def button():
    # The BOOT button of most ESP32 boards (GPIO0): 0 while pressed. examples/teach.py
    # captures a pose at each press.
    return Pin(0, Pin.IN, Pin.PULL_UP)
