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
# what the OS has room for, and says how much). It also says how its bytes come, for the
# driver's timing (latency_ms: a USB-serial chip hands them over every few ms, a busy
# computer later still; None on a pty, at any pace), and waits in the OS for them (wait(ms)),
# so that a query costs no CPU while it waits. What goes wrong is an OSError that says it
# in words: no such port (ENOENT), in use by another program (EBUSY), no permission
# (EACCES), a file or a folder, not a serial port (ENOTTY), gone, unplugged mid-command
# (ENODEV).
#
# The `busservo` command (main(), below) is this module too: `busservo --help` says it.
import errno
import io
import os
import re
import select
import sys
import time

import busservo_cpython
from busservo_cpython import BUSY_MS  # a busy computer's lateness, which latency_ms counts

BAUDRATE = 9600
# How often a USB-serial chip hands the bytes it took off the wire over to the computer, by
# its USB vendor id: an FTDI when its latency timer runs out (16 ms by default; on Linux
# /sys/bus/usb-serial/devices/ttyUSB0/latency_timer says it), a CH340 or CH9102 every few ms.
# An unknown chip counts as an FTDI.
_HAND_OVER_MS = {0x0403: 16, 0x1A86: 4}
_UNKNOWN_CHIP_MS = 16


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
    if "inappropriate ioctl" in text:  # pyserial's "Could not configure port": no tty
        return errno.ENOTTY
    return errno.EIO


def _not_a_port(path, what="a serial port"):
    return OSError(
        errno.ENOTTY, "%s is not %s (busservo ports lists those there are)" % (path, what)
    )


def _open_error(path, e):
    code = _why(e)
    if code == errno.ENOENT:
        return OSError(code, "no such port %s (busservo ports lists those there are)" % path)
    if code in (errno.EBUSY, errno.EAGAIN, errno.EWOULDBLOCK):
        return OSError(
            errno.EBUSY, "%s is busy: another program has it open (close it first)" % path
        )
    if code in (errno.ENOTTY, errno.EISDIR):
        return _not_a_port(path)
    if code == errno.EACCES:
        return OSError(
            code,
            "no permission to open %s (on Linux: sudo usermod -aG dialout $USER, then log in "
            "again)" % path,
        )
    return OSError(code, "could not open %s: %s" % (path, e))


class SerialUART(busservo_cpython.UART):
    """A pyserial port with machine.UART's any/read/readinto/write, as the driver uses them."""

    def __init__(self, port, path, latency_ms=None):
        self._port = port
        self.path = path
        # How much later than the wire its bytes may come, ms (None: at any pace): read by
        # busservo.BusServo() when it is made (latency_ms(), below).
        self.latency_ms = latency_ms
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

    def write(self, buf, off=None, nbytes=None):
        data = busservo_cpython.written(buf, off, nbytes)  # MicroPython's stream forms
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

    def wait(self, ms):
        """Wait until bytes have come, or ms have passed, in the OS: what a blocking query
        does between its looks at the port (busservo's _run), so that it costs no CPU."""
        if self._fd is None:  # Windows: no select() on a serial port
            time.sleep(ms / 1000)
        else:
            select.select([self._fd], [], [], ms / 1000)

    def flush(self):
        self._port.flush()

    def close(self):
        try:
            self._port.close()
        except Exception:
            pass

    def __repr__(self):
        return "<busservo_host.SerialUART %s>" % self.path


def serial_port(path, baudrate=BAUDRATE):
    """The serial port at path (/dev/ttyUSB0, COM3, ...), open at baudrate 8N1, for
    busservo.BusServo(). Raises OSError saying why it cannot be opened."""
    serial = _serial()
    if os.path.isdir(path):
        raise _not_a_port(path, "a serial port but a folder")
    if os.path.isfile(path):
        raise _not_a_port(path, "a serial port but a file")
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
    return SerialUART(port, path, latency_ms(path))


def latency_ms(path):
    """How much later than the wire the controller's bytes may reach a program reading the
    serial port at path, in ms, as busservo's driver counts it (a port's latency_ms): a
    USB-serial chip's hand-over period (an FTDI's latency timer, as Linux says it; else by the
    chip's USB vendor id) and BUSY_MS for a busy computer; BUSY_MS for a port with no USB
    (the bytes come as the wire paces them); None for a pty, whose far end writes at any
    pace."""
    real = os.path.realpath(path)
    if real.startswith("/dev/pts/") or re.match(r"/dev/ttys\d", real):  # Linux, macOS
        return None
    name = os.path.basename(real)
    try:
        with open("/sys/bus/usb-serial/devices/%s/latency_timer" % name) as f:
            return int(f.read()) + BUSY_MS
    except (OSError, ValueError):
        pass  # not Linux, or not a chip with a latency timer: by its vendor id
    try:
        from serial.tools import list_ports

        found = [p for p in list_ports.comports() if p.device in (path, real)]
    except Exception:  # listing the ports is a nicety here: never a reason to fail
        found = []
    if not found or found[0].vid is None:
        return BUSY_MS if found else _UNKNOWN_CHIP_MS + BUSY_MS
    return _HAND_OVER_MS.get(found[0].vid, _UNKNOWN_CHIP_MS) + BUSY_MS


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
    _serial()  # says pyserial is not installed, if it is not
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


# The command line: `busservo COMMAND PORT ...`, as _USAGE says. PORT --sim is the simulated
# controller; hid and hid:PATH a USB HID controller (busservo_hid, pip install ".[hid]").

_CHECKED = "--i-have-checked-my-robot"
_USAGE = """usage: busservo COMMAND ...
  busservo ports                       the controller's ports: serial (the USB ones first), HID
  busservo check PORT                  the wiring check: the battery and the round trip
  busservo scan PORT                   the servos that answer (ids 0..253), and where they are
  busservo positions PORT ID [ID...]   the positions of servos ID... (84 at most, 59 on HID)
  busservo move PORT ID POS MS [%(checked)s]
                                       move servo ID to POS (0..1000) over MS ms; Ctrl-C
                                       stops it where it is
  busservo limp PORT ID [ID...] [%(checked)s]
                                       servos ID... go limp (unload), to be turned by hand:
                                       what they hold up falls; each holds again when moved
  busservo group PORT N [TIMES] [%(checked)s]
                                       run the controller's action group N (0..255) TIMES
                                       times (once; 0: until stopped); Ctrl-C stops it
  busservo stop PORT                   stop the action group that runs
  busservo panel PORT --password P [--port N] [--host H] [%(checked)s]
                                       the browser panel, at http://127.0.0.1:N/ (8080), on
                                       every interface or H's (--host 127.0.0.1: this one)
  busservo record PORT FILE [--seconds S] [%(checked)s]
                                       the joints go limp: move the arm by hand; records
                                       until Ctrl-C (or S seconds) into FILE, whose name
                                       ends in .rec (the compact form) or .jsonl (JSON lines)
  busservo play PORT FILE [--speed X] [%(checked)s]
                                       play a recording: into its first pose at 30
                                       degrees/s, then at its pace, X times (0.25..2, 1);
                                       Ctrl-C stops it where it is
  busservo teleop LEADER [FOLLOWER] --leader-calibration F1
                  --follower-calibration F2 [--record FILE] [%(checked)s]
                                       the leader arm, limp, moved by hand, drives the
                                       follower live (each arm's robot.json: F1, F2); one
                                       PORT: both arms on its bus; Ctrl-C stops it; with
                                       --record, each read of the leader goes into FILE too;
                                       on --sim without F1 and F2: the demo's arm on servos
                                       1..4 leads the same arm on servos 7..10
  busservo --version                   busservo's version
PORT is /dev/ttyUSB0, COM3, ... (a serial port), hid or hid:PATH (a USB HID controller: the
first found, or that one), or --sim: a simulated controller, servos 1..6 (nothing real moves).
The robot is the calibration in robot.json, in the folder you run from, else the demo's arm.
--json: ports, check, scan, positions and move print JSON (and their words to stderr).
--timeout MS: how long each query waits for its answer (500 ms, and 10 ms more an id).
Anything that moves or goes limp asks for %(checked)s: check first that the
servos can turn freely, with nothing in their way, and hold an arm that goes limp (it falls).
Without it the command says what it would do, moves nothing and ends with exit status 1.
Ctrl-C ends record (exit status 0) and stops the others (130); so do SIGTERM and SIGHUP.""" % {
    "checked": _CHECKED
}

# What each command takes besides its words (--i-have-checked-my-robot: all of them).
_TAKES = {
    "ports": ("--json",),
    "check": ("--json", "--timeout"),
    "scan": ("--json", "--timeout"),
    "positions": ("--json", "--timeout"),
    "move": ("--json", "--timeout"),
    "limp": ("--timeout",),
    "group": ("--timeout",),
    "stop": ("--timeout",),
    "panel": ("--password", "--port", "--host", "--timeout"),
    "record": ("--seconds", "--timeout"),
    "play": ("--speed",),
    "teleop": ("--leader-calibration", "--follower-calibration", "--timeout", "--record"),
}
_VALUED = {
    "--password": "P",
    "--port": "N",
    "--host": "H",
    "--timeout": "MS",
    "--seconds": "S",
    "--speed": "X",
    "--leader-calibration": "F1",
    "--follower-calibration": "F2",
    "--record": "FILE",
}
_FLAGS = ("--json", _CHECKED, "-h", "--help", "-V", "--version")
# The command's queries wait this long for an answer (and _PER_ID_MS more a servo asked, for
# the wire's 4 more bytes and the servo the controller asks): USB adds its latency to the
# wire's (an adapter's own timer, 16 ms on an FTDI; a busy computer), and a command is no
# control loop.
_TIMEOUT_MS = 500
_PER_ID_MS = 10
_IDS_MAX = 84  # positions one query may ask for: the reply must fit in a Length byte
_HID_IDS_MAX = 59  # and on a HID controller: the request must fit in a report (busservo_hid)
# Ids a scan asks for at a time: 6 queries; each request fits in a HID controller's report too
# (64 bytes: 59 ids at most; busservo_hid refuses a longer frame).
_SCAN_IDS = 50
_UNLOAD_MAX = 252  # servos one unload may name
_HALT_MS = 100  # a move stopped by Ctrl-C: the servo goes where it is in this, as the panel's
# The panel's joints on a real controller turn no faster (degrees a second): a slider dragged
# fast would whip the arm.
_PANEL_DPS = 30
_ANY_HOST = "0.0.0.0"
_SIM_SERVOS = range(1, 7)  # the servos on --sim's bus


class _Usage(Exception):
    pass


class _BadFile(Exception):
    pass


class _Run:
    """One command's PORT and options, and where it writes: words for people on stdout, or
    with --json the JSON on stdout and the words on stderr."""

    def __init__(self, options):
        self.json = "--json" in options
        self.timeout = None
        if "--timeout" in options:
            self.timeout = _int(options["--timeout"], "--timeout", 1, 60000)
        self.port = None
        self.uarts = []  # the ports, once open: main() closes them
        self.waited = _TIMEOUT_MS  # the last query's timeout, for the words when it ran out
        self.said = False  # the JSON line is printed (--json: one a command)

    def ms(self, ids=0):
        """A query's timeout, for the positions of ids servos (0: the battery)."""
        self.waited = self.timeout or _TIMEOUT_MS + _PER_ID_MS * ids
        return self.waited

    def say(self, *words):
        print(*words, file=sys.stderr if self.json else sys.stdout, flush=True)

    def result(self, value):
        if self.json:
            import json

            print(json.dumps(value))
            self.said = True

    def fail(self, why):
        """A command that failed: why, in words (stderr with --json), and with --json a line
        {"error": why} on stdout, unless the command printed its JSON already."""
        self.say(why)
        if self.json and not self.said:
            self.result({"error": why})


def _parse(args):
    # The words (the command, PORT, numbers) and the options {name: value or True}.
    words, options = [], {}
    while args:
        arg = args.pop(0)
        if arg in _VALUED:
            if not args:
                raise _Usage("%s wants a value: %s %s" % (arg, arg, _VALUED[arg]))
            options[arg] = args.pop(0)
        elif arg in _FLAGS:
            options[arg] = True
        elif arg[:1] == "-" and arg != "--sim" and not arg[1:].isdigit():
            raise _Usage("no option %r" % arg)
        else:
            words.append(arg)
    return words, options


def _int(text, what, low, high):
    try:
        value = int(text)
    except ValueError:
        value = None
    if value is None or not low <= value <= high:
        raise _Usage("%s must be a number in %d..%d, got %r" % (what, low, high, text))
    return value


def _ids(words, what, high, port=None):
    ids = [_int(i, "an id", 0, 254) for i in words]
    if port and _is_hid(port) and len(ids) > _HID_IDS_MAX:
        raise _Usage(
            "%s wants 1..%d ids on a HID controller (its request fits in a 64-byte report), "
            "got %d" % (what, _HID_IDS_MAX, len(ids))
        )
    if not 1 <= len(ids) <= high:
        raise _Usage("%s wants 1..%d ids, got %d" % (what, high, len(ids)))
    return ids


def _hid():
    # busservo_hid (the USB HID controllers), or None where it is not installed.
    try:
        import busservo_hid
    except ImportError as e:
        if e.name != "busservo_hid":
            raise
        return None
    return busservo_hid


def _is_hid(port):
    # PORT names a USB HID controller: hid (the first) or hid:PATH.
    return port == "hid" or port.startswith("hid:")


def _open(port):
    """The UART for PORT: hid or hid:PATH a USB HID controller, else a serial port."""
    if _is_hid(port):
        hid = _hid()
        if hid is None:
            raise OSError(errno.ENOENT, "no busservo_hid module for %s: pip install ." % port)
        return hid.hid_port(port)
    return serial_port(port)


def _bus(run, port=None, servos=_SIM_SERVOS):
    # A BusServo on PORT (run.port, or port), and whether it is the simulated controller
    # (its servos: servos).
    import busservo

    port = port or run.port
    if port == "--sim":
        import busservo_sim

        sim = busservo_sim.SimController()
        sim.missing.update(i for i in range(256) if i not in servos)  # as a 6-servo arm
        return busservo.BusServo(sim), True
    uart = _open(port)
    run.uarts.append(uart)
    return busservo.BusServo(uart), False


def _checklist(run, out, e):
    # What a query that timed out says: the bytes that came, if any (the driver's words in
    # e: "no reply: N bytes came, M of them noise"), else the wiring's checklist.
    if e.strerror != "no reply":
        came, noise = [int(word) for word in e.strerror.split() if word.isdigit()]
        print(
            "no answer from the controller on %s within %d ms, though %d bytes came, %s"
            % (
                run.port,
                run.waited,
                came,
                "%d of them no frame: the controller at another baud rate than %d, or "
                "another program on the port" % (noise, BAUDRATE)
                if noise
                else "frames that answer nothing asked (another program asking it?)",
            ),
            file=out,
        )
        return
    print(
        "no answer from the controller on %s within %d ms. Check:" % (run.port, run.waited),
        file=out,
    )
    print("1. the controller is powered: battery charged, switch on, its LED lit", file=out)
    print("2. PORT is the controller's (busservo ports; unplug it and look again)", file=out)
    print("3. its USB cable carries data (some carry power only)", file=out)


def _answers(bus, run):
    # Ask the controller for its battery before a command it never answers: silence is the
    # checklist (raised), not "done". What came before the answer (a group's STOP meant for
    # the program before) is passed over.
    bus.read_battery(run.ms())
    while bus.poll() is not None:
        pass


def _where(bus, run, servo_id):
    # Where servo_id is, or None if it does not answer.
    return bus.read_positions([servo_id], run.ms(1))[servo_id]


def _ports(run, words, options):
    if words:
        raise _Usage("ports takes nothing more")
    hid = _hid()
    found = (hid.ports() if hid else []) + ports()
    run.result([{"port": port, "description": what} for port, what in found])
    for port, what in found:
        run.say("%s  %s" % (port, what))
    if not found:
        run.say(
            "no serial ports and no HID controllers: plug the controller's USB cable in "
            "(a data cable)"
        )
    return 0


def _check(run, words, options):
    if words:
        raise _Usage("check takes PORT only")
    bus, _ = _bus(run)
    if run.port == "hid":  # the first plugged in: which one it is
        run.say("the HID controller at %s" % run.uarts[-1].port)
    start = time.monotonic()
    mv = bus.read_battery(run.ms())  # silent: main() says the checklist, as for every command
    took = (time.monotonic() - start) * 1000
    run.result({"battery_mv": mv, "round_trip_ms": round(took, 1), "noise": bus.noise})
    run.say("battery: %.2f V" % (mv / 1000))
    run.say("round trip: %.1f ms (about 10.4 ms on the wire at 9600 baud, plus USB's)" % took)
    if bus.noise:
        run.say("%d bytes came that made no frame: the baud rate, or another program" % bus.noise)
        return 1
    return 0


def _positions(run, words, options):
    ids = _ids(words, "positions", _IDS_MAX, run.port)
    bus, _ = _bus(run)
    read = bus.read_positions(ids, run.ms(len(ids)))
    run.result({str(i): read[i] for i in ids})
    for i in ids:
        run.say("%d: %s" % (i, "no answer" if read[i] is None else read[i]))
    return 1 if None in read.values() else 0


def _scan(run, words, options):
    if words:
        raise _Usage("scan takes PORT only")
    bus, _ = _bus(run)
    found = {}
    for first in range(0, 254, _SCAN_IDS):
        ids = list(range(first, min(first + _SCAN_IDS, 254)))
        read = bus.read_positions(ids, run.ms(len(ids)))
        found.update((i, read[i]) for i in ids if read[i] is not None)
    run.result({str(i): found[i] for i in found})
    for i in found:
        run.say("%d: %s" % (i, found[i]))
    if not found:
        run.say(
            "no servo answers: their power (the controller's supply, not USB), the bus "
            "cables, each servo's id"
        )
        return 1
    return 0


def _move(run, words, options):
    if len(words) != 3:
        raise _Usage("move wants ID POS MS")
    servo_id = _int(words[0], "ID", 0, 254)
    position = _int(words[1], "POS", 0, 1000)
    ms = _int(words[2], "MS", 0, 30000)
    bus, simulated = _bus(run)
    now = _where(bus, run, servo_id)
    if now is None:
        run.fail("servo %d does not answer: its power, the bus cable, its id" % servo_id)
        return 1
    run.say("servo %d is at %d; this moves it to %d over %d ms" % (servo_id, now, position, ms))
    if not (_CHECKED in options or simulated):
        run.say(
            "nothing moved: check that servo %d can turn freely, then add %s"
            % (servo_id, _CHECKED)
        )
        return 1
    bus.move(servo_id, position, ms)
    try:
        time.sleep(ms / 1000 + 0.05)
    except KeyboardInterrupt:
        # Ctrl-C: stop it where it is (as the panel's STOP does), not where it was going.
        at = _where(bus, run, servo_id)
        if at is None:
            run.say("servo %d did not answer: it goes on to %d" % (servo_id, position))
        else:
            bus.move(servo_id, at, _HALT_MS)
            run.say("stopped: servo %d holds at %d" % (servo_id, at))
        return 130
    at = _where(bus, run, servo_id)
    run.result({"servo": servo_id, "from": now, "to": position, "at": at})
    if at is None:  # (its JSON, printed: "at": null)
        run.say("servo %d does not answer now: its power, the bus cable" % servo_id)
        return 1
    run.say("servo %d is at %d" % (servo_id, at))
    return 0


def _limp(run, words, options):
    ids = _ids(words, "limp", _UNLOAD_MAX, run.port)
    bus, simulated = _bus(run)
    _answers(bus, run)
    named = ", ".join(str(i) for i in ids)
    if not (_CHECKED in options or simulated):
        run.say("the servos are at", bus.read_positions(ids, run.ms(len(ids))))
        run.say("this lets servos %s go limp: what they hold up falls" % named)
        _unchecked(run)
        return 1
    bus.unload(ids)
    if len(ids) == 1:
        run.say("servo %d is limp: turn it by hand; it holds again when moved" % ids[0])
    else:
        run.say("servos %s are limp: turn them by hand; each holds again when moved" % named)
    return 0


def _unchecked(run):
    # What limp and record say without --i-have-checked-my-robot.
    run.say("nothing went limp: hold the arm (or rest it safely), check that nothing is in its")
    run.say("way, then add " + _CHECKED)


def _wait_for_group(bus, group, until):
    # The command byte of the controller's next RUN, STOP or COMPLETE frame (of group for
    # RUN and COMPLETE), or None once time.monotonic() passes until.
    import busservo

    while until is None or time.monotonic() < until:
        cmd = bus.poll()
        if cmd == busservo.CMD_ACTION_GROUP_STOP or (
            cmd in (busservo.CMD_ACTION_GROUP_RUN, busservo.CMD_ACTION_GROUP_COMPLETE)
            and bus.group == group
        ):
            return cmd
        if cmd is None:
            time.sleep(0.005)
    return None


def _group(run, words, options):
    import busservo

    if not 1 <= len(words) <= 2:
        raise _Usage("group wants N [TIMES]")
    group = _int(words[0], "N", 0, 255)
    times = _int(words[1], "TIMES", 0, 65535) if len(words) > 1 else 1
    bus, simulated = _bus(run)
    _answers(bus, run)
    if not (_CHECKED in options or simulated):
        print(
            "nothing moved: action group %d moves the servos it holds; check that they can" % group
        )
        print("turn freely, then add " + _CHECKED)
        return 1
    bus.run_group(group, times)
    try:
        until = time.monotonic() + run.ms() / 1000
        cmd = _wait_for_group(bus, group, until)
        if cmd == busservo.CMD_ACTION_GROUP_STOP:
            # A group ran: the controller stops it for this one (STOP), then starts this (RUN).
            print("(the action group that ran is stopped for it)")
            cmd = _wait_for_group(bus, group, until)
        if cmd != busservo.CMD_ACTION_GROUP_RUN:
            print(
                "action group %d did not start: has the controller one of that number? "
                "(its PC software stores them)" % group
            )
            return 1
        print(
            "action group %d runs %s (Ctrl-C stops it)"
            % (
                group,
                "until stopped" if not times else "once" if times == 1 else "%d times" % times,
            ),
            flush=True,
        )
        cmd = _wait_for_group(bus, group, None)
    except KeyboardInterrupt:
        bus.stop_group()
        print("stopped action group %d" % group)
        return 130
    if cmd == busservo.CMD_ACTION_GROUP_STOP:
        print("action group %d was stopped" % group)
        return 1
    print("action group %d done" % group)
    return 0


def _stop(run, words, options):
    import busservo

    if words:
        raise _Usage("stop takes PORT only")
    bus, _ = _bus(run)
    _answers(bus, run)
    bus.stop_group()
    # The controller says STOP back when a group was running.
    until = time.monotonic() + run.ms() / 1000
    while time.monotonic() < until:
        if bus.poll() == busservo.CMD_ACTION_GROUP_STOP:
            print("stopped the action group that ran")
            return 0
        time.sleep(0.005)
    print("no action group was running")
    return 0


def _robot(bus, dps):
    # The panel's robot: the calibration in robot.json, or examples/web_panel.py's joints.
    import busservo_board

    try:
        return busservo_board.robot(bus, busservo_board.joints(dps=dps))
    except (ValueError, TypeError) as e:  # the file's words: they name it
        raise _BadFile(
            "%s (the calibration in the folder you run from: mend it, or move it away)" % e
        )


def _panel(run, words, options):
    if words:
        raise _Usage("panel takes --password P, --port N and --host H, got %r" % words[0])
    key = options.get("--password")
    if not key or len(key) < 8:
        raise _Usage("panel wants --password P, of 8 characters or more")
    tcp = _int(options.get("--port", "8080"), "--port", 1, 65535)
    host = options.get("--host", _ANY_HOST)
    if not host:
        raise _Usage("--host wants an address of this computer's, or 0.0.0.0 for every one")
    bus, simulated = _bus(run)
    robot = _robot(bus, None if simulated else _PANEL_DPS)
    ids = [robot.joints[name].servo_id for name in robot.names]
    print("the servos are at", bus.read_positions(ids, run.ms(len(ids))))
    if not (_CHECKED in options or simulated):
        print("nothing moved: the panel moves servos %s; check that they can turn freely," % ids)
        print("then add " + _CHECKED)
        return 1
    robot.where()
    return _serve(robot, key, tcp, host)


def _serve(robot, key, tcp, host):
    import socket

    import busservo_web
    from busservo_cpython import asyncio

    async def serve():
        task = asyncio.ensure_future(busservo_web.serve(robot, key, tcp, host=host))
        await asyncio.sleep(0.2)
        if not task.done():
            shown = "127.0.0.1" if host in (_ANY_HOST, "::") else host
            if ":" in shown:
                shown = "[%s]" % shown  # an IPv6 address, in a URL
            # (not the password: what is printed may end up in a log, or on a screen)
            print("open http://%s:%d/ and log in with the password you gave" % (shown, tcp))
            print("(Ctrl-C stops the panel)", flush=True)
        await task

    try:
        asyncio.run(serve())
    except socket.gaierror as e:
        print("busservo: no address %r on this computer: %s" % (host, e.strerror), file=sys.stderr)
        return 1
    except OSError as e:
        if e.errno in (errno.EADDRINUSE, getattr(errno, "WSAEADDRINUSE", 0)):
            why = "port %d is in use (another panel?): give another with --port N" % tcp
        elif e.errno == errno.EADDRNOTAVAIL:
            why = "%s is no address of this computer's: give one with --host H" % host
        elif e.errno == errno.EACCES and tcp < 1024:
            why = "port %d needs the administrator: give one above 1023 with --port N" % tcp
        else:
            raise
        print("busservo: " + why, file=sys.stderr)
        return 1
    finally:
        robot.hold()
    return 0


# Recording, playback and a leader driving a follower (busservo_record, busservo_teleop).

_PLAY_DPS = 30  # a recording goes into its first pose, and a follower to the leader's, at this
_RATE_S = 1  # teleop says its rate this often (seconds)


def _number(text, what, low, high):
    try:
        value = float(text)
    except ValueError:
        value = None
    if value is None or not low <= value <= high:  # (nan is in no range)
        raise _Usage("%s must be a number in %g..%g, got %r" % (what, low, high, text))
    return value


def _file(path, what):
    # The file at path must be there (a usage error, not a traceback, if not).
    if not os.path.exists(path):
        raise _Usage("no such file %s (%s)" % (path, what))
    if os.path.isdir(path):
        raise _Usage("%s is a folder, not %s" % (path, what))


def _halt(robot, run):
    # Ctrl-C: each joint of robot stops where it is (read, then held there in _HALT_MS), as
    # move's Ctrl-C and the panel's STOP do. {servo_id: position or None}.
    ids = [robot.joints[name].servo_id for name in robot.names]
    at = robot.bus.read_positions(ids, run.ms(len(ids)))
    held = [(i, at[i]) for i in ids if at[i] is not None]
    if held:
        robot.bus.move_many(held, _HALT_MS)
    return at


def _record(run, words, options):
    import busservo_record

    if len(words) != 1:
        raise _Usage("record wants PORT FILE")
    path = words[0]
    seconds = None
    if "--seconds" in options:
        seconds = _number(options["--seconds"], "--seconds", 0.1, 86400)
    _writable(path)
    bus, simulated = _bus(run)
    robot = _robot(bus, None)
    _answers(bus, run)
    ids = [robot.joints[name].servo_id for name in robot.names]
    if not (_CHECKED in options or simulated):
        print("the servos are at", bus.read_positions(ids, run.ms(len(ids))))
        print(
            "this lets the joints %s (servos %s) go limp, to be moved by hand, and records "
            "them into %s; what they hold up falls" % (", ".join(robot.names), ids, path)
        )
        _unchecked(run)
        return 1
    print(
        "the joints %s (servos %s) go limp: move the arm by hand" % (", ".join(robot.names), ids)
    )
    print(
        "recording into %s %s" % (path, "for %g s" % seconds if seconds else "(Ctrl-C ends it)"),
        flush=True,
    )
    recorder = busservo_record.Recorder(robot, path=path, timeout_ms=run.timeout)
    start = time.monotonic()
    try:
        while seconds is None or time.monotonic() - start < seconds:
            recorder.step()  # never waits for the wire
            time.sleep(0.001)
    except KeyboardInterrupt:
        pass  # the normal end of a recording
    recording = recorder.stop()
    _saved(path, recording, recorder.missed)
    if not len(recording):
        print("no sample: no read was answered (the servos' power, the bus cable, their ids)")
        return 1
    return 0


class _ended_as_ctrl_c:
    """Within it, SIGTERM and SIGHUP (the terminal closed) end the command as Ctrl-C does:
    a KeyboardInterrupt, so that what it started is stopped (a move held where it is, a
    group stopped, a recording saved, the panel's servos halted). Once: a second one while
    it stops them is let pass (SIGKILL ends it at once)."""

    def __enter__(self):
        import signal

        self.before = {}
        came = []

        def interrupt(signum, frame):
            if not came:
                came.append(signum)
                raise KeyboardInterrupt

        for name in ("SIGTERM", "SIGHUP"):  # (Windows has no SIGHUP)
            number = getattr(signal, name, None)
            if number is None:
                continue
            try:
                self.before[number] = signal.signal(number, interrupt)
            except ValueError:  # not the main thread: as it was
                pass
        return self

    def __exit__(self, *exc):
        import signal

        for number, handler in self.before.items():
            signal.signal(number, handler)
        return False


def _writable(path):
    # A recording's FILE: its folder must be there, it must be no folder itself, and its
    # name says its form (anything else, robot.json say, would be replaced by a recording).
    folder = os.path.dirname(path) or "."
    if not os.path.isdir(folder):
        raise _Usage("no folder %s for FILE %s" % (folder, path))
    if os.path.isdir(path):
        raise _Usage("%s is a folder: FILE is the recording's file" % path)
    if not path.endswith((".rec", ".jsonl")):
        raise _Usage(
            "FILE must end in .rec (the compact form) or .jsonl (JSON lines), got %r" % path
        )


def _saved(path, recording, missed):
    # What a recording command says at its end.
    print(
        "saved %s: %d samples over %.1f s, %d reads missed"
        % (path, len(recording), recording.duration_ms / 1000, missed)
    )


def _recording(path):
    # The Recording in path, or a usage error saying why not.
    import busservo_record

    _file(path, "a recording: busservo record makes one")
    try:
        recording = busservo_record.Recording.load(path)
    except (ValueError, TypeError) as e:  # its words name the file
        raise _Usage(str(e))
    if not len(recording):
        raise _Usage("%s holds no sample" % path)
    return recording


def _play(run, words, options):
    if len(words) != 1:
        raise _Usage("play wants PORT FILE")
    speed = _number(options.get("--speed", "1"), "--speed", 0.25, 2)
    path = words[0]
    recording = _recording(path)
    bus, simulated = _bus(run)
    robot = _robot(bus, None)
    alien = [name for name in recording.names if name not in robot.joints]
    if alien:
        raise _BadFile(
            "%s records joints %s, which the robot has not (its joints: %s; robot.json in the "
            "folder you run from says them)" % (path, ", ".join(alien), ", ".join(robot.names))
        )
    ids = [robot.joints[name].servo_id for name in recording.names]
    print("the servos are at", bus.read_positions(ids, run.ms(len(ids))))
    print(
        "this plays %s (%d samples, %.1f s) on servos %s at %gx: into its first pose at %d "
        "degrees/s, then at its pace"
        % (path, len(recording), recording.duration_ms / 1000, ids, speed, _PLAY_DPS)
    )
    if not (_CHECKED in options or simulated):
        print("nothing moved: check that they can turn freely, then add " + _CHECKED)
        return 1
    player = recording.play(robot, speed=speed, dps=_PLAY_DPS)
    print("playing (Ctrl-C stops it)", flush=True)
    start = time.monotonic()
    try:
        player.wait()
    except KeyboardInterrupt:
        at = _halt(robot, run)
        print(
            "stopped at sample %d of %d: the servos hold at %s"
            % (player.index + 1, len(recording), at)
        )
        return 130
    print(
        "played %s in %.1f s%s"
        % (
            path,
            time.monotonic() - start,
            ", %d moves slowed by a joint's dps" % player.slowed if player.slowed else "",
        )
    )
    return 0


def _calibration(path, what):
    # The joints of the calibration in path (a Robot on no bus yet), or a usage error.
    import busservo_motion

    _file(path, "%s: a robot.json" % what)
    try:
        return busservo_motion.Robot.load(None, path)
    except (ValueError, TypeError) as e:  # its words name the file
        raise _Usage("%s: %s" % (what, e))


_SIM_FOLLOWER = 6  # --sim's follower without a calibration: the demo's arm, ids 6 more


def _moved(joints, offset):
    # joints {name: Joint}, each on the servo offset ids on.
    import busservo_motion

    moved = {}
    for name, joint in joints.items():
        config = joint.config()
        config["servo_id"] += offset
        moved[name] = busservo_motion.Joint(**config)
    return moved


def _teleop(run, words, options):
    import busservo_motion
    import busservo_teleop

    if len(words) > 1:
        raise _Usage("teleop wants LEADER [FOLLOWER]: two ports, or one with both arms on it")
    lpath = options.get("--leader-calibration")
    fpath = options.get("--follower-calibration")
    if not (lpath or fpath) and run.port == "--sim" and words in ([], ["--sim"]):
        # No arm yet: the demo's arm on servos 1..4 leads the same arm on 7..10.
        import busservo_board

        lpath, fpath = "the demo's arm", "the demo's arm on servos 7..10"
        lead = busservo_motion.Robot(None, busservo_board.joints())
        follow = busservo_motion.Robot(None, _moved(lead.joints, _SIM_FOLLOWER))
        print("the leader: %s (servos 1..4); the follower: %s" % (lpath, fpath))
    elif not lpath or not fpath:
        raise _Usage(
            "teleop wants --leader-calibration F1 and --follower-calibration F2 "
            "(each arm's robot.json; on --sim, neither: the demo's arm)"
        )
    else:
        lead = _calibration(lpath, "--leader-calibration")
        follow = _calibration(fpath, "--follower-calibration")
    path = options.get("--record")
    if path is not None:
        _writable(path)
    lids = [lead.joints[name].servo_id for name in lead.names]
    fids = [follow.joints[name].servo_id for name in follow.names]
    shared = not words
    if shared and set(lids) & set(fids):
        raise _Usage(
            "on one bus the arms need their own servo ids: %s and %s both have servos %s "
            "(give the follower's port too, if it has a controller of its own)"
            % (lpath, fpath, sorted(set(lids) & set(fids)))
        )
    if not set(lead.names) & set(follow.names):
        raise _Usage(
            "%s and %s share no joint name: the leader's are %s, the follower's %s"
            % (lpath, fpath, ", ".join(lead.names), ", ".join(follow.names))
        )
    if shared:
        lbus, simulated = _bus(run, servos=lids + fids)
        fbus = lbus
    else:
        lbus, simulated = _bus(run, servos=lids)
        fbus, fsim = _bus(run, words[0], servos=fids)
        simulated = simulated and fsim
    leader = busservo_motion.Robot(lbus, lead.joints)
    follower = busservo_motion.Robot(fbus, follow.joints)
    print("the leader's servos are at", lbus.read_positions(lids, run.ms(len(lids))))
    print("the follower's servos are at", fbus.read_positions(fids, run.ms(len(fids))))
    print(
        "this lets the leader's joints go limp (what they hold up falls), and the follower "
        "goes to its pose at %d degrees/s, then follows it" % _PLAY_DPS
    )
    if not (_CHECKED in options or simulated):
        print("nothing moved: hold the leader, check that the follower can turn freely, then")
        print("add " + _CHECKED)
        return 1
    recorder = None
    if path is not None:
        import busservo_record

        names = [name for name in leader.names if name in follower.joints]
        recorder = busservo_record.Recorder(leader, names, path, limp=False)
    teleop = busservo_teleop.Teleop(
        leader, follower, dps=_PLAY_DPS, timeout_ms=run.timeout, recorder=recorder
    )
    teleop.warn = lambda text: print(text, flush=True)
    print("the leader drives the follower (Ctrl-C stops it)", flush=True)
    if recorder:
        print("recording the leader into %s" % path, flush=True)
    then = time.monotonic()
    reads = 0
    try:
        while not teleop.done:
            teleop.step()  # never waits for the wire
            now = time.monotonic()
            if now - then >= _RATE_S:
                print(
                    "%.1f cycles a second, %s"
                    % (
                        (teleop.reads - reads) / (now - then),
                        "following"
                        if teleop.engaged
                        else "going to the leader's pose at %d degrees/s" % _PLAY_DPS,
                    ),
                    flush=True,
                )
                then, reads = now, teleop.reads
            time.sleep(0.0005)
    except KeyboardInterrupt:
        teleop.stop()
        at = _halt(follower, run)
        print("stopped: the follower holds at %s; the leader is limp" % at)
        return 130
    finally:
        if recorder:
            _saved(path, recorder.stop(), recorder.missed)
    return 0


_COMMANDS = {
    "ports": _ports,
    "check": _check,
    "scan": _scan,
    "positions": _positions,
    "move": _move,
    "limp": _limp,
    "group": _group,
    "stop": _stop,
    "panel": _panel,
    "record": _record,
    "play": _play,
    "teleop": _teleop,
}


def main(argv=None):
    """The `busservo` command: returns its exit status (0 done, 1 failed or nothing moved
    for want of --i-have-checked-my-robot, 2 bad usage, 130 stopped by Ctrl-C)."""
    args = list(sys.argv[1:] if argv is None else argv)
    run = None
    try:
        words, options = _parse(list(args))
        if not args or "-h" in options or "--help" in options or words[:1] == ["help"]:
            print(_USAGE)
            return 0 if args else 2
        if "-V" in options or "--version" in options:
            import busservo

            print("busservo", busservo.__version__)
            return 0
        if not words:
            raise _Usage("no command: busservo ports, check, scan, positions, move, ...")
        command = words.pop(0)
        if command not in _COMMANDS:
            raise _Usage("no command %r" % command)
        for name in options:
            if name not in _TAKES[command] and name != _CHECKED:
                raise _Usage("%s takes no %s" % (command, name))
        run = _Run(options)
        if command != "ports":
            if not words:
                raise _Usage(
                    "%s wants a PORT (busservo ports lists them; --sim: simulated)" % command
                )
            run.port = words.pop(0)
        with _ended_as_ctrl_c():  # every command ends on SIGTERM and SIGHUP as on Ctrl-C
            return _COMMANDS[command](run, words, options)
    except _Usage as e:
        print("busservo: %s (busservo --help)" % e, file=sys.stderr)
        return 2
    except _BadFile as e:
        print("busservo: %s" % e, file=sys.stderr)
        return 2
    except OSError as e:
        if e.errno == errno.ETIMEDOUT and run and run.port:
            words = io.StringIO()
            _checklist(run, words, e)
            why = words.getvalue().rstrip("\n")
        elif e.strerror and len(e.args) > 1:
            why = e.strerror
            if e.filename:  # a file's error (robot.json a folder, say): its name first
                why = "%s: %s" % (e.filename, why)
        else:
            why = str(e)
        print("busservo: %s" % why, file=sys.stderr)
        if run and run.json and not run.said:
            run.result({"error": why})  # --json: a line, always
        return 1
    except KeyboardInterrupt:
        return 130
    finally:
        for uart in run.uarts if run else ():
            close = getattr(uart, "close", None)
            if close:
                close()


class _Stdout:
    """The command's stdout, whose reader may go away (busservo ... | head -1): then what it
    says goes nowhere, quietly, as Unix tools end on a closed pipe, and the command goes on
    (a group it started is still stopped at Ctrl-C, not left running by a traceback)."""

    def __init__(self, out):
        self._out = out

    def write(self, text):
        try:
            return self._out.write(text)
        except BrokenPipeError:
            self._gone()
            return len(text)

    def flush(self):
        try:
            self._out.flush()
        except BrokenPipeError:
            self._gone()

    def _gone(self):
        # The descriptor becomes /dev/null: what is left in the buffer, and Python's flush
        # as it exits, go there rather than to the closed pipe.
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, self._out.fileno())
        os.close(null)

    def __getattr__(self, name):
        return getattr(self._out, name)


def _entry():
    sys.stdout = _Stdout(sys.stdout)
    sys.exit(main())


if __name__ == "__main__":
    _entry()
