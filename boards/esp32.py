# ESP32: UART2 on GPIO17 (TX) and GPIO16 (RX), 9600 baud.
# Copy to the board as board.py: mpremote cp boards/esp32.py :board.py
#
# Wiring: GPIO17 (TX) to the controller's RX, GPIO16 (RX) to its TX, GND to GND.
# The servos take their power from the controller's supply, never from the ESP32.
# GPIO16 is 3.3 V and not 5 V tolerant: if the controller's TX measures about 5 V,
# put a divider (1k in series, 2k to GND) on it. boards/README.md, wiring-esp32.svg.
# (UART0 is the REPL's; UART1's default pins are the flash's on most modules.)
#
# Which modules these pins fit: the ESP32-WROOM ones (ESP32-DevKitC, most dev boards)
# and the ESP32-S3's. They do not fit:
# - an ESP32 with PSRAM (ESP32-WROVER modules: ESP32-CAM, WROVER-KIT, DevKitC-VE), whose
#   PSRAM has GPIO16 and GPIO17: set TX, RX = 25, 26 below (an ESP32-CAM with its SD card
#   unused: 14, 15), and wire those;
# - an ESP32-C3, -C6 or -S2, which have no UART2: set UART_ID = 1 and two free pins
#   (TX, RX = 5, 4 on most ESP32-C3 boards), and wire those.
# uart() refuses the pins where the board can tell they cannot work (the firmware's name
# for its chip, a PSRAM heap), before anything is opened.
import gc
import sys
from machine import UART, Pin

UART_ID = 2
TX = 17
RX = 16

# examples/web_panel.py joins this Wi-Fi network (a Pico W or an ESP32); without WIFI it
# starts an access point of its own, "busservo".
# WIFI = ("network name", "its password")


def uart():
    _check(UART_ID, TX, RX)
    return UART(UART_ID, baudrate=9600, tx=TX, rx=RX)


def _check(uart_id, tx, rx):
    """Refuse a UART or pins this ESP32 cannot have, naming the fix."""
    # "Generic ESP32 module with ESP32", "ESP32C3 module with ESP32C3", ...
    chip = sys.implementation._machine.rsplit(" with ", 1)[-1]
    if uart_id == 2 and chip in ("ESP32C2", "ESP32C3", "ESP32C6", "ESP32H2", "ESP32S2"):
        raise ValueError(
            "the %s has no UART2: in board.py set UART_ID = 1 and TX, RX to two free pins "
            "(5, 4 on most ESP32-C3 boards), and wire those" % chip
        )
    # A PSRAM heap is megabytes; without PSRAM an ESP32 has about 110 KB for scripts.
    psram = "SPIRAM" in sys.implementation._machine or gc.mem_free() + gc.mem_alloc() > 1 << 20
    if chip == "ESP32" and psram and (16 in (tx, rx) or 17 in (tx, rx)):
        raise ValueError(
            "GPIO16 and GPIO17 belong to this module's PSRAM (an ESP32-WROVER: ESP32-CAM, "
            "WROVER-KIT, DevKitC-VE): in board.py set TX, RX to two free pins (25, 26; on "
            "an ESP32-CAM with its SD card unused, 14, 15), and wire those"
        )


def button():
    # The BOOT button of most ESP32 boards (GPIO0): 0 while pressed. examples/teach.py
    # captures a pose at each press.
    return Pin(0, Pin.IN, Pin.PULL_UP)
