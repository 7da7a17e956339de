# board.py: a board file from boards/ (boards/esp32.py, ...), copied to the board as board.py.
# The examples import uart() from it, and fall back to busservo_sim.uart() without one.
# examples/teach.py also takes a button() if the board file offers one (esp32.py and rp2.py do):
# anything with value(), 0 while pressed.
from typing import Protocol

from busservo import _UART

class _Button(Protocol):
    def value(self) -> int: ...

def uart() -> _UART: ...
def button() -> _Button: ...
