# The MicroPython unix port: a Linux serial device (a USB-serial adapter wired
# to the controller, or a pty such as `sh boards/unix.sh --sim-pty` prints) as
# an object with machine.UART's any(), read(), readinto() and write().
#
#   import busservo
#   from unix import uart
#   bus = busservo.BusServo(uart("/dev/ttyUSB0"))
#
# Wiring for an adapter: its TX to the controller's RX, its RX to the
# controller's TX, GND to GND; the servos take their power from the controller.
import select
import termios

_BAUDRATES = {
    9600: termios.B9600,
    57600: termios.B57600,
    115200: termios.B115200,
}
_VTIME = 5  # indices into termios' control characters (Linux)
_VMIN = 6


def uart(path, baudrate=9600):
    """Open the serial device at path, raw, at baudrate."""
    return SerialUART(path, baudrate)


class SerialUART:
    def __init__(self, path, baudrate=9600):
        if baudrate not in _BAUDRATES:
            raise ValueError("baudrate must be one of %s" % sorted(_BAUDRATES))
        try:
            self._file = open(path, "r+b")
        except OSError as e:
            raise OSError(e.args[0], "cannot open serial device %s" % path)
        fd = self._file.fileno()
        termios.setraw(fd)  # no echo, no line editing, 8 bits through untouched
        attrs = termios.tcgetattr(fd)
        attrs[4] = attrs[5] = _BAUDRATES[baudrate]
        # Reads return at once with what has arrived, as machine.UART's do.
        attrs[6][_VMIN] = 0
        attrs[6][_VTIME] = 0
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
        self._poll = select.poll()
        self._poll.register(self._file, select.POLLIN)
        self._buf = bytearray(256)  # read ahead, so any() can count
        self._start = 0
        self._end = 0

    def any(self):
        """Bytes waiting to be read."""
        if self._start == self._end and self._poll.poll(0):
            self._start = 0
            self._end = self._file.readinto(self._buf) or 0
        return self._end - self._start

    def readinto(self, buf, nbytes=None):
        n = self.any()
        if not n:
            return None
        if nbytes is None:
            nbytes = len(buf)
        if n > nbytes:
            n = nbytes
        start = self._start
        for i in range(n):
            buf[i] = self._buf[start + i]
        self._start = start + n
        return n

    def read(self, nbytes=None):
        n = self.any()
        if not n:
            return None
        buf = bytearray(n if nbytes is None else min(n, nbytes))
        return bytes(buf[: self.readinto(buf)])

    def write(self, buf, nbytes=None):
        """Write the first nbytes of buf (all of it by default); returns when written."""
        if nbytes is None:
            nbytes = len(buf)
        done = 0
        while done < nbytes:
            done += self._file.write(buf[done:nbytes]) or 0
        return nbytes

    def close(self):
        self._file.close()
