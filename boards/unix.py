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
# A 3.3 V adapter's RX wants a divider if the controller's TX measures about 5 V
# (boards/README.md).
#
# It says how its bytes come, for the driver's timing (latency_ms: a USB-serial adapter
# hands them over every few ms, a busy computer later still; None for a pty, at any pace),
# and a blocking query waits for them in the OS (wait(ms)), costing no CPU meanwhile.
#
# An unplugged adapter raises OSError(EIO) from the next call. But a process
# that leads a session with no terminal (a systemd service, setsid) takes the
# device as its terminal (MicroPython's open() has no O_NOCTTY), and an unplug
# then kills it with SIGHUP: start such a one under nohup.
import errno
import select
import termios

_BAUDRATES = {
    9600: termios.B9600,
    57600: termios.B57600,
    115200: termios.B115200,
}
_VTIME = 5  # indices into termios' control characters (Linux)
_VMIN = 6
# What a computer adds to a serial port's bytes, ms, as busservo_host.latency_ms() says it
# (tests/test_host.py checks that they agree): an FTDI adapter's latency timer (16 ms by
# default, or what Linux says), one unknown as long, and what a busy computer adds to each
# hand-over (busservo_host.BUSY_MS).
_HAND_OVER_MS = 16
_BUSY_MS = 20


def uart(path, baudrate=9600):
    """Open the serial device at path, raw, at baudrate."""
    return SerialUART(path, baudrate)


def _mount_type(fd):
    # The type of the file system an open file is on, by its mount's id (Linux /proc): a pty
    # is on devpts. The unix port has no readlink() to follow a link to one.
    try:
        with open("/proc/self/fdinfo/%d" % fd) as f:
            mount = [line.split()[1] for line in f if line.startswith("mnt_id:")][0]
        with open("/proc/self/mountinfo") as f:
            for line in f:
                if line.split()[0] == mount:
                    return line.split(" - ")[1].split()[0]
    except (OSError, IndexError):
        pass
    return None


def latency_ms(path, fd):
    """How much later than the wire the controller's bytes may reach this program, in ms,
    as busservo's driver counts it: None for a pty, whose far end writes at any pace."""
    if _mount_type(fd) == "devpts":
        return None
    try:
        with open("/sys/bus/usb-serial/devices/%s/latency_timer" % path.split("/")[-1]) as f:
            return int(f.read()) + _BUSY_MS
    except (OSError, ValueError):
        return _HAND_OVER_MS + _BUSY_MS


class SerialUART:
    def __init__(self, path, baudrate=9600):
        # A path, never a number: open(0) is this process's own terminal (stdin), which a
        # board's UART(0) habit would put in raw mode.
        if type(path) is not str:
            raise TypeError(
                "uart() wants the serial device's path, such as '/dev/ttyUSB0', got %r" % (path,)
            )
        if baudrate not in _BAUDRATES:
            raise ValueError("baudrate must be one of %s, got %r" % (sorted(_BAUDRATES), baudrate))
        self.path = path
        try:
            self._file = open(path, "r+b")
        except OSError as e:
            raise OSError(e.args[0], "cannot open serial device %s" % path)
        attrs = None
        try:
            fd = self._file.fileno()
            termios.setraw(fd)  # no echo, no line editing, 8 bits through untouched
            attrs = termios.tcgetattr(fd)
            attrs[4] = attrs[5] = _BAUDRATES[baudrate]
            # Reads return at once with what has arrived, as machine.UART's do.
            attrs[6][_VMIN] = 0
            attrs[6][_VTIME] = 0
            termios.tcsetattr(fd, termios.TCSANOW, attrs)
        except OSError as e:
            self._file.close()  # give the descriptor back
            if attrs is None:  # termios refused it: no tty
                raise OSError(e.args[0], "%s is not a serial device" % path)
            raise OSError(e.args[0], "%s: cannot set %d baud" % (path, baudrate))
        self.latency_ms = latency_ms(path, self._file.fileno())  # read by busservo.BusServo()
        self._in = select.poll()
        self._in.register(self._file, select.POLLIN)
        self._out = select.poll()
        self._out.register(self._file, select.POLLOUT)
        self._buf = bytearray(256)  # read ahead, so any() can count
        self._start = 0
        self._end = 0

    def _raise_hung_up(self):
        # The device has gone (an unplugged adapter, a pty whose other side
        # closed). A hung-up tty stays so: it reads nothing, fails writes with
        # EIO and polls POLLHUP for ever, so each call raises from then on.
        raise OSError(errno.EIO, "%s: the serial device hung up" % self.path)

    def _ready(self, poller):
        # Whether the device is ready (poll with no wait); a hang-up raises.
        for _, event in poller.poll(0):
            if event & (select.POLLHUP | select.POLLERR):
                self._raise_hung_up()
            return True
        return False

    def any(self):
        """Bytes waiting to be read."""
        if self._start == self._end and self._ready(self._in):
            try:
                n = self._file.readinto(self._buf)
            except OSError as e:
                if e.args[0] != errno.EIO:
                    raise
                n = 0
            if not n:  # ready, yet nothing: the other end has gone
                self._raise_hung_up()
            self._start = 0
            self._end = n
        return self._end - self._start

    def readinto(self, buf, nbytes=None):
        n = self.any()
        if not n:
            return None
        if nbytes is None or nbytes > len(buf):
            nbytes = len(buf)
        if n > nbytes:
            n = nbytes
        start = self._start
        for i in range(n):
            buf[i] = self._buf[start + i]
        self._start = start + n
        return n

    def wait(self, ms):
        """Wait until bytes have come, or ms have passed, in the OS: what a blocking query
        does between its looks at the device."""
        if self._start == self._end:
            self._in.poll(ms)

    def read(self, nbytes=None):
        n = self.any()
        if not n:
            return None
        buf = bytearray(n if nbytes is None else min(n, nbytes))
        return bytes(buf[: self.readinto(buf)])

    def write(self, buf, off=None, nbytes=None):
        """As machine.UART.write() on a port with timeout=0: what the device
        takes now (the stream protocol's write(buf), write(buf, n) and
        write(buf, off, n)), or None if it takes nothing."""
        # The unix port can open no file O_NONBLOCK (no os.open, fcntl or ffi),
        # and its file write() goes on until all is written. So: only when poll()
        # says the device is writable, and at most 256 bytes, which Linux then
        # has room for (POLLOUT: under 256 bytes queued; a pty's room comes in
        # 256-byte steps, a USB adapter's in kilobytes).
        if nbytes is None:
            nbytes = len(buf) if off is None else off
            off = 0
        off = min(off, len(buf))
        nbytes = min(nbytes, len(buf) - off, 256)
        if nbytes <= 0:
            return 0  # as the stream protocol: nothing asked, nothing written
        if not self._ready(self._out):
            return None
        try:
            return self._file.write(buf, off, nbytes) or None
        except OSError as e:
            if e.args[0] != errno.EIO:
                raise
        self._raise_hung_up()

    def close(self):
        self._file.close()
