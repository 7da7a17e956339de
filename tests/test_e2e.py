# End to end: the simulated controller behind a pty in one process
# (sh boards/unix.sh --sim-pty), the driver in this one, talking through
# boards/unix.py as it would through a USB-serial adapter. Real time, real bytes.
import errno
import os
import time
import unittest

import busservo
from busservo import (
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_RUN,
    CMD_ACTION_GROUP_STOP,
)
from unix import uart

# Two processes and a pty on a machine that may be busy: a generous timeout, so
# that a slow round trip is not taken for a missing reply (a read once took more than
# 1 s in a fresh clone's run beside a mutation pass and three browser sessions).
TIMEOUT_MS = 3000


def wait_for(path, ms):
    start = time.ticks_ms()
    while time.ticks_diff(time.ticks_ms(), start) < ms:
        try:
            os.stat(path)
            return True
        except OSError:
            time.sleep_ms(20)
    return False


class EndToEnd(unittest.TestCase):
    def setUp(self):
        self.link = "/tmp/busservo-e2e-%s" % "".join("%02x" % b for b in os.urandom(6))
        os.system(
            "sh boards/unix.sh --sim-pty --link %s >%s.log 2>&1 & echo $! >%s.pid"
            % (self.link, self.link, self.link)
        )
        self.assertTrue(wait_for(self.link, 10000), "the simulator did not start")
        self.uart = uart(self.link)
        self.bus = busservo.BusServo(self.uart)

    def tearDown(self):
        self.uart.close()
        os.system("kill $(cat {0}.pid) 2>/dev/null; rm -f {0}.pid {0}.log".format(self.link))

    def events_until(self, want, ms):
        got = []
        start = time.ticks_ms()
        while want not in got and time.ticks_diff(time.ticks_ms(), start) < ms:
            cmd = self.bus.poll()
            if cmd is not None:
                got.append(cmd)
        return got

    def test_move_and_read_back_during_and_after(self):
        bus = self.bus
        bus.move_many([(1, 900), (2, 100), (3, 500)], 1500)
        start = time.ticks_ms()
        time.sleep_ms(300)
        mid = bus.read_positions([1, 2, 3], TIMEOUT_MS)
        for _ in range(10):  # on a busy machine the simulator may take the move late
            if mid[1] != 500:
                break
            time.sleep_ms(100)
            mid = bus.read_positions([1, 2, 3], TIMEOUT_MS)
        self.assertTrue(500 < mid[1] < 900, mid)
        self.assertTrue(100 < mid[2] < 500, mid)
        self.assertEqual(mid[3], 500)
        time.sleep_ms(1600 - time.ticks_diff(time.ticks_ms(), start))
        # The move ends 1500 ms after the simulator took it: on a busy machine (other tests
        # beside these two processes) that can be later than 1500 ms after this one sent it.
        # So while it is still on its way, ask again 100 ms later, for 2 s at most.
        target = {1: 900, 2: 100, 3: 500}
        got = bus.read_positions([1, 2, 3], TIMEOUT_MS)
        for _ in range(20):
            if got == target:
                break
            on_its_way = mid[1] <= got[1] <= 900 and 100 <= got[2] <= mid[2] and got[3] == 500
            self.assertTrue(on_its_way and got != mid, (mid, got))
            mid = got
            time.sleep_ms(100)
            got = bus.read_positions([1, 2, 3], TIMEOUT_MS)
        self.assertEqual(got, target)
        self.assertEqual(bus.positions, {1: 900, 2: 100, 3: 500})

    def test_a_group_runs_and_completes(self):
        self.bus.run_group(1)  # 500 ms in the simulator
        got = self.events_until(CMD_ACTION_GROUP_COMPLETE, 5000)
        self.assertEqual(got, [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_COMPLETE])
        self.assertEqual((self.bus.running, self.bus.group, self.bus.times), (False, 1, 1))

    def test_a_forever_group_is_stopped(self):
        self.bus.run_group(2, 0)
        self.assertEqual(self.events_until(CMD_ACTION_GROUP_RUN, 5000), [CMD_ACTION_GROUP_RUN])
        self.assertTrue(self.bus.running)
        self.bus.stop_group()
        self.assertEqual(self.events_until(CMD_ACTION_GROUP_STOP, 5000), [CMD_ACTION_GROUP_STOP])
        self.assertFalse(self.bus.running)

    def test_battery_speed_and_unload(self):
        self.assertEqual(self.bus.read_battery(TIMEOUT_MS), 7500)
        self.bus.set_group_speed(2, 1000)  # 2000 ms at 1000 %: 200 ms
        self.bus.run_group(2)
        start = time.ticks_ms()
        self.events_until(CMD_ACTION_GROUP_COMPLETE, 5000)
        self.assertTrue(time.ticks_diff(time.ticks_ms(), start) < 1500)  # not 2000
        self.bus.move(4, 800, 0)
        self.bus.unload([4])
        self.assertEqual(self.bus.read_positions([4], TIMEOUT_MS), {4: 800})

    def test_a_silent_controller_times_out(self):
        self.uart.write(bytes((0x55, 0x55, 0x03, 0xF0, 0x01)))  # the simulator's "be silent"
        start = time.ticks_ms()
        try:
            self.bus.read_battery(timeout_ms=200)
        except OSError as e:
            self.assertEqual(e.args[0], errno.ETIMEDOUT)
        else:
            self.fail("no timeout")
        self.assertTrue(time.ticks_diff(time.ticks_ms(), start) >= 200)

    def test_a_hang_up_raises_eio_at_once(self):
        # The other end goes away (an unplugged adapter; here the pty's server):
        # the next call says so, rather than reading nothing for ever.
        self.assertEqual(self.bus.read_battery(TIMEOUT_MS), 7500)
        os.system("kill $(cat %s.pid)" % self.link)
        start = time.ticks_ms()
        error = None
        while error is None and time.ticks_diff(time.ticks_ms(), start) < 5000:
            try:
                self.bus.poll()
            except OSError as e:
                error = e
        self.assertIsNotNone(error, "no hang-up noticed")
        self.assertEqual(error.args[0], errno.EIO)
        self.assertIn("hung up", str(error))

    def test_writes_never_block_and_take_the_stream_protocols_forms(self):
        frame = b"xx" + bytes((0x55, 0x55, 0x02, 0x0F)) + b"yy"
        self.assertEqual(self.uart.write(frame, 2, 4), 4)  # a battery request
        self.assertEqual(self.events_until(busservo.CMD_GET_BATTERY_VOLTAGE, 2000), [15])
        start = time.ticks_ms()
        took = 0
        for _ in range(200):  # far more than the pty holds: it takes less, never waits
            took += self.uart.write(bytes(256)) or 0
        self.assertTrue(time.ticks_diff(time.ticks_ms(), start) < 1000)
        self.assertTrue(took < 200 * 256)


class NotATty(unittest.TestCase):
    def test_a_file_that_is_no_serial_device_is_refused_and_closed(self):
        path = "/tmp/busservo-not-a-tty-%s" % "".join("%02x" % b for b in os.urandom(4))
        with open(path, "w") as f:
            f.write("x")
        before = len(os.listdir("/proc/self/fd"))
        try:
            uart(path)
        except OSError as e:
            self.assertIn("not a serial device", str(e))
            self.assertIn(path, str(e))
        else:
            self.fail("a regular file was taken for a serial device")
        finally:
            os.remove(path)
        self.assertEqual(len(os.listdir("/proc/self/fd")), before)


if __name__ == "__main__":
    unittest.main()
