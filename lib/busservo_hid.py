# busservo_hid: the controller on a computer's USB as a HID device (CPython, and the hidapi
# binding: pip install ".[hid]"). Hiwonder's xArm 1S and LeArm controllers, and others of
# the family, have no USB-serial chip: they enumerate as a HID device, USB 0483:5750, and
# speak the same frames, one in each report. The driver talks to one as to a board's UART:
#
#   import busservo, busservo_hid
#   bus = busservo.BusServo(busservo_hid.hid_port())   # the first one plugged in
#   busservo_hid.ports()    # [("hid:/dev/hidraw3", "MyUSB_HID LOBOT (USB HID 0483:5750, ...)")]
#
# hid_port() gives the UART methods the driver uses, as busservo_host.serial_port() does:
# any() and readinto() never wait (they read the reports that have come, without
# blocking, as a byte stream), and write() gathers bytes until a whole frame, by its
# Length byte, and sends it as one report; wait(ms) waits for a report in the OS, and
# latency_ms says how late a report may come (a poll of the endpoint, a busy computer). A
# controller just switched on or plugged in may leave its first second unanswered: hid_port()
# asks it for its battery until it answers (up to WAKE_MS), so that the first query of a
# program is answered. What goes wrong is an OSError that says it in
# words: the binding not installed, no controller plugged in (ENOENT), no permission on
# Linux (EACCES: a udev rule), unplugged mid-command (ENODEV), a frame too long for a
# report (EMSGSIZE).
#
# The framing, as the public libraries that drive these controllers through hidapi do it
# (read, not copied):
# - ccourson/xArmServoController (PyPI's `xarm`), Python/xarm/controller.py: opens 0483:5750
#   with cython-hidapi (`hid.device`, by serial number or path), non-blocking; a command is
#   one output report, `00 55 55 Len Cmd Params`: report id 0, then the frame; a reply is
#   read as a 64-byte input report (waiting 50 ms at most) with the frame at its start, and
#   what follows the frame is not used. Its battery read tries 5 times, a second apart, as
#   the controller "sometimes takes a second or two" to answer just after it is opened.
# - adeguet1/lewansoul-xarm (src/lewansoul_xarm/controller.py) and dmklee/nuro-arm
#   (nuro_arm/robot/xarm_controller.py), through easyhid, which puts the report id 0 before
#   what it is given: the same frames, the reply at the start of the report, positions
#   read as signed 16-bit values.
# - Native Windows code for the xArm writes 65 bytes (report id 0, the frame, zeros), as
#   Windows wants a report whole; this module pads every report so, whatever the system.
# - A note in Maxime Chevalier-Boisvert's xArm script, which several of these build on:
#   position reads "can take up to 450ms". Give read_positions() a timeout to match.
# None of them sends a frame longer than one report, or reads a reply longer than one: they
# ask for 6 servos at most. Here a reply whose Length runs past its report goes on in the
# next reports (a stream's bytes, as the controller's serial side sends them); a frame to
# send that does not fit in one report is refused (EMSGSIZE), since nothing says the
# controller joins reports: move_many() of up to 19 servos, unload() and read_positions() of
# up to 59 ids fit (a reply to 59 spans 3 reports).
import errno
import os
import re
import sys
import time

import busservo_cpython
from busservo_cpython import BUSY_MS

VID = 0x0483  # STMicroelectronics' vendor id, which these controllers use
PID = 0x5750
REPORT = 64  # bytes of a report, each way; written behind its report id, 0
_HEADER = 0x55
_READ = 256  # bytes asked for a report read: a longer report is not cut short
_HOLD = 4096  # bytes read ahead of the driver at most; the OS queues the reports behind them
_REPORTS = 64  # reports read a call at most, so that a flood of them cannot hold it
# How much later than it was sent a report may reach a program, ms: a poll of the endpoint
# (up to 10 ms) and what a busy computer adds.
LATENCY_MS = 10 + BUSY_MS
# A controller just opened is asked for its battery up to this long, every _ASK_MS, until it
# answers (the public xArm library retries its first battery read for 5 s).
WAKE_MS = 3000
_ASK_MS = 250
_GET_BATTERY = b"\x55\x55\x02\x0f"

# On Linux: the rule that lets a user open the controller's hidraw device (root's alone
# otherwise), in /etc/udev/rules.d/70-busservo.rules.
UDEV_RULE = (
    'KERNEL=="hidraw*", ATTRS{idVendor}=="0483", ATTRS{idProduct}=="5750", '
    'MODE="0660", GROUP="plugdev", TAG+="uaccess"'
)


def _binding():
    # cython-hidapi (the `hidapi` package). On Linux its `hidraw` module uses the kernel's
    # hidraw devices (/dev/hidrawN: the kernel's driver keeps the device, a udev rule gives
    # the permission); its `hid` module there goes through libusb.
    hid = None
    names = ("hidraw", "hid") if sys.platform.startswith("linux") else ("hid",)
    for name in names:
        try:
            hid = __import__(name)
        except ImportError:
            continue
        if hasattr(hid, "device") and hasattr(hid, "enumerate"):
            return hid
    if hid is None:
        raise OSError(
            errno.ENOENT,
            'the hidapi binding is not installed: pip install ".[hid]" in the clone '
            "(it is not installed by default)",
        )
    raise OSError(
        errno.ENOENT,
        "the hid module at %s is not hidapi's (another package named hid?): "
        'pip uninstall hid, then pip install ".[hid]"' % getattr(hid, "__file__", "?"),
    )


def _text(path):
    # hidapi's path (bytes) as the text a PORT holds, and back again, byte for byte.
    return path.decode("utf-8", "surrogateescape") if isinstance(path, bytes) else str(path)


def _controllers(hid):
    # In the order of their paths' numbers (hidraw3 before hidraw10), as a person counts.
    found = [d for d in hid.enumerate(VID, PID) if d.get("path")]
    return sorted(found, key=lambda d: _in_number_order(_text(d["path"])))


def _in_number_order(text):
    # A sort key: text's digits as numbers, the rest as text.
    key = []
    for part in re.split(r"(\d+)", text):
        key.append((0, int(part), "") if part.isdigit() else (1, 0, part))
    return key


def _describe(d):
    words = [d.get(k) or "" for k in ("manufacturer_string", "product_string")]
    what = " ".join(w.strip() for w in words if w.strip()) or "HID controller"
    serial = (d.get("serial_number") or "").strip()
    return "%s (USB HID %04X:%04X%s)" % (what, VID, PID, ", serial " + serial if serial else "")


def ports():
    """The HID controllers plugged in, [(port, description)]: port is "hid:<path>", as
    hid_port() and the busservo command take it. [] when none, or when the hidapi binding
    is not installed."""
    try:
        hid = _binding()
        return [("hid:" + _text(d["path"]), _describe(d)) for d in _controllers(hid)]
    except OSError:
        return []


def _open_error(hid, port, path, e):
    text = _text(path)
    known = [_text(d.get("path") or b"") for d in hid.enumerate(0, 0)]
    if text not in known and not os.path.exists(text):
        return OSError(
            errno.ENOENT, "no such port %s (busservo ports lists those there are)" % port
        )
    if text.startswith("/dev/") and not os.access(text, os.R_OK | os.W_OK):
        return OSError(
            errno.EACCES,
            "no permission to open %s: on Linux, a udev rule gives it (docs/computer.md): "
            "%s, in /etc/udev/rules.d/70-busservo.rules, then sudo udevadm control "
            "--reload-rules, sudo udevadm trigger, and plug it in again" % (text, UDEV_RULE),
        )
    why = "another program may have it: close it, or plug the controller in again"
    if sys.platform.startswith("linux"):
        why += "; or no permission: docs/computer.md's udev rule"
    return OSError(errno.EIO, "could not open %s: %s (%s)" % (port, e, why))


def hid_port(port="hid", wake_ms=WAKE_MS):
    """The HID controller at port, "hid" for the first one plugged in or "hid:<path>" (as
    ports() lists them), open for busservo.BusServo(), and awake: it is asked for its battery
    until it answers, for up to wake_ms (0: not asked; one that never answers is open all the
    same, and its first query says so). Raises OSError saying why it cannot be opened."""
    if not isinstance(port, str) or not (port == "hid" or port.startswith("hid:")):
        raise ValueError(
            "port must be 'hid' or 'hid:<path>' (busservo_hid.ports() lists them), got %r"
            % (port,)
        )
    hid = _binding()
    if port == "hid":
        found = _controllers(hid)
        if not found:
            raise OSError(
                errno.ENOENT,
                "no HID controller (USB %04X:%04X) is plugged in: plug its USB cable in, "
                "and switch it on (one with a USB-serial chip is a serial port: busservo "
                "ports)" % (VID, PID),
            )
        path = found[0]["path"]
        port = "hid:" + _text(path)
    else:
        path = port[4:].encode("utf-8", "surrogateescape")
    device = hid.device()
    try:
        device.open_path(path)
    except (OSError, ValueError) as e:  # hidapi says only "open failed"
        raise _open_error(hid, port, path, e)
    device.set_nonblocking(1)
    uart = HidUART(device, port)
    uart.wake(wake_ms)
    return uart


class HidUART(busservo_cpython.UART):
    """A hidapi device with machine.UART's any/read/readinto/write, as the driver uses
    them: reports in, a byte stream out, and back."""

    def __init__(self, device, port):
        self._device = device
        self.port = port
        self._in = bytearray()  # the frames read from reports, not yet read by the driver
        self._rest = 0  # bytes of a frame longer than its report, due in the next reports
        self._out = bytearray()  # bytes written that make no whole frame yet
        self._lost = None  # why the device is gone, once it is
        self.latency_ms = LATENCY_MS  # read by busservo.BusServo() when it is made

    def _gone(self, e):
        self._lost = e
        self.close()
        return OSError(errno.ENODEV, "the controller %s is gone (unplugged?): %s" % (self.port, e))

    def _open(self):
        if self._device is None:
            if self._lost is not None:
                raise OSError(errno.ENODEV, "the controller %s is gone (unplugged?)" % self.port)
            raise OSError(errno.EBADF, "the port %s is closed" % self.port)
        return self._device

    def _why(self, what):
        try:
            said = self._device.error()
        except Exception:
            said = ""
        return "%s%s" % (what, ": " + said if said else "")

    # Reading: each report the controller sends starts with a frame (`55 55 Len Cmd ...`),
    # behind a report id 0 where a binding leaves one; what follows the frame is padding.
    # A frame longer than its report goes on at the start of the next ones.

    def _pump(self):
        device = self._open()
        for _ in range(_REPORTS):
            if len(self._in) >= _HOLD:
                return
            try:
                report = device.read(_READ)  # non-blocking: [] when none has come
            except (OSError, ValueError) as e:
                raise self._gone(e)
            if not report:
                return
            self._take(bytes(report))

    def wait(self, ms):
        """Wait until a report has come, or ms have passed, in the OS (hidapi's read with a
        timeout): what a blocking query does between its looks (busservo's _run)."""
        device = self._open()
        if self._in:
            return
        try:
            report = device.read(_READ, ms)
        except (OSError, ValueError) as e:
            raise self._gone(e)
        if report:
            self._take(bytes(report))

    def wake(self, ms=WAKE_MS):
        """Ask the controller for its battery every _ASK_MS until it answers, for up to ms:
        True once it has. Its answers are not read (what else comes is)."""
        end = time.monotonic() + ms / 1000
        ask = 0
        while time.monotonic() < end:
            if time.monotonic() >= ask:
                self.write(_GET_BATTERY)
                ask = time.monotonic() + _ASK_MS / 1000
            self.wait(10)
            if self._battery_taken():
                self.wait(20)  # the answer to an earlier ask may be right behind it
                self._battery_taken()
                return True
        return False

    def _battery_taken(self):
        # Take the battery replies out of what has come, frame by frame: True if one was.
        data = self._in
        taken = False
        at = 0
        while len(data) - at > 3 and data[at] == data[at + 1] == _HEADER:
            end = at + data[at + 2] + 2
            if data[at + 3] == _GET_BATTERY[3] and end <= len(data):
                del data[at:end]
                taken = True
            else:
                at = end
        return taken

    def _take(self, report):
        n = len(report)
        if self._rest:
            k = min(self._rest, n)
            self._in += report[:k]
            self._rest -= k
            return
        at = 1 if n > 2 and report[0] == 0 and report[1] == report[2] == _HEADER else 0
        if n - at > 2 and report[at] == report[at + 1] == _HEADER:
            end = at + report[at + 2] + 2
            self._in += report[at:end]
            self._rest = max(0, end - n)
        else:
            # No frame: the driver sees its bytes (but the zeros at the end) and counts
            # them as noise, as it counts a serial line's.
            self._in += report.rstrip(b"\0")

    def any(self):
        self._pump()
        return len(self._in)

    def readinto(self, buf, nbytes=-1):
        self._pump()
        n = len(buf) if nbytes < 0 or nbytes > len(buf) else nbytes
        got = min(n, len(self._in))
        buf[:got] = self._in[:got]
        del self._in[:got]
        return got or None

    # Writing: bytes gather until they make a whole frame, by its Length byte; each frame
    # goes as one report. Bytes that start no frame go as they are, a report of their own
    # (the controller drops them, as it drops a serial line's noise).

    def write(self, buf, off=None, nbytes=None):
        data = busservo_cpython.written(buf, off, nbytes)  # MicroPython's stream forms
        self._open()
        if not data:
            return 0
        out = self._out
        out += data
        while out:
            if out[0] != _HEADER or len(out) > 1 and out[1] != _HEADER:
                k = out.find(_HEADER, 1)
                k = len(out) if k < 0 else k
            elif len(out) < 3:
                break
            else:
                k = out[2] + 2
                if k > REPORT:
                    del out[:]
                    raise OSError(
                        errno.EMSGSIZE,
                        "a frame of %d bytes: a HID report carries %d at most (move_many() "
                        "of up to 19 servos, read_positions() of up to 59 ids)" % (k, REPORT),
                    )
                if len(out) < k:
                    break
            self._report(out[:k])
            del out[:k]
        return len(data)

    def _report(self, frame):
        report = bytes(1) + bytes(frame) + bytes(REPORT - len(frame))  # id 0, frame, zeros
        try:
            done = self._device.write(report)
        except (OSError, ValueError) as e:
            raise self._gone(e)
        if done is None or done < 0:
            raise self._gone(self._why("write failed"))

    def close(self):
        device, self._device = self._device, None
        if device is not None:
            try:
                device.close()
            except Exception:
                pass

    def __repr__(self):
        return "<busservo_hid.HidUART %s>" % self.port
