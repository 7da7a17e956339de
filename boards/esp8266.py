# ESP8266: UART0 on GPIO1 (TX) and GPIO3 (RX), 9600 baud, taken from the REPL.
# Copy to the board as board.py: mpremote cp boards/esp8266.py :board.py
#
# Wiring: GPIO1 (TX) to the controller's RX, GPIO3 (RX) to its TX, GND to GND.
# The servos take their power from the controller's supply, never from the board.
# GPIO3 is 3.3 V: if the controller's TX measures about 5 V, put a divider (1k in
# series, 2k to GND) on it (boards/README.md).
#
# The ESP8266 has one full UART, and the REPL uses it (UART1 can only send, on
# GPIO2). uart() detaches the REPL from UART0 so the driver can have it. The
# trade-off: from then until a reset, the serial REPL (and so mpremote) is gone;
# use WebREPL meanwhile, or call repl() to give UART0 back. The board's USB-serial
# chip shares these pins, so unplug USB or expect the controller to hear (and beep
# at) the boot messages.
import os
from machine import UART


def uart():
    os.dupterm(None, 1)  # detach the REPL
    return UART(0, baudrate=9600)


def repl():
    """Give UART0 back to the REPL, at its usual 115200 baud."""
    os.dupterm(UART(0, baudrate=115200), 1)
