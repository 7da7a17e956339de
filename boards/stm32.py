# pyboard / stm32: UART6 on Y1 (TX) and Y2 (RX), 9600 baud.
# Copy to the board as board.py: mpremote cp boards/stm32.py :board.py
#
# Wiring: Y1 (TX) to the controller's RX, Y2 (RX) to its TX, GND to GND. The
# servos take their power from the controller's supply, never from the pyboard.
# If the controller's TX measures about 5 V, check Y2 is 5 V tolerant in your
# board's datasheet, or put a divider on it (boards/README.md).
# The REPL is on USB, so UART6 is free. On another stm32 board, pick a UART whose
# pins are free there: UART(id) uses that board's default pins.
from machine import UART


def uart():
    return UART(6, baudrate=9600)
