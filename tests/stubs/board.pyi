# board.py: a board file from boards/ (boards/esp32.py, ...), copied to the board as board.py.
# The examples import uart() from it, and fall back to busservo_sim.uart() without one.
from busservo import _UART

def uart() -> _UART: ...
