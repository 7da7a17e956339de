# The controller as a USB HID device (lib/busservo_hid.py; CPython only: tests/run.sh runs
# this module in its CPython pass). A fake hidapi binding stands in for cython-hidapi, with
# controllers plugged into it: reports out, reports in, a reply padded or split over reports as
# a real one is, the report id byte, unplugging. Behind it, the simulated controller answers at
# USB speed (no 9600-baud line), and the driver, busservo_async's queries included, runs over
# it as over a serial port. Last, the real binding, if installed: nothing plugged in is [].
import asyncio
import errno
import sys
import time
import unittest

import busservo
import busservo_async
import busservo_hid
import busservo_sim
from busservo import (
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_RUN,
    CMD_GET_BATTERY_VOLTAGE,
    CMD_MULT_SERVO_POS_READ,
)

GET_BATTERY = bytes.fromhex("5555020f")
BATTERY_7500 = bytes.fromhex("5555040f4c1d")
ALL_500 = {1: 500, 2: 500, 3: 500, 4: 500, 5: 500, 6: 500}
XARM = "/dev/hidraw3"


def report(frame, pad=0):
    """An output report as hidapi is given it: report id 0, the frame, padding to 64 bytes."""
    return bytes(1) + frame + bytes([pad]) * (64 - len(frame))


def frames(data):
    """The frames in a stream of whole frames, in order."""
    found = []
    while data:
        end = data[2] + 2
        found.append(bytes(data[:end]))
        data = data[end:]
    return found


class Controller:
    """A HID controller plugged into the fake binding. What the computer sends is in `got`
    (its reports, whole); what it says is in `reports` (to read, in order). With `sim`, the
    simulated controller answers every frame at once, each frame at the start of a 64-byte
    report padded with `pad`, a longer one going on in the next reports, as a real one's."""

    def __init__(self, path=XARM, vid=0x0483, pid=0x5750, sim=None, pad=0):
        self.path = path.encode()
        self.vid, self.pid = vid, pid
        self.manufacturer, self.product, self.serial = "MyUSB_HID", "LOBOT", "497223563535"
        self.sim = sim
        self.pad = pad
        self.got = []
        self.reports = []
        self.plugged = True
        self.denied = False  # opening it fails, as hidapi fails without permission
        self.said = bytearray()  # what the sim said that makes no whole frame yet
        self.script = None  # or a function: a frame received -> the reports it answers with
        self.deaf_s = 0  # it answers nothing for this long after it is opened
        self.opened = 0  # (time.monotonic())

    def receive(self, data):
        self.got.append(data)
        if time.monotonic() < self.opened + self.deaf_s:
            return  # just switched on: what it is sent is not answered
        frame = data[1 : 1 + data[3] + 2]  # the report id, then the frame
        if self.script is not None:
            self.reports += self.script(frame)
        elif self.sim is not None:
            self.sim.write(frame)

    def answer(self):
        if self.sim is None:
            return
        self.said += self.sim.read() or b""
        while len(self.said) > 2 and len(self.said) >= self.said[2] + 2:
            end = self.said[2] + 2
            frame = bytes(self.said[:end])
            del self.said[:end]
            for at in range(0, len(frame), 64):
                part = frame[at : at + 64]
                self.reports.append(part + bytes([self.pad]) * (64 - len(part)))

    def frames_got(self):
        return [r[1 : 1 + r[3] + 2] for r in self.got]


class Device:
    """cython-hidapi's hid.device, as busservo_hid uses it."""

    def __init__(self, binding):
        self.binding = binding
        self.controller = None
        self.nonblocking = 0
        self.closed = False
        self.reads = 0
        self.waits = 0  # reads that may wait (a timeout given): busservo_hid's wait() alone

    def open_path(self, path):
        if not isinstance(path, bytes):
            raise TypeError("path must be bytes")
        c = self.binding.find(path)
        if c is None or c.denied:
            raise OSError("open failed")
        self.controller = c
        c.opened = time.monotonic()

    def set_nonblocking(self, v):
        self.nonblocking = v
        return 0

    def read(self, max_length, timeout_ms=0):
        # Non-blocking: at once, or with a timeout for up to that (hid_read_timeout()). What
        # a controller says comes at once, so a read that finds nothing sleeps it all.
        assert self.nonblocking, "a read that may wait for ever"
        c = self._open()
        if not c.plugged:
            raise OSError("read error")
        self.reads += 1
        c.answer()
        if not c.reports and timeout_ms > 0:
            self.waits += 1
            time.sleep(timeout_ms / 1000)
        return list(c.reports.pop(0)[:max_length]) if c.reports else []

    def write(self, buff):
        c = self._open()
        if not c.plugged:
            return -1
        c.receive(bytes(buff))
        return len(buff)

    def error(self):
        return "" if self.controller.plugged else "No such device"

    def close(self):
        self.closed = True

    def _open(self):
        if self.closed or self.controller is None:
            raise ValueError("not open")
        return self.controller


class Binding:
    """The hidapi binding (the `hidraw` module on Linux, `hid` elsewhere), with the
    controllers plugged in."""

    def __init__(self, *controllers):
        self.controllers = list(controllers)
        self.devices = []
        self.__file__ = "fake"

    def find(self, path):
        for c in self.controllers:
            if c.path == path and c.plugged:
                return c
        return None

    def enumerate(self, vendor_id=0, product_id=0):
        return [
            {
                "path": c.path,
                "vendor_id": c.vid,
                "product_id": c.pid,
                "serial_number": c.serial,
                "manufacturer_string": c.manufacturer,
                "product_string": c.product,
                "interface_number": 0,
            }
            for c in self.controllers
            if c.plugged and vendor_id in (0, c.vid) and product_id in (0, c.pid)
        ]

    def device(self):
        d = Device(self)
        self.devices.append(d)
        return d


class WithBinding(unittest.TestCase):
    """Each test installs its binding: the modules busservo_hid imports are the fake's."""

    NAMES = ("hid", "hidraw")

    def setUp(self):
        self.saved = {name: sys.modules.get(name) for name in self.NAMES}
        self.uarts = []

    def tearDown(self):
        for uart in self.uarts:
            uart.close()
        for name, module in self.saved.items():
            if module is None:
                sys.modules.pop(name, None)
            else:
                sys.modules[name] = module

    def install(self, binding):
        for name in self.NAMES:
            sys.modules[name] = binding  # None: "import hid" raises ImportError
        return binding

    def port(self, port="hid", wake_ms=busservo_hid.WAKE_MS):
        uart = busservo_hid.hid_port(port, wake_ms)
        self.uarts.append(uart)
        return uart

    def oserror(self, call, *args):
        with self.assertRaises(OSError) as caught:
            call(*args)
        e = caught.exception
        self.assertEqual(len(e.args), 2, "an OSError with its errno and its words: %r" % e)
        return e


class Finding(WithBinding):
    def test_ports_lists_the_controllers_as_the_port_the_command_takes(self):
        other = Controller("/dev/hidraw0", vid=0x046D, pid=0xC52B)  # a mouse
        second = Controller("/dev/hidraw7")
        second.serial = ""
        self.install(Binding(second, other, Controller(XARM)))
        self.assertEqual(
            busservo_hid.ports(),
            [
                ("hid:/dev/hidraw3", "MyUSB_HID LOBOT (USB HID 0483:5750, serial 497223563535)"),
                ("hid:/dev/hidraw7", "MyUSB_HID LOBOT (USB HID 0483:5750)"),
            ],
        )
        self.assertEqual((busservo_hid.VID, busservo_hid.PID), (0x0483, 0x5750))
        # "hid" is the first of them; "hid:<path>" that one.
        self.assertEqual(self.port().port, "hid:/dev/hidraw3")
        self.assertEqual(self.port("hid:/dev/hidraw7").port, "hid:/dev/hidraw7")

    def test_hid_is_the_first_in_the_order_of_the_paths_numbers(self):
        # hidraw3 before hidraw10, as a person counts (string order opened hidraw10 first:
        # issue 42), and `busservo check hid` names the one it opened.
        sim = busservo_sim.SimController(baudrate=None)
        self.install(Binding(Controller("/dev/hidraw10"), Controller("/dev/hidraw3", sim=sim)))
        self.assertEqual(
            [port for port, _ in busservo_hid.ports()], ["hid:/dev/hidraw3", "hid:/dev/hidraw10"]
        )
        from test_host import busservo_command

        status, out, err = busservo_command("check", "hid")
        self.assertEqual(status, 0, out + err)
        self.assertEqual(out.split("\n")[0], "the HID controller at hid:/dev/hidraw3")

    def test_a_path_that_is_not_text_comes_back_byte_for_byte(self):
        c = Controller()
        c.path = b"\\\\?\\hid#vid_0483&pid_5750#\xff"
        self.install(Binding(c))
        ((port, _),) = busservo_hid.ports()
        self.assertEqual(self.port(port).port, port)

    def test_without_the_binding_ports_is_empty_and_hid_port_says_what_to_install(self):
        self.install(None)
        self.assertEqual(busservo_hid.ports(), [])
        e = self.oserror(busservo_hid.hid_port)
        self.assertEqual(e.errno, errno.ENOENT)
        self.assertIn('pip install ".[hid]"', e.strerror)

    def test_another_module_named_hid_is_named(self):
        class CtypesHid:  # the `hid` package: hid.Device, no hid.device
            __file__ = "/site-packages/hid/__init__.py"

            def enumerate(self, vid=0, pid=0):
                return []

        self.install(CtypesHid())
        self.assertEqual(busservo_hid.ports(), [])
        e = self.oserror(busservo_hid.hid_port)
        self.assertIn("/site-packages/hid/__init__.py", e.strerror)
        self.assertIn('pip install ".[hid]"', e.strerror)

    def test_nothing_plugged_in(self):
        self.install(Binding(Controller("/dev/hidraw0", vid=0x046D, pid=0xC52B)))
        self.assertEqual(busservo_hid.ports(), [])
        e = self.oserror(busservo_hid.hid_port)
        self.assertEqual(e.errno, errno.ENOENT)
        self.assertIn("plug its USB cable in", e.strerror)
        e = self.oserror(busservo_hid.hid_port, "hid:/dev/hidraw9")
        self.assertEqual(e.errno, errno.ENOENT)
        self.assertIn("no such port hid:/dev/hidraw9", e.strerror)

    def test_a_port_that_is_no_hid_port_is_a_value_error(self):
        self.install(Binding(Controller()))
        for port in ("/dev/ttyUSB0", "COM3", "HID", 3, None):
            with self.assertRaises(ValueError) as caught:
                busservo_hid.hid_port(port)
            self.assertIn("'hid' or 'hid:<path>'", str(caught.exception))
            self.assertIn(repr(port), str(caught.exception))
        self.assertEqual(self.install(Binding()).devices, [])  # nothing was opened

    def test_no_permission_on_linux_names_the_udev_rule(self):
        # A hidraw device listed, that this user may not open (root's alone by default).
        c = Controller("/dev/hidraw-busservo-test")  # no such file: no access to it either
        c.denied = True
        self.install(Binding(c))
        e = self.oserror(busservo_hid.hid_port)
        self.assertEqual(e.errno, errno.EACCES)
        self.assertIn(busservo_hid.UDEV_RULE, e.strerror)
        self.assertIn("udevadm", e.strerror)

    def test_a_device_that_will_not_open_says_so(self):
        c = Controller("DevSrvsID:4294969371")  # macOS's kind of path: another program has it
        c.denied = True
        self.install(Binding(c))
        e = self.oserror(busservo_hid.hid_port)
        self.assertEqual(e.errno, errno.EIO)
        self.assertIn("could not open hid:DevSrvsID:4294969371", e.strerror)


class Reports(WithBinding):
    def setUp(self):
        super().setUp()
        self.xarm = Controller()
        self.binding = self.install(Binding(self.xarm))
        self.uart = self.port(wake_ms=0)  # the reports alone: nothing answers them here

    def test_a_frame_is_one_report_behind_report_id_0_padded_to_64_bytes(self):
        self.assertEqual(self.uart.write(GET_BATTERY), 4)
        self.assertEqual(self.xarm.got, [report(GET_BATTERY)])
        self.assertEqual(len(self.xarm.got[0]), 65)

    def test_a_frame_written_in_parts_goes_whole_in_one_report(self):
        move = bytes.fromhex("5555080301e803012003")
        self.assertEqual(self.uart.write(move, 3), 3)  # write(buf, n)
        self.assertEqual(self.uart.write(move, 3, 1), 1)  # write(buf, off, n)
        self.assertEqual(self.xarm.got, [])  # not whole yet: nothing sent
        self.assertEqual(self.uart.write(memoryview(move)[4:]), 6)
        self.assertEqual(self.xarm.got, [report(move)])
        self.assertEqual(self.uart.write(b""), 0)
        self.assertEqual(self.uart.write(move, 0, 0), 0)
        self.assertEqual(len(self.xarm.got), 1)

    def test_frames_written_together_go_one_a_report(self):
        stop = bytes.fromhex("55550207")
        self.assertEqual(self.uart.write(GET_BATTERY + stop + GET_BATTERY[:2]), 10)
        self.assertEqual(self.xarm.got, [report(GET_BATTERY), report(stop)])
        self.uart.write(GET_BATTERY[2:])
        self.assertEqual(self.xarm.frames_got(), [GET_BATTERY, stop, GET_BATTERY])

    def test_bytes_that_start_no_frame_go_as_they_are(self):
        self.uart.write(b"\x01\x02" + GET_BATTERY)
        self.assertEqual(self.xarm.got, [bytes(1) + b"\x01\x02" + bytes(62), report(GET_BATTERY)])

    def test_a_frame_longer_than_a_report_is_refused_and_nothing_sent(self):
        bus = busservo.BusServo(self.uart)
        nineteen = [(i, 500) for i in range(1, 20)]
        bus.move_many(nineteen, 1000)  # 64 bytes: fits
        self.assertEqual(len(self.xarm.got), 1)
        self.assertEqual(self.xarm.got[0][-3:], bytes.fromhex("13f401"))  # servo 19 at 500
        e = self.oserror(bus.move_many, nineteen + [(20, 500)], 1000)
        self.assertEqual(e.errno, errno.EMSGSIZE)
        self.assertIn("67 bytes", e.strerror)
        self.assertEqual(len(self.xarm.got), 1)
        bus.move(1, 800, 1000)  # the next command goes as it should
        self.assertEqual(self.xarm.frames_got()[1], bytes.fromhex("5555080301e803012003"))

    def test_a_reply_padded_as_a_real_one_comes_without_its_padding(self):
        for pad in (0, 0xAA, 0x55):  # zeros, or what the last report left
            self.xarm.reports.append(BATTERY_7500 + bytes([pad]) * 58)
            self.assertEqual(self.uart.any(), 6)
            self.assertEqual(self.uart.read(), BATTERY_7500)
            self.assertEqual(self.uart.any(), 0)

    def test_a_report_id_before_the_frame_is_dropped(self):
        self.xarm.reports.append(bytes(1) + BATTERY_7500 + bytes(57))
        self.assertEqual(self.uart.read(), BATTERY_7500)

    def test_a_reply_longer_than_a_report_goes_on_in_the_next(self):
        ids = list(range(1, 31))  # 30 positions: 95 bytes, two reports
        reply = bytes((0x55, 0x55, 93, CMD_MULT_SERVO_POS_READ, 30))
        for i in ids:
            reply += bytes((i, 0xF4, 0x01))
        self.assertEqual(len(reply), 95)
        self.xarm.reports += [reply[:64], reply[64:] + bytes(33), BATTERY_7500 + bytes(58)]
        self.assertEqual(self.uart.read(), reply + BATTERY_7500)

    def test_a_frame_s_rest_is_taken_by_its_length_not_by_its_padding(self):
        # The rest of a long reply in the next report is as many bytes as its Length says:
        # its last servo at 200 (C8 00: a zero, as padding is), or a controller that pads
        # with 55, and the reply came cut, or with a frame's start of padding behind it (a
        # rest taken as noise passed every test once: issue 41).
        for n in (20, 59):  # 65 bytes, two reports; 182, three
            reply = bytes((0x55, 0x55, 3 * n + 3, CMD_MULT_SERVO_POS_READ, n))
            for i in range(1, n + 1):
                reply += bytes((i, 0xC8, 0x00))  # 200
            for pad in (0, 0x55, 0xFF):
                for at in range(0, len(reply), 64):
                    part = reply[at : at + 64]
                    self.xarm.reports.append(part + bytes([pad]) * (64 - len(part)))
                self.xarm.reports.append(BATTERY_7500 + bytes([pad]) * 58)
                self.assertEqual(self.uart.read(), reply + BATTERY_7500, (n, pad))

    def test_a_report_that_starts_no_frame_is_noise_for_the_driver(self):
        self.xarm.reports += [b"\x01\x02\x03" + bytes(61), BATTERY_7500 + bytes(58)]
        bus = busservo.BusServo(self.uart)
        self.assertEqual(bus.poll(), CMD_GET_BATTERY_VOLTAGE)
        self.assertEqual(bus.noise, 3)

    def test_any_and_readinto_never_wait(self):
        device = self.binding.devices[0]
        self.assertEqual(device.nonblocking, 1)  # and Device.read() checks each read
        self.addCleanup(lambda: self.assertEqual(device.waits, 0))
        self.assertEqual(self.uart.any(), 0)
        buf = bytearray(16)
        self.assertIsNone(self.uart.readinto(buf))  # nothing came: None, as a UART says
        self.assertIsNone(self.uart.read())
        self.xarm.reports.append(BATTERY_7500 + bytes(58))
        self.assertEqual(self.uart.readinto(buf, 4), 4)  # readinto(buf, n)
        self.assertEqual(bytes(buf[:4]), BATTERY_7500[:4])
        self.assertEqual(self.uart.read(5), BATTERY_7500[4:])

    def test_a_flood_of_reports_is_read_a_bounded_amount_a_call(self):
        self.xarm.reports += [bytes(64)] * 10000  # a device that sends nothing but reports
        self.assertEqual(self.uart.any(), 0)
        self.assertLess(self.binding.devices[0].reads, 10000)

    def test_unplugged_mid_session_is_enodev_that_says_so(self):
        self.xarm.plugged = False
        e = self.oserror(self.uart.any)
        self.assertEqual(e.errno, errno.ENODEV)
        self.assertIn("hid:/dev/hidraw3 is gone (unplugged?)", e.strerror)
        for call, args in ((self.uart.any, ()), (self.uart.write, (GET_BATTERY,))):
            self.assertEqual(self.oserror(call, *args).errno, errno.ENODEV)  # and stays so
        self.assertTrue(self.binding.devices[0].closed)

    def test_a_write_that_fails_is_enodev_with_hidapis_words(self):
        bus = busservo.BusServo(self.uart)
        self.xarm.plugged = False
        e = self.oserror(bus.move, 1, 800, 1000)
        self.assertEqual(e.errno, errno.ENODEV)
        self.assertIn("No such device", e.strerror)

    def test_close_deinit_the_context_manager_and_repr(self):
        with busservo_hid.hid_port() as uart:
            self.assertEqual(repr(uart), "<busservo_hid.HidUART hid:/dev/hidraw3>")
        device = self.binding.devices[-1]
        self.assertTrue(device.closed)
        e = self.oserror(uart.write, GET_BATTERY)
        self.assertEqual(e.errno, errno.EBADF)
        self.assertIn("closed", e.strerror)
        self.uart.deinit()
        self.assertTrue(self.binding.devices[0].closed)
        self.uart.close()  # twice: nothing happens


class Driver(WithBinding):
    """The driver over a HID controller that answers at USB speed: no 9600-baud line."""

    def setUp(self):
        super().setUp()
        self.sim = busservo_sim.SimController(baudrate=None)
        self.xarm = Controller(sim=self.sim)
        self.install(Binding(self.xarm))
        self.bus = busservo.BusServo(self.port())
        # hid_port() asked for the battery until the controller answered: once, here.
        self.assertEqual(self.xarm.frames_got(), [GET_BATTERY])
        self.xarm.got.clear()

    def test_read_battery(self):
        self.assertEqual(self.bus.read_battery(), 7500)
        self.assertEqual(self.xarm.got, [report(GET_BATTERY)])
        self.assertIsNone(self.bus.poll())
        self.assertEqual(self.bus.noise, 0)

    def test_read_positions(self):
        self.assertEqual(self.bus.read_positions([1, 2, 3, 4, 5, 6]), ALL_500)
        self.assertEqual(self.xarm.frames_got(), [bytes.fromhex("5555091506010203040506")])
        self.assertEqual(self.bus.noise, 0)

    def test_a_reply_over_three_reports(self):
        ids = list(range(1, 60))  # 59 ids: the most a request fits; a reply of 182 bytes
        got = self.bus.read_positions(ids)
        self.assertEqual(got, {i: 500 for i in ids})
        self.assertEqual(self.bus.noise, 0)

    def test_padding_left_from_the_last_report_is_not_read(self):
        self.xarm.pad = 0x55
        self.assertEqual(self.bus.read_positions([1, 2]), {1: 500, 2: 500})
        self.assertEqual(self.bus.read_battery(), 7500)
        self.assertEqual(self.bus.noise, 0)

    def test_requests_answered_through_poll(self):
        self.bus.request_positions([1, 2])
        self.assertEqual(self.bus.poll(), CMD_MULT_SERVO_POS_READ)
        self.assertEqual(self.bus.positions, {1: 500, 2: 500})
        self.bus.request_battery()
        self.assertEqual(self.bus.poll(), CMD_GET_BATTERY_VOLTAGE)
        self.assertEqual(self.bus.battery, 7500)
        self.assertIsNone(self.bus.poll())

    def test_busservo_async_queries(self):
        bus = busservo_async.AsyncBusServo(self.bus)

        async def main():
            return await bus.read_battery(), await bus.read_positions([1, 2, 3])

        self.assertEqual(asyncio.run(main()), (7500, {1: 500, 2: 500, 3: 500}))

    def test_moves_and_group_commands_reach_it_as_their_reports(self):
        bus = self.bus
        bus.move(1, 800, 1000)
        bus.move_many([(2, 100), (3, 900)], 500)
        bus.unload([4, 5])
        bus.set_group_speed(8, 200)
        bus.run_group(8, 1)
        bus.stop_group()
        self.assertEqual(
            self.xarm.got,
            [
                report(bytes.fromhex(f))
                for f in (
                    "5555080301e803012003",
                    "55550b0302f401026400038403",
                    "55550514020405",
                    "5555050b08c800",
                    "55550506080100",
                    "55550207",
                )
            ],
        )
        self.assertEqual(self.sim.speed(8), 200)
        self.assertEqual(self.sim.limp, {4, 5})
        # The controller's frames: RUN as the group starts, STOP as it is stopped.
        self.assertEqual(bus.poll(), CMD_ACTION_GROUP_RUN)
        self.assertEqual(bus.poll(), busservo.CMD_ACTION_GROUP_STOP)
        self.assertFalse(bus.running)

    def test_every_reply_is_early_and_a_late_one_is_not_the_next_answer(self):
        # At USB speed every reply comes sooner than 9600 baud allows: counted, and taken.
        self.assertEqual(self.bus.read_battery(), 7500)
        self.assertEqual(self.bus.read_positions([1, 2]), {1: 500, 2: 500})
        self.assertEqual(self.bus.early, 2)
        # The next battery request goes unanswered; its reply (7000) comes only once the one
        # after it is asked, right before that one's own: the query takes its own.
        asked = []

        def script(frame):
            asked.append(frame)
            if len(asked) == 1:
                return []
            return [bytes.fromhex("5555040f581b") + bytes(58), BATTERY_7500 + bytes(58)]

        self.xarm.script = script
        with self.assertRaises(OSError) as caught:
            self.bus.read_battery()
        self.assertEqual(caught.exception.errno, errno.ETIMEDOUT)
        self.assertEqual(self.bus.read_battery(), 7500)
        self.assertEqual(asked, [GET_BATTERY, GET_BATTERY])

    def test_a_group_runs_to_its_end(self):
        self.sim.groups[1] = 0  # a group that ends at once
        self.bus.run_group(1, 1)
        self.assertEqual(self.bus.poll(), CMD_ACTION_GROUP_RUN)
        self.assertEqual(self.bus.poll(), CMD_ACTION_GROUP_COMPLETE)
        self.assertEqual((self.bus.group, self.bus.times, self.bus.running), (1, 1, False))


class JustSwitchedOn(WithBinding):
    """A controller that leaves its first second unanswered, as one just switched on or
    plugged in may (the public xArm library retries its battery read for 5 s)."""

    def setUp(self):
        super().setUp()
        self.xarm = Controller(sim=busservo_sim.SimController(baudrate=None))
        self.xarm.deaf_s = 1.0
        self.install(Binding(self.xarm))

    def test_hid_port_asks_until_it_answers_and_the_first_read_is_answered(self):
        # docs/computer.md's snippet: a read right after hid_port(). It raised TimeoutError.
        start = time.monotonic()
        bus = busservo.BusServo(self.port())
        woke = time.monotonic() - start
        self.assertEqual(bus.read_battery(), 7500)
        self.assertTrue(1.0 <= woke < 2.0, woke)
        asks = self.xarm.frames_got()
        self.assertEqual(set(asks), {GET_BATTERY})
        self.assertTrue(4 <= len(asks) <= 8, len(asks))  # every 250 ms, then the read's
        self.assertIsNone(bus.poll())  # its answers to the asks are not events
        self.assertEqual((bus.noise, bus.early), (0, 1))

    def test_without_asking_the_first_read_finds_it_silent(self):
        bus = busservo.BusServo(self.port(wake_ms=0))
        with self.assertRaises(OSError):
            bus.read_battery()
        self.assertEqual(self.xarm.frames_got(), [GET_BATTERY])

    def test_one_that_never_answers_is_opened_all_the_same(self):
        # Asked for wake_ms, then open: its first query says it does not answer.
        self.xarm.deaf_s = 3600
        start = time.monotonic()
        uart = self.port(wake_ms=600)
        self.assertTrue(0.6 <= time.monotonic() - start < 1.5)
        self.assertFalse(uart.wake(0))
        with self.assertRaises(OSError):
            busservo.BusServo(uart).read_battery()


class Package(unittest.TestCase):
    def test_pip_install_dot_hid_pins_the_binding_and_installs_the_module(self):
        with open("pyproject.toml") as f:
            text = f.read()
        with open("tests/run.sh") as f:
            run = f.read()
        pinned = text.split("[project.optional-dependencies]")[1].split("\n")[1]
        self.assertTrue(pinned.startswith('hid = ["hidapi==%s"]' % hidapi_version(run)), pinned)
        self.assertIn('"busservo_hid",', text.split("py-modules")[1].split("]")[0])

    def test_the_docs_give_the_rule_the_module_gives(self):
        with open("docs/computer.md") as f:
            text = f.read()
        self.assertIn(busservo_hid.UDEV_RULE, text)
        self.assertIn('pip install ".[hid]"', text)


def hidapi_version(run_sh):
    # The version tests/run.sh installs for this module: pip_install hidapi hid VERSION ...
    return run_sh.split("pip_install hidapi hid ")[1].split()[0]


class RealBinding(unittest.TestCase):
    """cython-hidapi itself (tests/run.sh installs it for this module), with nothing plugged
    in: this machine has no controller."""

    def setUp(self):
        try:
            self.hid = busservo_hid._binding()
        except OSError as e:
            self.skipTest(e.strerror)

    def test_it_is_the_pinned_version_and_lists_nothing(self):
        import hid

        with open("tests/run.sh") as f:
            self.assertEqual(hid.__version__, hidapi_version(f.read()))
        plugged = self.hid.enumerate(busservo_hid.VID, busservo_hid.PID)
        if plugged:
            self.skipTest("a controller is plugged in here")
        self.assertEqual(busservo_hid.ports(), [])
        with self.assertRaises(OSError) as caught:
            busservo_hid.hid_port()
        self.assertEqual(caught.exception.errno, errno.ENOENT)
        with self.assertRaises(OSError) as caught:
            busservo_hid.hid_port("hid:/dev/hidraw-busservo-test")
        self.assertEqual(caught.exception.errno, errno.ENOENT)


if __name__ == "__main__":
    unittest.main()
