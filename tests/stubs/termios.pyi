# MicroPython's termios module on the unix port (it shadows CPython's for the check).
from typing import Any

TCSANOW: int
B9600: int
B57600: int
B115200: int
B230400: int
B460800: int
B500000: int
B576000: int
B921600: int
B1000000: int
B1152000: int

def tcgetattr(fd: int, /) -> list[Any]: ...
def tcsetattr(fd: int, when: int, attrs: list[Any], /) -> None: ...
def setraw(fd: int, /) -> None: ...
