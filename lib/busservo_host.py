# busservo_host: the controller on a computer's serial port (CPython and pyserial), and the
# `busservo` command. The controller's USB port is a USB-serial chip: plugged into a laptop
# or a Raspberry Pi it is /dev/ttyUSB0 (Linux), /dev/cu.usbserial-... (macOS) or COM3
# (Windows), and the driver talks to it as to a board's UART:
#
#   import busservo, busservo_host
#   bus = busservo.BusServo(busservo_host.serial_port("/dev/ttyUSB0"))
#   busservo_host.ports()      # [(port, description)]: which one is the controller
#
# serial_port() opens the port at 9600 8N1 and gives the UART methods the driver uses, as
# MicroPython's ports have them: any(), readinto() and write() never wait (write() takes
# what the OS has room for, and says how much). What goes wrong is an OSError that says it
# in words: no such port (ENOENT), in use by another program (EBUSY), no permission
# (EACCES), gone, unplugged mid-command (ENODEV).
import errno
import os
import sys
import time

BAUDRATE = 9600
# The command's queries wait this long for an answer: USB adds its latency to the wire's
# (an adapter's own timer, 16 ms on an FTDI; a busy computer), and a command is no control loop.
_TIMEOUT_MS = 500


def _serial():
    try:
        import serial
    except ImportError:
        raise OSError(
            errno.ENOENT, "pyserial is not installed: pip install . (or pip install pyserial)"
        )
    return serial


def _why(e):
    # SerialException's errno, else the one its words name (Windows gives only words).
    if getattr(e, "errno", None):
        return e.errno
    text = str(e).lower()
    if "filenotfound" in text or "cannot find" in text or "no such" in text:
        return errno.ENOENT
    if "access is denied" in text or "permission" in text:
        return errno.EBUSY if sys.platform == "win32" else errno.EACCES
    return errno.EIO


def _open_error(path, e):
    code = _why(e)
    if code == errno.ENOENT:
        return OSError(code, "no such port %s (busservo ports lists those there are)" % path)
    if code in (errno.EBUSY, errno.EAGAIN, errno.EWOULDBLOCK):
        return OSError(
            errno.EBUSY, "%s is busy: another program has it open (close it first)" % path
        )
    if code == errno.EACCES:
        return OSError(
            code,
            "no permission to open %s (on Linux: sudo usermod -aG dialout $USER, then log in "
            "again)" % path,
        )
    return OSError(code, "could not open %s: %s" % (path, e))


class SerialUART:
    """A pyserial port with machine.UART's any/read/readinto/write, as the driver uses them."""

    def __init__(self, port, path):
        self._port = port
        self.path = path
        # POSIX: the port's file is non-blocking (pyserial opens it so): a write takes what
        # fits and says how much, as a board's UART does. pyserial's own write() would wait.
        self._fd = port.fileno() if hasattr(os, "O_NONBLOCK") else None

    def _gone(self, e):
        self.close()
        return OSError(errno.ENODEV, "the port %s is gone (unplugged?): %s" % (self.path, e))

    def any(self):
        try:
            return self._port.in_waiting
        except Exception as e:  # OSError (EIO) from the ioctl, or pyserial's
            raise self._gone(e)

    def readinto(self, buf, nbytes=-1):
        n = len(buf) if nbytes < 0 or nbytes > len(buf) else nbytes
        try:
            data = self._port.read(n)  # timeout=0: what has come, at once
        except Exception as e:
            raise self._gone(e)
        got = len(data)
        buf[:got] = data
        return got or None

    def read(self, nbytes=-1):
        buf = bytearray(self.any() if nbytes < 0 else nbytes)
        got = self.readinto(buf) if buf else 0
        return bytes(buf[:got]) if got else None

    def write(self, buf, off=None, nbytes=None):
        # write(buf), write(buf, n), write(buf, off, n): MicroPython's stream write().
        if nbytes is None:
            data = memoryview(buf)[: off if off is not None else len(buf)]
        else:
            data = memoryview(buf)[off : off + nbytes]
        if not data:
            return 0
        try:
            if self._fd is None:
                return self._port.write(data) or None
            return os.write(self._fd, data) or None
        except BlockingIOError:
            return None  # no room: none of it taken, as a board's UART with timeout=0 says
        except Exception as e:
            if self._port.is_open:
                raise self._gone(e)
            raise OSError(errno.EBADF, "the port %s is closed" % self.path)

    def flush(self):
        self._port.flush()

    def close(self):
        try:
            self._port.close()
        except Exception:
            pass

    deinit = close

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self):
        return "<busservo_host.SerialUART %s>" % self.path


def serial_port(path, baudrate=BAUDRATE):
    """The serial port at path (/dev/ttyUSB0, COM3, ...), open at baudrate 8N1, for
    busservo.BusServo(). Raises OSError saying why it cannot be opened."""
    serial = _serial()
    try:
        port = serial.Serial(
            path,
            baudrate,
            bytesize=8,
            parity="N",
            stopbits=1,
            timeout=0,
            write_timeout=0,
            exclusive=True if os.name == "posix" else None,
        )
    except (serial.SerialException, OSError, ValueError) as e:
        raise _open_error(path, e)
    return SerialUART(port, path)


# USB-serial chips seen on these controllers' boards, first in ports()'s list.
_CHIPS = {
    (0x1A86, 0x7523): "CH340",
    (0x1A86, 0x55D4): "CH9102",
    (0x10C4, 0xEA60): "CP210x",
    (0x0403, 0x6001): "FT232",
}


def ports():
    """The serial ports there are, [(port, description)], the USB ones first: the
    controller is one of them (unplug it and look again to see which)."""
    from serial.tools import list_ports

    found = []
    for p in list_ports.comports():
        usb = p.vid is not None
        what = p.description or "n/a"
        if usb:
            chip = _CHIPS.get((p.vid, p.pid))
            what = "%s (USB %04X:%04X%s)" % (what, p.vid, p.pid, ", " + chip if chip else "")
        found.append((not usb, p.device, what))
    return [(device, what) for _, device, what in sorted(found)]


# The command line: busservo ports | check PORT | positions PORT ID... | move PORT ID POS MS |
# panel PORT --password P [--port N]. PORT --sim is the simulated controller.

_CHECKED = "--i-have-checked-my-robot"
_USAGE = """usage: busservo COMMAND ...
  busservo ports                       the serial ports, the USB ones first
  busservo check PORT                  the wiring check: the battery and the round trip
  busservo positions PORT ID [ID...]   the positions of servos ID...
  busservo move PORT ID POS MS [%s]
                                       move servo ID to POS (0..1000) over MS ms
  busservo panel PORT --password P [--port N] [%s]
                                       the browser panel, at http://127.0.0.1:N/ (8080)
PORT is /dev/ttyUSB0, COM3, ... or --sim for the simulated controller (nothing real moves).
Anything that moves asks for %s: check first that the servos can turn freely,
with nothing in their way.""" % (_CHECKED, _CHECKED, _CHECKED)


class _Usage(Exception):
    pass


def _bus(port):
    import busservo

    if port == "--sim":
        import busservo_sim

        return busservo.BusServo(busservo_sim.SimController()), True
    return busservo.BusServo(serial_port(port)), False


def _int(text, what, low, high):
    try:
        value = int(text)
    except ValueError:
        value = None
    if value is None or not low <= value <= high:
        raise _Usage("%s must be a number in %d..%d, got %r" % (what, low, high, text))
    return value


def _check(port):
    bus, _ = _bus(port)
    start = time.monotonic()
    try:
        mv = bus.read_battery(_TIMEOUT_MS)
    except OSError as e:
        if e.errno != errno.ETIMEDOUT:
            raise
        print("no answer from the controller on %s within %d ms. Check:" % (port, _TIMEOUT_MS))
        print("1. the controller is powered: battery charged, switch on, its LED lit")
        print("2. PORT is the controller's (busservo ports; unplug it and look again)")
        print("3. its USB cable carries data (some carry power only)")
        return 1
    took = time.monotonic() - start
    print("battery: %.2f V" % (mv / 1000))
    print(
        "round trip: %.1f ms (about 10.4 ms on the wire at 9600 baud, plus USB's)" % (took * 1000)
    )
    if bus.noise:
        print("%d bytes came that made no frame: the baud rate, or another program" % bus.noise)
        return 1
    return 0


def _positions(port, ids):
    ids = [_int(i, "an id", 0, 254) for i in ids]
    if not ids:
        raise _Usage("positions wants one id or more")
    bus, _ = _bus(port)
    read = bus.read_positions(ids, _TIMEOUT_MS)
    for i in ids:
        print("%d: %s" % (i, "no answer" if read[i] is None else read[i]))
    return 1 if None in read.values() else 0


def _move(port, args):
    checked = _CHECKED in args
    args = [a for a in args if a != _CHECKED]
    if len(args) != 3:
        raise _Usage("move wants ID POS MS")
    servo_id = _int(args[0], "ID", 0, 254)
    position = _int(args[1], "POS", 0, 1000)
    ms = _int(args[2], "MS", 0, 30000)
    bus, simulated = _bus(port)
    now = bus.read_positions([servo_id], _TIMEOUT_MS)[servo_id]
    if now is None:
        print("servo %d does not answer: its power, the bus cable, its id" % servo_id)
        return 1
    print("servo %d is at %d; this moves it to %d over %d ms" % (servo_id, now, position, ms))
    if not (checked or simulated):
        print(
            "nothing moved: check that servo %d can turn freely, then add %s"
            % (servo_id, _CHECKED)
        )
        return 1
    bus.move(servo_id, position, ms)
    time.sleep(ms / 1000 + 0.05)
    print("servo %d is at %d" % (servo_id, bus.read_positions([servo_id], _TIMEOUT_MS)[servo_id]))
    return 0


def _panel(port, args):
    import asyncio

    import busservo_board
    import busservo_motion as bm
    import busservo_web

    checked = _CHECKED in args
    args = [a for a in args if a != _CHECKED]
    options = {"--password": None, "--port": "8080"}
    while args:
        name = args.pop(0)
        if name not in options or not args:
            raise _Usage("panel takes --password P and --port N, got %r" % name)
        options[name] = args.pop(0)
    key = options["--password"]
    if not key or len(key) < 8:
        raise _Usage("panel wants --password P, of 8 characters or more")
    tcp = _int(options["--port"], "--port", 1, 65535)
    # The page beside busservo_web, in the computer's own way of writing paths.
    busservo_web._PAGE = os.path.join(
        os.path.dirname(os.path.abspath(busservo_web.__file__)), "busservo_web.html.gz"
    )
    bus, simulated = _bus(port)
    dps = None if simulated else 30
    robot = busservo_board.robot(
        bus,
        {
            "base": bm.Joint(1, dps=dps),
            "shoulder": bm.Joint(2, limits=(-90, 90), dps=dps),
            "elbow": bm.Joint(3, limits=(-90, 90), dps=dps),
            "claw": bm.Joint(4, limits=(0, 60), dps=dps),
        },
    )
    ids = [robot.joints[name].servo_id for name in robot.names]
    print("the servos are at", bus.read_positions(ids, _TIMEOUT_MS))
    if not (checked or simulated):
        print("nothing moved: the panel moves servos %s; check that they can turn freely," % ids)
        print("then add " + _CHECKED)
        return 1
    robot.where()

    async def serve():
        task = asyncio.ensure_future(busservo_web.serve(robot, key, tcp))
        await asyncio.sleep(0.2)
        if not task.done():
            print("open http://127.0.0.1:%d/ and log in with the password %r" % (tcp, key))
            print("(Ctrl-C stops the panel)", flush=True)
        await task

    try:
        asyncio.run(serve())
    except OSError as e:
        if e.errno not in (errno.EADDRINUSE, getattr(errno, "WSAEADDRINUSE", 0)):
            raise
        print("port %d is in use (another panel?): give another with --port N" % tcp)
        return 1
    finally:
        robot.hold()
    return 0


def main(argv=None):
    """The `busservo` command: returns its exit status (0 done, 1 failed, 2 bad usage)."""
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        if not args or args[0] in ("-h", "--help", "help"):
            print(_USAGE)
            return 0 if args else 2
        command = args.pop(0)
        if command == "ports":
            found = ports()
            for device, what in found:
                print("%s  %s" % (device, what))
            if not found:
                print("no serial ports: plug the controller's USB cable in (a data cable)")
            return 0
        if command not in ("check", "positions", "move", "panel"):
            raise _Usage("no command %r" % command)
        if not args:
            raise _Usage("%s wants a PORT (busservo ports lists them; --sim: simulated)" % command)
        port = args.pop(0)
        if command == "check":
            if args:
                raise _Usage("check takes PORT only")
            return _check(port)
        if command == "positions":
            return _positions(port, args)
        if command == "move":
            return _move(port, args)
        return _panel(port, args)
    except _Usage as e:
        print("busservo: %s (busservo --help)" % e, file=sys.stderr)
        return 2
    except OSError as e:
        if e.errno == errno.ETIMEDOUT:
            why = "the controller did not answer in time"
        else:
            why = e.strerror if e.strerror and len(e.args) > 1 else str(e)
        print("busservo: %s" % why, file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130


def _entry():
    sys.exit(main())


if __name__ == "__main__":
    _entry()
