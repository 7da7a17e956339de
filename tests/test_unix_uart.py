# boards/unix.py's SerialUART, which should behave as machine.UART on a port
# with timeout=0. Stand-ins for open(), termios and select do what a device will
# not do on cue (fail a read or write with EIO, refuse its settings); real ptys
# do the rest: the simulated controller behind one (sh boards/unix.sh --sim-pty),
# and one that nobody reads (a CPython one-liner: the unix port opens no pty).
import errno
import io
import os
import time
import unittest

from shell import fresh_import, scratch, start, stop, wait_for

BATTERY = bytes((0x55, 0x55, 0x02, 0x0F))
BATTERY_7500 = bytes((0x55, 0x55, 0x04, 0x0F, 0x4C, 0x1D))


class File:
    """The device's file: readinto() hands out `data` (or raises OSError(read_error)),
    write() keeps what it takes (or raises OSError(write_error))."""

    def __init__(self):
        self.data = b""
        self.read_error = self.write_error = None
        self.written = bytearray()
        self.writes = []  # (buf, off, n) of each write() call
        self.closed = False

    def fileno(self):
        return 99

    def readinto(self, buf):
        if self.read_error:
            raise OSError(self.read_error)
        n = min(len(buf), len(self.data))
        for i in range(n):
            buf[i] = self.data[i]
        self.data = self.data[n:]
        return n

    def write(self, buf, off=0, n=None):  # as the unix port's: all it is given
        if n is None:
            n = len(buf) - off
        self.writes.append((buf, off, n))
        if self.write_error:
            raise OSError(self.write_error)
        self.written += buf[off : off + n]
        return n

    def close(self):
        self.closed = True


class Termios:
    """termios, with `refuse` naming the call that fails (ENOTTY on setraw, EINVAL else)."""

    B9600, B57600, B115200, TCSANOW = 13, 4097, 4098, 0

    def __init__(self):
        self.refuse = None

    def _call(self, name):
        if self.refuse == name:
            raise OSError(25 if name == "setraw" else errno.EINVAL)

    def setraw(self, fd):
        self._call("setraw")

    def tcgetattr(self, fd):
        self._call("tcgetattr")
        return [0, 0, 0, 0, 0, 0, [0] * 32]

    def tcsetattr(self, fd, when, attrs):
        self._call("tcsetattr")


class Select:
    """select: each poll reports POLLIN if `readable`, POLLOUT if `writable` (when
    registered for it), and POLLHUP if `hung_up` (always, as Linux does)."""

    POLLIN, POLLOUT, POLLERR, POLLHUP = 1, 4, 8, 16

    def __init__(self):
        self.readable = False
        self.writable = True
        self.hung_up = False

    def poll(self):
        return Poll(self)


class Poll:
    def __init__(self, select):
        self.select = select
        self.timeouts = []  # of each poll(), in ms

    def register(self, obj, mask):
        self.obj = obj
        self.mask = mask

    def poll(self, timeout):
        self.timeouts.append(timeout)
        s = self.select
        event = s.POLLHUP if s.hung_up else 0
        if s.readable:
            event |= self.mask & s.POLLIN
        if s.writable:
            event |= self.mask & s.POLLOUT
        return [(self.obj, event)] if event else []


def load_unix(termios, select):
    """Import boards/unix.py afresh against the stand-ins."""
    return fresh_import("unix", termios=termios, select=select)


def fds():
    return len(os.listdir("/proc/self/fd"))


class StandIns(unittest.TestCase):
    def setUp(self):
        self.termios = Termios()
        self.select = Select()
        self.file = File()
        self.unix = load_unix(self.termios, self.select)
        self.sysfs = {}  # path: what it reads (the rest of the system's files: none)

        def opened(path, mode="r"):  # found before the builtin
            if path == "/dev/ttyUSB0":
                return self.file
            if path in self.sysfs:
                return io.StringIO(self.sysfs[path])
            raise OSError(errno.ENOENT, path)

        self.unix.open = opened

    def assertHangUp(self, call, *args):
        try:
            call(*args)
        except OSError as e:
            self.assertEqual(e.args[0], errno.EIO)
            self.assertIn("/dev/ttyUSB0", str(e))
            self.assertIn("hung up", str(e))
        else:
            self.fail("no hang-up from %r" % (call,))

    def test_a_read_that_fails_with_eio_is_a_hang_up_that_names_the_device(self):
        uart = self.unix.uart("/dev/ttyUSB0")
        self.select.readable = True
        self.file.read_error = errno.EIO
        self.assertHangUp(uart.any)
        self.assertHangUp(uart.read)
        self.assertHangUp(uart.readinto, bytearray(4))

    def test_a_write_that_fails_with_eio_is_a_hang_up_that_names_the_device(self):
        uart = self.unix.uart("/dev/ttyUSB0")
        self.file.write_error = errno.EIO
        self.assertHangUp(uart.write, BATTERY)
        self.assertHangUp(uart.write, BATTERY, 2)
        self.assertHangUp(uart.write, BATTERY, 1, 2)

    def test_other_errors_are_left_as_they_are(self):
        uart = self.unix.uart("/dev/ttyUSB0")
        self.select.readable = True
        self.file.read_error = self.file.write_error = errno.EBADF
        for call, args in ((uart.any, ()), (uart.write, (BATTERY,))):
            try:
                call(*args)
            except OSError as e:
                self.assertEqual(e.args[0], errno.EBADF)
            else:
                self.fail("no OSError")

    def test_pollhup_is_a_hang_up_in_every_call(self):
        uart = self.unix.uart("/dev/ttyUSB0")
        self.select.hung_up = True
        for call, args in (
            (uart.any, ()),
            (uart.read, ()),
            (uart.read, (1,)),
            (uart.readinto, (bytearray(4),)),
            (uart.readinto, (bytearray(4), 1)),
            (uart.write, (BATTERY,)),
            (uart.write, (BATTERY, 1)),
            (uart.write, (BATTERY, 1, 2)),
        ):
            self.assertHangUp(call, *args)
        self.assertEqual(self.file.writes, [])

    def test_readable_yet_nothing_to_read_is_a_hang_up(self):
        uart = self.unix.uart("/dev/ttyUSB0")
        self.select.readable = True  # and no data: as a hung-up tty reads
        self.assertHangUp(uart.any)

    def test_write_hands_the_forms_to_the_file_unsliced(self):
        uart = self.unix.uart("/dev/ttyUSB0")
        frame = b"xx" + BATTERY + b"yy"
        self.assertEqual(uart.write(frame, 2, 4), 4)
        self.assertEqual(uart.write(BATTERY), 4)
        self.assertEqual(uart.write(BATTERY, 3), 3)
        self.assertEqual(uart.write(BATTERY, 3, 100), 1)  # n clamped to what is left
        self.assertEqual(uart.write(bytes(300)), 256)  # what Linux has room for, at most
        self.assertEqual(
            [(off, n) for _, off, n in self.file.writes],
            [(2, 4), (0, 4), (0, 3), (3, 1), (0, 256)],
        )
        self.assertTrue(self.file.writes[0][0] is frame)  # no copy
        self.assertEqual(self.file.written[:12], frame[2:6] + BATTERY + BATTERY[:3] + BATTERY[3:])

    def test_write_of_nothing_is_0_and_unwritable_is_none(self):
        uart = self.unix.uart("/dev/ttyUSB0")
        self.assertEqual(uart.write(BATTERY, 50, 4), 0)  # off clamped to len(buf)
        self.assertEqual(uart.write(BATTERY, 4, 1), 0)
        self.assertEqual(uart.write(BATTERY, 0), 0)
        self.assertEqual(uart.write(b""), 0)
        self.select.writable = False
        self.assertIsNone(uart.write(BATTERY))
        self.assertEqual(self.file.writes, [])

    def test_how_late_its_bytes_may_come(self):
        # A USB-serial adapter: its FTDI's latency timer where Linux says it, else as long
        # as an FTDI's default (16 ms), and what a busy computer adds (20 ms).
        self.assertEqual(self.unix.uart("/dev/ttyUSB0").latency_ms, 16 + 20)
        self.sysfs["/sys/bus/usb-serial/devices/ttyUSB0/latency_timer"] = "1\n"
        self.assertEqual(self.unix.uart("/dev/ttyUSB0").latency_ms, 1 + 20)

    def test_wait_waits_in_the_os_until_bytes_come(self):
        # What a blocking query does between its looks: poll() for up to ms, or nothing when
        # bytes wait already.
        uart = self.unix.uart("/dev/ttyUSB0")
        reads = uart._in
        reads.timeouts.clear()
        uart.wait(2)
        self.assertEqual(reads.timeouts, [2])
        self.select.readable = True
        self.file.data = BATTERY_7500
        self.assertEqual(uart.any(), 6)
        reads.timeouts.clear()
        uart.wait(2)
        self.assertEqual(reads.timeouts, [])

    def test_readinto_clamps_to_the_buffer(self):
        uart = self.unix.uart("/dev/ttyUSB0")
        self.file.data = BATTERY_7500
        self.select.readable = True
        buf = bytearray(4)
        self.assertEqual(uart.readinto(buf, 100), 4)
        self.assertEqual(buf, BATTERY_7500[:4])
        self.assertEqual(uart.readinto(buf, 1), 1)
        self.assertEqual(uart.read(), BATTERY_7500[5:])
        self.assertEqual(len(buf), 4)

    def test_a_device_that_refuses_its_settings_is_closed_and_named(self):
        for refuse, says in (
            ("setraw", "is not a serial device"),
            ("tcgetattr", "is not a serial device"),
            ("tcsetattr", "cannot set 9600 baud"),
        ):
            self.file = File()
            self.termios.refuse = refuse
            try:
                self.unix.uart("/dev/ttyUSB0")
            except OSError as e:
                self.assertIn("/dev/ttyUSB0", str(e))
                self.assertIn(says, str(e))
            else:
                self.fail("%s refused, no OSError" % refuse)
            self.assertTrue(self.file.closed, refuse)


class NoTty(unittest.TestCase):
    def test_what_is_no_tty_is_refused_and_its_descriptor_given_back(self):
        from unix import uart

        path = scratch("no-tty")
        with open(path, "w") as f:
            f.write("x")
        try:
            for name in (path, "/dev/null"):  # a file, a character device
                before = fds()
                try:
                    uart(name)
                except OSError as e:
                    self.assertIn(name, str(e))
                    self.assertIn("not a serial device", str(e))
                else:
                    self.fail("%s taken for a serial device" % name)
                self.assertEqual(fds(), before, name)
        finally:
            os.remove(path)

    def test_a_number_is_no_path_and_nothing_is_opened(self):
        # uart(0), a board's UART(0) habit: open(0) would be this process's own terminal,
        # put in raw mode. Anything but a path string is refused before anything is opened.
        unix = load_unix(Termios(), Select())
        opened = []
        unix.open = lambda path, mode: opened.append(path)
        for bad in (0, 2, b"/dev/ttyUSB0", None):
            try:
                unix.uart(bad)
            except TypeError as e:
                self.assertIn("path", str(e))
                self.assertIn("/dev/ttyUSB0", str(e))
                self.assertIn(repr(bad), str(e))
            else:
                self.fail("uart(%r) was taken" % (bad,))
        self.assertEqual(opened, [])


class SimPty(unittest.TestCase):
    # The simulated controller behind a pty, its server then stopped: the pty's
    # other side closes, as when a USB-serial adapter is unplugged.

    def setUp(self):
        self.link = scratch("pty")
        self.pid = start("sh boards/unix.sh --sim-pty --link " + self.link, self.link + ".log")
        self.assertTrue(wait_for(self.link), "the simulator did not start")
        from unix import uart

        self.uart = uart(self.link)

    def tearDown(self):
        self.uart.close()
        stop(self.pid)
        os.system("rm -f %s %s.log" % (self.link, self.link))

    def test_a_pty_is_at_any_pace_and_a_query_waits_for_it(self):
        # Through a link to it, as --link makes: its far end writes when its program runs,
        # so no pause tells the driver anything (latency_ms None).
        import busservo

        self.assertIsNone(self.uart.latency_ms)
        bus = busservo.BusServo(self.uart)
        self.assertEqual(bus.read_battery(1000), 7500)
        self.assertEqual(bus.read_positions([1, 2, 3, 4, 5, 6], 1000)[6], 500)

    def test_a_hang_up_raises_eio_from_every_call_at_once(self):
        uart = self.uart
        self.assertEqual(uart.write(BATTERY), 4)
        start_ms = time.ticks_ms()
        got = b""  # the reply comes a byte at a time, at 9600 baud
        while len(got) < 6 and time.ticks_diff(time.ticks_ms(), start_ms) < 5000:
            got += uart.read() or b""
            time.sleep_ms(1)
        self.assertEqual(got, BATTERY_7500)
        stop(self.pid)
        start_ms = time.ticks_ms()
        error = None
        while error is None and time.ticks_diff(time.ticks_ms(), start_ms) < 5000:
            try:
                uart.any()
            except OSError as e:
                error = e
        self.assertIsNotNone(error, "no hang-up noticed in 5 s")
        self.assertTrue(time.ticks_diff(time.ticks_ms(), start_ms) < 2000)
        buf = bytearray(4)
        for call, args in (
            (uart.any, ()),
            (uart.read, ()),
            (uart.readinto, (buf,)),
            (uart.readinto, (buf, 1)),
            (uart.write, (BATTERY,)),
            (uart.write, (BATTERY, 2)),
            (uart.write, (BATTERY, 1, 2)),
        ):
            try:
                call(*args)
            except OSError as e:
                self.assertEqual(e.args[0], errno.EIO)
                self.assertIn(self.link, str(e))
                self.assertIn("hung up", str(e))
            else:
                self.fail("no hang-up from %r%r" % (call, args))


# A pty nobody reads: its server holds both ends for 5 s, reading nothing.
UNREAD_PTY = (
    ".venv/bin/python -c 'import os, sys, time, tty; m, s = os.openpty(); tty.setraw(s); "
    "os.symlink(os.ttyname(s), sys.argv[1]); time.sleep(5)' "
)


class UnreadPty(unittest.TestCase):
    def setUp(self):
        self.link = scratch("unread")
        self.pid = start(UNREAD_PTY + self.link, self.link + ".log")
        self.assertTrue(wait_for(self.link), "the pty did not come")
        from unix import uart

        self.uart = uart(self.link)

    def tearDown(self):
        self.uart.close()
        stop(self.pid)
        os.system("rm -f %s %s.log" % (self.link, self.link))

    def test_writes_take_what_fits_then_none_and_never_wait(self):
        # A blocking write would wait here until the server exits (5 s).
        data = bytes(1000)
        took = 0
        start_ms = time.ticks_ms()
        for _ in range(1000):  # up to 256 KB: far more than a pty holds
            n = self.uart.write(data)
            if n is None:
                break
            self.assertTrue(0 < n <= len(data), n)
            took += n
        else:
            self.fail("a pty nobody reads took it all")
        self.assertTrue(took > 0)
        self.assertIsNone(self.uart.write(data, 10, 5))  # still full
        self.assertTrue(time.ticks_diff(time.ticks_ms(), start_ms) < 1000)


class APtyThatAnswersAtOnce(unittest.TestCase):
    # A controller on a pty that answers the moment a request is in (tests/pty_peer.py), as a
    # simulator a user writes does: no line between, so every reply comes sooner than 9600
    # baud allows. Nothing else can be its answer: the driver takes it.
    def setUp(self):
        self.link = scratch("peer")
        self.pid = start(".venv/bin/python tests/pty_peer.py " + self.link, self.link + ".log")
        self.assertTrue(wait_for(self.link), "the peer did not start")
        from unix import uart

        self.uart = uart(self.link)

    def tearDown(self):
        self.uart.close()
        stop(self.pid)
        os.system("rm -f %s %s.log" % (self.link, self.link))

    def test_queries_are_answered(self):
        import busservo

        bus = busservo.BusServo(self.uart)
        for _ in range(3):
            self.assertEqual(bus.read_battery(timeout_ms=1000), 7500)
            self.assertEqual(bus.read_positions([1, 2], timeout_ms=1000), {1: 500, 2: 500})
        self.assertTrue(bus.early > 0, bus.early)


if __name__ == "__main__":
    unittest.main()
