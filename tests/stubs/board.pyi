# board.py: a board file from boards/ (boards/esp32.py, ...), copied to the board as board.py.
# The examples import uart() from it, and fall back to busservo_sim.uart() without one.
# examples/teach.py also takes a button() if the board file offers one (boards/esp32.py does).
from machine import Pin

from busservo import _UART

def uart() -> _UART: ...
def button() -> Pin: ...
