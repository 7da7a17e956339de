# The driver on a computer (CPython only: tests/run.sh runs this module in its CPython pass).
# pyserial on a pty with the simulated controller at the far end (sh boards/unix.sh
# --sim-pty), as a controller on USB is; the busservo command on good and bad input; and
# pip install . of a copy of the checkout into a scratch venv, then the command it installs.
import asyncio
import errno
import io
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import tty
import types
import unittest
from contextlib import redirect_stderr, redirect_stdout
from unittest import mock

import busservo
import busservo_host

PYTHON = sys.executable
ROOT = os.getcwd()  # tests start in the repository's root
CHECKED = "--i-have-checked-my-robot"


def busservo_command(*args):
    """`busservo ARGS` run in this process: (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        status = busservo_host.main([str(a) for a in args])
    return status, out.getvalue(), err.getvalue()


def at_a_terminal():
    # Ctrl-C's signal as at a terminal (a job in the background of tests/run.sh's shell
    # starts with it ignored).
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def command_process(*args, cwd=None):
    """`busservo ARGS` in a process of its own, its output read line by line."""
    return subprocess.Popen(
        [PYTHON, "-m", "busservo_host"] + [str(a) for a in args],
        env=dict(os.environ, PYTHONPATH=os.path.join(ROOT, "lib"), PYTHONUNBUFFERED="1"),
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=at_a_terminal,
    )


COMPLETE = bytes.fromhex("55550508010100")  # ACTION_GROUP_COMPLETE: group 1, once


class Peer:
    """A controller scripted in a thread at the far end of a pty (path), as one on a
    USB-serial adapter is: it answers the battery (7500 mV) and positions (500 each) after
    `delay` s (None: never, as a controller with its TX unplugged), and with `flood` sends
    ACTION_GROUP_COMPLETE frames back to back, at 9600 baud's pace, all along (for 30 s at
    most). `frames` holds every frame it was sent; `read_bps` paces its reading (None: all
    there is, at once). The default delay, 30 ms, is a real controller's on USB: the wire's
    time and the adapter's latency."""

    FLOOD_S = 30

    def __init__(self, delay=0.03, flood=False, read_bps=None, pause=0, garbled=False):
        self.delay = delay
        self.flood = flood
        self.read_bps = read_bps
        self.pause = pause  # s between each reply's first 5 bytes and the rest (a USB hand-over)
        self.garbled = garbled  # each reply's bytes as at another baud rate: no frame
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self.slave)
        self.frames = []
        self.received = 0  # bytes
        self.flooding = flood
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def wait(self, frame, seconds=3):
        """True once frame has come (the thread reads the pty a few ms behind the command)."""
        end = time.monotonic() + seconds
        while frame not in self.frames and time.monotonic() < end:
            time.sleep(0.005)
        return frame in self.frames

    def close(self):
        self._done.set()
        self._thread.join()
        os.close(self.master)
        os.close(self.slave)

    def _answer(self, frame):
        reply = self._reply(frame)
        if reply and self.garbled:
            return bytes(b ^ 0xF0 for b in reply)  # (no 0x55: never a frame's start)
        return reply

    def _reply(self, frame):
        if frame[3] == 0x0F:  # the battery
            return bytes.fromhex("5555040F4C1D")
        if frame[3] == 0x15:  # positions
            n = frame[4]
            reply = bytearray(b"\x55\x55" + bytes([3 * n + 3, 0x15, n]))
            for servo_id in frame[5 : 5 + n]:
                reply += bytes([servo_id, 500 & 0xFF, 500 >> 8])
            return bytes(reply)
        return None

    def _write(self, data):
        try:
            os.write(self.master, data)
        except BlockingIOError:
            pass  # nobody reads: dropped, as a line does

    def _run(self):
        start = time.monotonic()
        sent = 0  # flood bytes
        buf = bytearray()
        due = []  # [(when, reply)]
        while not self._done.is_set():
            select.select([self.master], [], [], 0.002)
            now = time.monotonic()
            try:
                got = os.read(self.master, 4096 if self.read_bps is None else 64)
            except OSError:  # BlockingIOError: nothing came
                got = b""
            self.received += len(got)
            buf += got
            if got and self.read_bps:
                time.sleep(len(got) / self.read_bps)
            while len(buf) >= 4:
                if buf[:2] != b"\x55\x55":
                    del buf[0]
                    continue
                end = buf[2] + 2
                if len(buf) < end:
                    break
                frame = bytes(buf[:end])
                del buf[:end]
                self.frames.append(frame)
                reply = self._answer(frame)
                if reply and self.delay is not None:
                    if self.pause:
                        due.append((now + self.delay, reply[:5]))
                        reply = reply[5:]
                    due.append((now + self.delay + self.pause, reply))
            while due and due[0][0] <= now:
                self._write(due.pop(0)[1])
            if self.flooding:
                if now - start > self.FLOOD_S:
                    self.flooding = False
                # 7 bytes at 9600 baud each 7.3 ms: none missing from the wire's pace
                while sent * 10 / 9600 <= now - start:
                    self._write(COMPLETE)
                    sent += len(COMPLETE)


class FloodUART:
    """A UART whose controller answers nothing and, from the first request on, sends
    ACTION_GROUP_COMPLETE frames back to back for 30 s: `bps` bytes a second by the clock
    (960: 9600 baud's pace), or with None as many as are asked for, always (faster than
    they are read). In this process, with no thread: the pace is the clock's alone."""

    FLOOD_S = 30

    def __init__(self, bps):
        self.bps = bps
        self.start = None  # the first write's time
        self.given = 0  # bytes read

    def flooding(self):
        return self.start is None or time.monotonic() - self.start < self.FLOOD_S

    def any(self):
        if self.start is None or not self.flooding():
            return 0
        if self.bps is None:
            return 64
        return int((time.monotonic() - self.start) * self.bps) - self.given

    def readinto(self, buf, nbytes=-1):
        n = min(len(buf) if nbytes < 0 else nbytes, self.any())
        if n <= 0:
            return None
        for i in range(n):
            buf[i] = COMPLETE[(self.given + i) % len(COMPLETE)]
        self.given += n
        return n

    def write(self, buf, off=None, nbytes=None):
        if self.start is None:
            self.start = time.monotonic()
        if nbytes is None:
            return off if off is not None else len(buf)
        return nbytes


class WithPeers(unittest.TestCase):
    def setUp(self):
        self.peers = []

    def tearDown(self):
        for peer in self.peers:
            peer.close()

    def peer(self, *args, **kwargs):
        peer = Peer(*args, **kwargs)
        self.peers.append(peer)
        return peer


def wait_for(path, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if os.path.exists(path):
            return True
        time.sleep(0.02)
    return False


class Scratch(unittest.TestCase):
    def setUp(self):
        self.scratch = tempfile.mkdtemp(prefix="busservo-host-")

    def tearDown(self):
        shutil.rmtree(self.scratch, ignore_errors=True)


class OnAPty(Scratch):
    """The simulated controller behind a pty, as a controller on a USB-serial adapter."""

    def setUp(self):
        super().setUp()
        self.link = os.path.join(self.scratch, "controller")
        self.sim = subprocess.Popen(
            ["sh", "boards/unix.sh", "--sim-pty", "--link", self.link],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        self.assertTrue(wait_for(self.link, 10), "the simulator did not start")
        self.uarts = []
        # The link comes as the simulator starts: its first answer says it is up (a loaded
        # machine may take seconds).
        with busservo_host.serial_port(self.link) as uart:
            bus = busservo.BusServo(uart)
            for _ in range(20):
                try:
                    bus.read_battery(timeout_ms=1000)
                    break
                except OSError as e:
                    if e.errno != errno.ETIMEDOUT:
                        raise

    def tearDown(self):
        for uart in self.uarts:
            uart.close()
        self.unplug()
        super().tearDown()

    def unplug(self):
        if self.sim.poll() is None:
            os.killpg(self.sim.pid, signal.SIGTERM)
            self.sim.wait()

    def port(self):
        uart = busservo_host.serial_port(self.link)
        self.uarts.append(uart)
        return uart

    def test_a_battery_read_and_a_move_end_to_end(self):
        bus = busservo.BusServo(self.port())
        self.assertEqual(bus.read_battery(timeout_ms=1000), 7500)
        bus.move_many([(1, 900), (2, 100)], 200)
        time.sleep(0.4)
        got = bus.read_positions([1, 2, 3, 4, 5, 6], timeout_ms=1000)
        self.assertEqual(got, {1: 900, 2: 100, 3: 500, 4: 500, 5: 500, 6: 500})
        self.assertEqual(bus.noise, 0)

    def test_the_port_is_9600_8n1_and_never_waits(self):
        uart = self.port()
        port = uart._port
        self.assertEqual(
            (port.baudrate, port.bytesize, port.parity, port.stopbits), (9600, 8, "N", 1)
        )
        self.assertEqual((port.timeout, port.write_timeout), (0, 0))
        self.assertEqual(uart.any(), 0)
        self.assertIsNone(uart.readinto(bytearray(16)))  # nothing came: None, as a UART says
        # write(buf, off, n): the driver's way of sending the rest of a frame.
        self.assertEqual(uart.write(b"xx\x55\x55\x02\x0fyy", 2, 4), 4)  # a battery request
        end = time.monotonic() + 2
        while uart.any() < 6 and time.monotonic() < end:
            time.sleep(0.01)
        buf = bytearray(16)
        self.assertEqual(uart.readinto(buf, 6), 6)
        self.assertEqual(bytes(buf[:6]), bytes.fromhex("5555040f4c1d"))  # 7500 mV

    def test_a_second_program_on_the_port_is_told_it_is_busy(self):
        self.port()
        with self.assertRaises(OSError) as caught:
            busservo_host.serial_port(self.link)
        self.assertEqual(caught.exception.errno, errno.EBUSY)
        self.assertIn("busy", str(caught.exception))

    def test_unplugged_mid_session_is_an_oserror_that_says_so(self):
        bus = busservo.BusServo(self.port())
        self.assertEqual(bus.read_battery(timeout_ms=1000), 7500)
        self.unplug()
        with self.assertRaises(OSError) as caught:
            bus.read_battery(timeout_ms=1000)
        self.assertEqual(caught.exception.errno, errno.ENODEV)
        self.assertIn("gone (unplugged?)", str(caught.exception))

    def test_the_command_checks_reads_and_moves_only_once_told(self):
        status, out, err = busservo_command("check", self.link)
        self.assertEqual(status, 0, out + err)
        self.assertIn("battery: 7.50 V", out)
        said = busservo_command("positions", self.link, 1, 2, 3)
        self.assertEqual(said, (0, "1: 500\n2: 500\n3: 500\n", ""))
        status, out, err = busservo_command("move", self.link, 1, 800, 100)
        self.assertEqual(status, 1, out + err)
        self.assertIn("nothing moved", out)
        self.assertIn(CHECKED, out)
        self.assertEqual(busservo_command("positions", self.link, 1), (0, "1: 500\n", ""))
        status, out, err = busservo_command("move", self.link, 1, 800, 100, CHECKED)
        self.assertEqual(status, 0, out + err)
        self.assertIn("servo 1 is at 800", out)

    def test_a_port_that_vanishes_mid_command_fails_saying_so(self):
        command = subprocess.Popen(
            [PYTHON, "-m", "busservo_host", "move", self.link, "1", "800", "1500", CHECKED],
            env=dict(os.environ, PYTHONPATH="lib", PYTHONUNBUFFERED="1"),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        said = command.stdout.readline()  # said as the move starts
        self.assertIn("this moves it to 800", said)
        time.sleep(0.3)
        self.unplug()
        out, err = command.communicate(timeout=10)
        self.assertEqual(command.returncode, 1, out + err)
        self.assertIn("is gone (unplugged?)", err)
        self.assertNotIn("Traceback", err)

    def test_ctrl_c_sigterm_and_sighup_stop_a_move_where_the_servo_is(self):
        # As the panel's STOP does: where it is, read, is where it goes (not on to 900).
        # SIGTERM and SIGHUP (the terminal closed) as Ctrl-C: before issue 41 they ended
        # the command with no stop (exit -15, -1), and the servo went on to 900.
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            move = command_process("move", self.link, 1, 900, 20000, CHECKED)
            try:
                self.assertIn("this moves it to 900", move.stdout.readline())
                time.sleep(0.5)
                move.send_signal(sig)
                out, err = move.communicate(timeout=10)
            finally:
                move.kill()
                move.wait()
            self.assertEqual(move.returncode, 130, (sig, out + err))
            self.assertIn("stopped: servo 1 holds at", out)
            time.sleep(0.3)  # the stop's own 100 ms
            status, first, _ = busservo_command("positions", self.link, 1)
            time.sleep(0.5)  # 10 positions more on the way to 900, had it gone on
            self.assertEqual(busservo_command("positions", self.link, 1), (0, first, ""), sig)
            self.assertLess(int(first.split()[1]), 900)
            self.assertIn("holds at %s" % first.split()[1], out)

    def test_ctrl_c_stops_an_action_group_and_stop_stops_one_left_running(self):
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):  # each as Ctrl-C
            group = command_process("group", self.link, 2, 0, CHECKED)  # until stopped
            try:
                self.assertIn("action group 2 runs until stopped", group.stdout.readline())
                group.send_signal(sig)
                out, err = group.communicate(timeout=10)
            finally:
                group.kill()
                group.wait()
            self.assertEqual(group.returncode, 130, (sig, out + err))
            self.assertIn("stopped action group 2", out)
            self.assertEqual(
                busservo_command("stop", self.link), (0, "no action group was running\n", "")
            )
        # A group left running (its command killed): stop stops it.
        group = command_process("group", self.link, 2, 0, CHECKED)
        try:
            self.assertIn("runs until stopped", group.stdout.readline())
        finally:
            group.kill()
            group.wait()
        status, out, err = busservo_command("stop", self.link)
        self.assertEqual((status, out), (0, "stopped the action group that ran\n"), err)

    def test_a_group_started_while_another_runs_runs(self):
        # The controller stops the group that runs (STOP), then starts the one asked (RUN):
        # the command took the STOP for its own group's and said it did not start (exit 1,
        # while it ran: until issue 41).
        group = command_process("group", self.link, 2, 0, CHECKED)  # until stopped
        try:
            self.assertIn("runs until stopped", group.stdout.readline())
        finally:
            group.kill()  # left running
            group.wait()
        status, out, err = busservo_command("group", self.link, 1, 1, CHECKED)  # 500 ms
        self.assertEqual(status, 0, out + err)
        self.assertEqual(
            out,
            "(the action group that ran is stopped for it)\n"
            "action group 1 runs once (Ctrl-C stops it)\naction group 1 done\n",
        )
        self.assertEqual(
            busservo_command("stop", self.link), (0, "no action group was running\n", "")
        )

    def test_a_group_runs_once_told_and_says_when_it_is_done(self):
        status, out, err = busservo_command("group", self.link, 1)
        self.assertEqual(status, 1, out + err)
        self.assertIn("nothing moved", out)
        self.assertIn(CHECKED, out)
        self.assertEqual(busservo_command("stop", self.link)[1], "no action group was running\n")
        status, out, err = busservo_command("group", self.link, 1, 2, CHECKED)  # 2 x 500 ms
        self.assertEqual(status, 0, out + err)
        self.assertEqual(
            out, "action group 1 runs 2 times (Ctrl-C stops it)\naction group 1 done\n"
        )
        status, out, err = busservo_command("group", self.link, 7, CHECKED)  # no group 7
        self.assertEqual(status, 1, out + err)
        self.assertIn("action group 7 did not start", out)

    def test_the_panel_caps_each_joints_dps_on_a_real_controller(self):
        # A slider dragged fast would whip the arm: on a real controller each joint turns
        # at 30 degrees a second at most; the simulated one needs no such care.
        import busservo_web

        served = []

        async def serve(robot, password, port=80, arm=None, path="robot.json", host="0.0.0.0"):
            served.append((robot, port, host))

        with mock.patch.object(busservo_web, "serve", serve):
            status, out, err = busservo_command(
                "panel", self.link, "--password", "a password!", "--port", 8123, CHECKED
            )
            self.assertEqual(status, 0, out + err)
            robot, port, host = served.pop()
            self.assertEqual((port, host), (8123, "0.0.0.0"))  # every interface, by default
            self.assertEqual(
                {name: robot.joints[name].dps for name in robot.names},
                {"base": 30, "shoulder": 30, "elbow": 30, "claw": 30},
            )
            status, out, err = busservo_command(
                "panel", "--sim", "--password", "a password!", "--host", "127.0.0.1"
            )
            self.assertEqual(status, 0, out + err)
            robot, port, host = served.pop()
            self.assertEqual((port, host), (8080, "127.0.0.1"))
            self.assertEqual({robot.joints[name].dps for name in robot.names}, {None})

    def test_play_and_teleop_move_nothing_until_told(self):
        here = os.getcwd()
        os.chdir(self.scratch)
        try:
            write_recording("wave.jsonl", seconds=1)
            leader, follower = write_calibrations(self.scratch)
            for command in (
                ("play", self.link, "wave.jsonl"),
                (
                    "teleop",
                    self.link,
                    "--leader-calibration",
                    leader,
                    "--follower-calibration",
                    follower,
                ),
            ):
                status, out, err = busservo_command(*command)
                self.assertEqual(status, 1, out + err)
                self.assertIn("500", out)  # where the servos are, read first
                self.assertIn("this ", out)  # what it would do
                self.assertIn("nothing moved", out)
                self.assertIn(CHECKED, out)
        finally:
            os.chdir(here)
        self.assertEqual(
            busservo_command("positions", self.link, 1, 4),
            (0, "1: 500\n4: 500\n", ""),
        )

    def test_ctrl_c_sigterm_and_sighup_stop_a_recording_playing_where_the_servo_is(self):
        # The base turns 0..90 degrees over 10 s (500..875): stopped 1.5 s in, it holds there.
        path = os.path.join(self.scratch, "slow.jsonl")
        write_recording(path, seconds=10, degrees=90)
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            play = command_process("play", self.link, path, CHECKED, cwd=self.scratch)
            said = read_until(play, "playing (Ctrl-C stops it)")
            time.sleep(1.5)
            status, out, err = ctrl_c(play, sig)
            self.assertEqual(status, 130, (sig, said + out + err))
            self.assertIn("stopped at sample ", out)
            time.sleep(0.3)  # the stop's own 100 ms
            _, first, _ = busservo_command("positions", self.link, 1)
            time.sleep(0.5)  # 20 positions more on the way, had it gone on
            self.assertEqual(busservo_command("positions", self.link, 1), (0, first, ""), sig)
            at = int(first.split()[1])
            self.assertTrue(500 < at < 875, first)
            self.assertIn("the servos hold at {1: %d" % at, out)

    def test_sigterm_and_sighup_end_every_command_as_ctrl_c_does(self):
        # Those that run until stopped, each ended by the signal: what Ctrl-C says, the same
        # exit status (record: 0, its normal end), no traceback. Before issue 41 scan and the
        # panel died of them (exit -15, -1), as move, group and play did (above).
        for command, started, stopped, status in (
            (("scan", self.link), "", "", 130),  # 254 ids at 9600 baud: 2 s
            (
                ("panel", "--sim", "--password", "a password!", "--port", free_tcp()),
                "(Ctrl-C stops the panel)",
                "",
                130,
            ),
            (("record", "--sim", "hand.rec"), "Ctrl-C ends it", "saved hand.rec", 0),
            (("teleop", "--sim"), "Ctrl-C stops it", "", 130),
        ):
            for sig in (signal.SIGTERM, signal.SIGHUP):
                process = command_process(*command, cwd=self.scratch)
                said = read_until(process, started)
                self.assertIn(started, said, command)
                time.sleep(0.3)
                code, out, err = ctrl_c(process, sig)
                self.assertEqual(code, status, (command, sig, said + out + err))
                self.assertIn(stopped, out, command)
                self.assertNotIn("Traceback", err, command)


class ScriptedPeers(WithPeers):
    """The command against a controller scripted in the test: silent, slow, or talking
    without a pause."""

    def assert_no_answer(self, command, said, came=False):
        # With came, frames came that answer nothing asked: said instead of the checklist.
        status, out, err = said
        self.assertEqual(status, 1, command)
        self.assertIn("no answer from the controller on %s within" % command[1], out + err)
        if came:
            self.assertIn("bytes came, frames that answer nothing asked", out + err)
        else:
            self.assertIn("1. the controller is powered", out + err)
        self.assertNotIn("Traceback", err)

    def test_a_silent_controller_gets_the_checklist_from_each_command(self):
        # OSError(ETIMEDOUT) has its errno on CPython too: not "busservo: 110".
        port = self.peer(delay=None).path
        for command in (
            ("check", port),
            ("positions", port, 1, 2),
            ("move", port, 1, 800, 100, CHECKED),
            ("panel", port, "--password", "a password!", CHECKED),
            ("scan", port),
            ("limp", port, 1),
            ("group", port, 1, CHECKED),
            ("stop", port),
        ):
            self.assert_no_answer(command, busservo_command(*command))
        # How long it waited: 500 ms, and 10 ms more a servo asked.
        # On stderr, behind "busservo: ", as every command's error (check said it on stdout
        # alone, until issue 42).
        said = "no answer from the controller on %s within %d ms. Check:"
        status, out, err = busservo_command("check", port)
        self.assertEqual((err.split("\n")[0], out), ("busservo: " + said % (port, 500), ""))
        err = busservo_command("positions", port, 1, 2)[2]
        self.assertEqual(err.split("\n")[0], "busservo: " + said % (port, 520))

    def test_json_says_an_error_in_a_line_of_its_own(self):
        # --json promises a line on stdout: a failed command printed none (until issue 42).
        port = self.peer(delay=None).path
        for command in (("check", port), ("positions", port, 1, 2), ("move", port, 1, 2, 3)):
            status, out, err = busservo_command(*command, "--json")
            self.assertEqual(status, 1, command)
            self.assertEqual(len(out.splitlines()), 1, out)
            error = json.loads(out)["error"]
            self.assertTrue(error.startswith("no answer from the controller on %s" % port))
            self.assertIn("busservo: " + error.split("\n")[0], err)
        status, out, err = busservo_command("move", "--sim", 9, 2, 3, "--json")
        self.assertEqual(status, 1)
        self.assertEqual(
            json.loads(out), {"error": "servo 9 does not answer: its power, the bus cable, its id"}
        )

    def test_the_command_waits_for_a_controller_behind_usb(self):
        # USB adds its latency to the wire's (16 ms of an FTDI's timer, a busy computer):
        # 160 ms is beyond the driver's default timeout (100 ms, and 10 more a servo), within
        # the command's (500 ms) with room for a loaded machine's own delays (250 ms failed
        # once so, with the suite's modules four at a time on two cores).
        port = self.peer(delay=0.16).path
        self.assertEqual(busservo_command("positions", port, 1, 2), (0, "1: 500\n2: 500\n", ""))
        status, out, err = busservo_command("check", port)
        self.assertEqual(status, 0, out + err)
        self.assertIn("battery: 7.50 V", out)
        # --timeout: the user's, for each query.
        command = ("positions", port, 1, "--timeout", 50)
        self.assert_no_answer(command, busservo_command(*command))
        time.sleep(0.5)  # its reply, come late, goes by
        self.assertEqual(
            busservo_command("positions", port, 1, "--timeout", 2000), (0, "1: 500\n", "")
        )

    def test_a_query_ends_while_the_controller_talks_without_a_pause(self):
        # Frames that answer nothing, back to back: the query ends at its time all the
        # same, not when the line falls quiet, whether the frames come at the wire's pace
        # or faster than the driver reads them. On a pty, then (for a deterministic pace)
        # from a UART in this process.
        peer = self.peer(delay=None, flood=True)
        for command in (("check", peer.path), ("positions", peer.path, 1)):
            self.assert_no_answer(command, busservo_command(*command), came=True)
            self.assertTrue(peer.flooding, "the query ended only once the flood did")
        for bps in (960, None):
            for command in (("check", "flood"), ("positions", "flood", 1)):
                uart = FloodUART(bps)
                with mock.patch.object(busservo_host, "_open", return_value=uart):
                    self.assert_no_answer(command, busservo_command(*command), came=True)
                self.assertTrue(uart.flooding(), "%s: it ended once the flood did" % bps)

    def test_a_pause_inside_a_reply_on_a_pty_loses_nothing(self):
        # A pty hands bytes over at its far end's pace: no pause there says a frame was
        # cut. Each reply's first 5 bytes, then 150 ms later the rest (a busy machine's
        # pause, a USB hand-over): every query is answered. The driver took such a frame's
        # start for noise once the line had been quiet 20 ms and its missing bytes' time,
        # and then each reply's rest was noise too: `scan` said the wiring's checklist.
        port = self.peer(pause=0.15).path
        self.assertEqual(busservo_command("positions", port, 1, 2), (0, "1: 500\n2: 500\n", ""))
        status, out, err = busservo_command("scan", port)
        self.assertEqual((status, out), (0, "".join("%d: 500\n" % i for i in range(254))), err)
        status, out, err = busservo_command("check", port)
        self.assertEqual(status, 0, out + err)
        self.assertIn("battery: 7.50 V", out)

    def test_bytes_that_came_are_said_not_the_wiring_checklist(self):
        # A controller at another baud rate: its replies come, and make no frame. The words
        # say what came, and what to look at; the checklist of the wiring is for silence.
        # (--timeout 2000: the peer, a thread of this process, may answer late on a loaded
        # machine; 500 ms was missed once with two suites at once.)
        port = self.peer(garbled=True).path
        status, out, err = busservo_command("check", port, "--timeout", 2000)
        self.assertEqual(status, 1, out + err)
        self.assertIn(
            "no answer from the controller on %s within 2000 ms, though 6 bytes came, 6 of "
            "them no frame: the controller at another baud rate than 9600, or another "
            "program on the port" % port,
            err,
        )
        self.assertNotIn("Check:", err)
        status, out, err = busservo_command("positions", port, 1, 2, "--timeout", 2000)
        self.assertEqual(status, 1, out + err)
        self.assertIn("though 11 bytes came, 11 of them no frame", err)
        self.assertNotIn("Check:", err)

    def test_a_query_waits_in_the_os_not_in_a_loop(self):
        # The port waits for its bytes in select(), between the query's looks at it: a
        # silent controller's 200 ms cost about 100 waits of 2 ms, not a core spinning (it
        # spun before: 2.54 s of CPU in a 3 s wait).
        port = self.peer(delay=None).path
        waits = []
        real = select.select

        def counted(*args):
            if args[0] == [uart._fd]:  # (the peer's thread selects too)
                waits.append(args[3])
            return real(*args)

        with busservo_host.serial_port(port) as uart:
            bus = busservo.BusServo(uart)
            with mock.patch.object(busservo_host.select, "select", counted):
                with self.assertRaises(OSError):
                    bus.read_battery(200)
        self.assertTrue(20 <= len(waits) <= 110, len(waits))
        self.assertEqual(set(waits), {0.002})

    def test_limp_lets_the_servos_go(self):
        peer = self.peer()
        status, out, err = busservo_command("limp", peer.path, 1, 2, CHECKED)
        self.assertEqual(status, 0, out + err)
        self.assertEqual(
            out.split("\n")[-2],
            "servos 1, 2 are limp: turn them by hand; each holds again when moved",
        )
        self.assertTrue(peer.wait(bytes.fromhex("55550514020102")), peer.frames)  # UNLOAD 1, 2

    def test_nothing_moves_until_told(self):
        peer = self.peer()
        for command in (
            ("move", peer.path, 1, 800, 100),
            ("group", peer.path, 1),
            ("panel", peer.path, "--password", "a password!"),
        ):
            status, out, err = busservo_command(*command)
            self.assertEqual(status, 1, out + err)
            self.assertIn("nothing moved", out)
            self.assertIn("then add " + CHECKED, out)
        # What went: queries (battery 0F, positions 15) alone.
        self.assertEqual({frame[3] for frame in peer.frames}, {0x0F, 0x15})

    def test_nothing_goes_limp_until_told(self):
        # A limp arm falls under its own weight: limp and record ask for the flag, as what
        # moves does. They say where the servos are and which would go limp, and nothing
        # else goes: no UNLOAD (14), no recording's file.
        peer = self.peer()
        folder = tempfile.mkdtemp(prefix="busservo-host-")
        try:
            path = os.path.join(folder, "hand.rec")
            for command, servos in (
                (("limp", peer.path, 1, 2), "servos 1, 2"),
                (("record", peer.path, path), "servos [1, 2, 3, 4]"),
            ):
                status, out, err = busservo_command(*command)
                self.assertEqual(status, 1, out + err)
                self.assertIn("500", out)  # where the servos are, read first
                self.assertIn(servos, out)
                self.assertIn("go limp", out)
                self.assertIn("nothing went limp", out)
                self.assertIn("then add " + CHECKED, out)
            self.assertFalse(os.path.exists(path))
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        self.assertEqual({frame[3] for frame in peer.frames}, {0x0F, 0x15})

    def test_a_full_transmit_buffer_is_no_unplugged_port(self):
        # A burst of moves fills the OS's buffer faster than the line empties it: write()
        # takes what fits, or nothing (None), as a board's UART does, and the driver waits
        # for room; the port is not "gone".
        peer = self.peer(read_bps=20000)  # slower than the burst, faster than the wire
        uart = busservo_host.serial_port(peer.path)
        try:
            took = 10
            for _ in range(10000):  # up to 100 kB at once: more than the OS holds
                took = uart.write(bytes(10))
                if took is None:
                    break
            self.assertIsNone(took)
            bus = busservo.BusServo(uart)
            for i in range(2500):  # 25 kB more: the driver waits for room
                bus.move(1, i % 1000, 100)
            end = time.monotonic() + 60
            while len(peer.frames) < 2500 and time.monotonic() < end:
                time.sleep(0.05)
            self.assertEqual(len(peer.frames), 2500)  # each whole, none lost
            self.assertEqual(peer.frames[-1], bytes.fromhex("5555080301640001F301"))  # 499
        finally:
            uart.close()


class Latency(Scratch):
    """How late a serial port's bytes may come (busservo_host.latency_ms(), the port's
    latency_ms, which the driver's timing counts): a USB-serial chip's hand-overs and a busy
    computer's delay; at any pace on a pty."""

    def test_a_pty_is_at_any_pace_through_a_link_too(self):
        master, slave = os.openpty()
        try:
            path = os.ttyname(slave)
            self.assertIsNone(busservo_host.latency_ms(path))
            link = os.path.join(self.scratch, "controller")
            os.symlink(path, link)
            self.assertIsNone(busservo_host.latency_ms(link))
            with busservo_host.serial_port(link) as uart:
                self.assertIsNone(uart.latency_ms)
        finally:
            os.close(master)
            os.close(slave)

    def test_a_usb_chip_by_its_latency_timer_else_by_its_vendor(self):
        from serial.tools import list_ports

        def port(device, vid):
            p = types.SimpleNamespace(device=device, vid=vid, pid=vid and 1, description="")
            return p

        listed = []
        sysfs = {}
        real_open = open

        def fake_open(path, *args, **kwargs):
            if path in sysfs:
                return io.StringIO(sysfs[path])
            if path.startswith("/sys/bus/usb-serial/"):
                raise FileNotFoundError(path)
            return real_open(path, *args, **kwargs)

        busy = busservo_host.BUSY_MS
        with mock.patch.object(list_ports, "comports", lambda: listed), mock.patch(
            "builtins.open", fake_open
        ):
            for vid, want in ((0x0403, 16), (0x1A86, 4), (0x10C4, 16), (None, 0)):
                listed[:] = [port("/dev/ttyUSB7", vid)]
                self.assertEqual(busservo_host.latency_ms("/dev/ttyUSB7"), want + busy, vid)
            listed[:] = []  # not listed at all: as an unknown chip
            self.assertEqual(busservo_host.latency_ms("/dev/ttyUSB7"), 16 + busy)
            # Linux says an FTDI's timer (set to 1 ms here, as setserial's low_latency does).
            sysfs["/sys/bus/usb-serial/devices/ttyUSB7/latency_timer"] = "1\n"
            self.assertEqual(busservo_host.latency_ms("/dev/ttyUSB7"), 1 + busy)

    def test_the_unix_ports_board_file_and_the_links_models_say_the_same(self):
        # boards/unix.py runs on MicroPython and tests/wire.py on both: each keeps the number.
        import busservo_hid
        import wire

        with open("boards/unix.py") as f:
            unix = f.read()
        self.assertIn("_BUSY_MS = %d\n" % busservo_host.BUSY_MS, unix)
        self.assertIn("_HAND_OVER_MS = %d\n" % busservo_host._UNKNOWN_CHIP_MS, unix)
        self.assertEqual(wire.BUSY_MS, busservo_host.BUSY_MS)
        ftdi = wire.World("ftdi").uart.latency_ms
        self.assertEqual(ftdi, busservo_host._HAND_OVER_MS[0x0403] + busservo_host.BUSY_MS)
        self.assertEqual(busservo_hid.LATENCY_MS, 10 + busservo_host.BUSY_MS)


class CommandLine(Scratch):
    def test_no_such_port(self):
        missing = os.path.join(self.scratch, "ttyUSB9")
        for command in (("check", missing), ("positions", missing, 1), ("move", missing, 1, 2, 3)):
            status, out, err = busservo_command(*command)
            self.assertEqual(status, 1, command)
            self.assertEqual(
                err, "busservo: no such port %s (busservo ports lists those there are)\n" % missing
            )

    def test_bad_input_is_refused_before_anything_is_opened_or_moved(self):
        for command, words in (
            (("positions", "--sim", "x"), "an id must be a number in 0..254, got 'x'"),
            (("positions", "--sim"), "positions wants 1..84 ids, got 0"),
            (("move", "--sim", 300, 500, 1000), "ID must be a number in 0..254, got '300'"),
            (("move", "--sim", 1, 5000, 1000), "POS must be a number in 0..1000, got '5000'"),
            (("move", "--sim", 1, 500), "move wants ID POS MS"),
            (("move", "--sim", 1, 500, -1), "MS must be a number in 0..30000, got '-1'"),
            (("check",), "check wants a PORT"),
            (("panel", "--sim", "--password", "short"), "8 characters or more"),
            (("panel", "--sim", "--password", "long enough", "--port", "0"), "--port must be"),
            (("fly", "--sim"), "no command 'fly'"),
        ):
            status, out, err = busservo_command(*command)
            self.assertEqual((status, out), (2, ""), command)
            self.assertIn(words, err)
            self.assertIn("busservo --help", err)

    def test_the_simulated_controller(self):
        self.assertEqual(busservo_command("positions", "--sim", 1, 2)[:2], (0, "1: 500\n2: 500\n"))
        status, out, _ = busservo_command("move", "--sim", 1, 700, 50)  # nothing real to check
        self.assertEqual(status, 0)
        self.assertIn("servo 1 is at 700", out)
        status, out, _ = busservo_command("check", "--sim")
        self.assertEqual(status, 0)
        self.assertIn("battery: 7.50 V", out)

    def test_help_and_ports(self):
        status, out, _ = busservo_command("--help")
        self.assertEqual(status, 0)
        for command in ("ports", "check PORT", "positions PORT", "move PORT", "panel PORT"):
            self.assertIn("busservo " + command, out)
        self.assertEqual(busservo_command()[0], 2)
        self.assertEqual(busservo_command("ports")[0], 0)

    def test_version(self):
        for flag in ("--version", "-V"):
            self.assertEqual(
                busservo_command(flag), (0, "busservo %s\n" % busservo.__version__, "")
            )

    def test_the_limits_and_the_calibration_file_are_usage_errors_not_tracebacks(self):
        ids = range(1, 86)
        self.assertEqual(
            busservo_command("positions", "--sim", *ids),
            (2, "", "busservo: positions wants 1..84 ids, got 85 (busservo --help)\n"),
        )
        self.assertEqual(busservo_command("limp", "--sim", *range(253))[0], 2)
        here = os.getcwd()
        os.chdir(self.scratch)  # robot.json is read from the folder the command runs in
        try:
            for text, words in (
                ('{"links": {"upper_arm": 100}}', "robot.json: no 'joints' in it"),
                ('{"joints": ', "robot.json: not valid JSON"),
                ('{"joints": {"base": {"servo_id": 1, "speed": 2}}}', "robot.json: joint 'base'"),
                ('{"joints": {"base": {"servo_id": 300}}}', "servo_id must be"),
            ):
                with open("robot.json", "w") as f:
                    f.write(text)
                status, out, err = busservo_command("panel", "--sim", "--password", "long enough")
                self.assertEqual((status, out), (2, ""), text + err)
                self.assertIn(words, err)
                self.assertIn("mend it, or move it away", err)
            os.remove("robot.json")
            os.mkdir("robot.json")
            status, out, err = busservo_command("panel", "--sim", "--password", "long enough")
            self.assertEqual((status, err), (1, "busservo: robot.json: Is a directory\n"))
        finally:
            os.chdir(here)

    def test_a_file_or_a_folder_is_not_a_serial_port(self):
        path = os.path.join(self.scratch, "notes.txt")
        with open(path, "w") as f:
            f.write("not a port")
        for port, what in (
            (path, "is not a serial port but a file"),
            (self.scratch, "is not a serial port but a folder"),
            (os.devnull, "is not a serial port"),  # a device, but no tty
        ):
            for command in (("check", port), ("positions", port, 1)):
                self.assertEqual(
                    busservo_command(*command),
                    (
                        1,
                        "",
                        "busservo: %s %s (busservo ports lists those there are)\n" % (port, what),
                    ),
                )
            with self.assertRaises(OSError) as caught:
                busservo_host.serial_port(port)
            self.assertEqual(caught.exception.errno, errno.ENOTTY)

    def test_no_permission_on_the_port_is_the_dialout_hint_not_busy(self):
        # What pyserial raises when the OS refuses to open the port (here as root, who may
        # open anything, the refusal is os.open's, as a user outside dialout gets it).
        refused = PermissionError(errno.EACCES, "Permission denied")
        with mock.patch.object(os, "open", side_effect=refused):
            with self.assertRaises(OSError) as caught:
                busservo_host.serial_port("/dev/ttyUSB0")
        e = caught.exception
        self.assertEqual(e.errno, errno.EACCES)
        self.assertIn("no permission to open /dev/ttyUSB0", str(e))
        self.assertIn("sudo usermod -aG dialout $USER", str(e))
        self.assertNotIn("busy", str(e))

    def test_json(self):
        import json

        status, out, err = busservo_command("positions", "--sim", 1, 7, "--json")
        self.assertEqual((status, json.loads(out)), (1, {"1": 500, "7": None}))
        self.assertEqual(err, "1: 500\n7: no answer\n")  # the words, beside
        status, out, _ = busservo_command("--json", "scan", "--sim")
        self.assertEqual((status, json.loads(out)), (0, {str(i): 500 for i in range(1, 7)}))
        status, out, _ = busservo_command("check", "--sim", "--json")
        got = json.loads(out)
        self.assertEqual((status, got["battery_mv"], got["noise"]), (0, 7500, 0))
        self.assertGreater(got["round_trip_ms"], 0)
        status, out, _ = busservo_command("move", "--sim", 2, 600, 50, "--json")
        self.assertEqual(json.loads(out), {"servo": 2, "from": 500, "to": 600, "at": 600})
        status, out, _ = busservo_command("ports", "--json")
        self.assertIsInstance(json.loads(out), list)

    def test_a_reader_that_goes_away_ends_nothing_and_says_nothing(self):
        # busservo --help | head -1: the reader gone, the command printed "busservo: Broken
        # pipe" and ended, exit 1 (until issue 42); a group it had started ran on. Now what
        # it says goes nowhere, quietly, and it ends as it would.
        for command, status in (
            (("--help",), 0),
            (("scan", "--sim"), 0),
            (("positions", "--sim", 1, 7), 1),
            (("group", "--sim", 1), 0),
        ):
            read, write = os.pipe()
            os.close(read)  # the reader is gone before the command says anything
            done = subprocess.run(
                [PYTHON, "-m", "busservo_host"] + [str(a) for a in command],
                env=dict(os.environ, PYTHONPATH=os.path.join(ROOT, "lib")),
                stdout=write,
                stderr=subprocess.PIPE,
                text=True,
                timeout=60,
            )
            os.close(write)
            self.assertEqual((done.returncode, done.stderr), (status, ""), command)

    def test_the_panel_says_its_address_in_a_url_and_not_the_password(self):
        # An IPv6 host in brackets (http://::1:8080/ is no URL); the password given is not
        # printed (it may end up in a log, or on a screen); the panel's own errors as every
        # command's, on stderr behind "busservo: " (they went to stdout, bare: issue 42).
        import busservo_web

        async def serve(robot, password, port=80, arm=None, path="robot.json", host="0.0.0.0"):
            await asyncio.sleep(0.5)  # serving, a while

        for host, shown in (("::1", "[::1]"), ("127.0.0.1", "127.0.0.1"), ("::", "127.0.0.1")):
            with mock.patch.object(busservo_web, "serve", serve):
                status, out, err = busservo_command(
                    "panel", "--sim", "--password", "a password!", "--host", host, "--port", 8123
                )
            self.assertEqual(status, 0, out + err)
            self.assertIn(
                "open http://%s:8123/ and log in with the password you gave" % shown, out
            )
            self.assertNotIn("a password!", out + err)

        async def refused(robot, password, port=80, arm=None, path="robot.json", host="0.0.0.0"):
            raise OSError(errno.EADDRNOTAVAIL, "cannot assign requested address")

        with mock.patch.object(busservo_web, "serve", refused):
            status, out, err = busservo_command(
                "panel", "--sim", "--password", "a password!", "--host", "1.2.3.4"
            )
        self.assertEqual(status, 1)
        self.assertEqual(
            err, "busservo: 1.2.3.4 is no address of this computer's: give one with --host H\n"
        )
        self.assertNotIn("no address", out)

    def test_a_hid_controller_takes_59_ids_a_query_said_in_the_commands_words(self):
        # 60 ids on HID failed with the transport's words (a frame of 65 bytes...): the
        # command says what it takes, before anything is opened.
        ids = list(range(1, 61))
        for port in ("hid", "hid:/dev/hidraw3"):
            for command in ("positions", "limp"):
                status, out, err = busservo_command(command, port, *ids)
                self.assertEqual((status, out), (2, ""), err)
                self.assertIn(
                    "%s wants 1..59 ids on a HID controller (its request fits in a 64-byte "
                    "report), got 60" % command,
                    err,
                )
        self.assertIn("(84 at most, 59 on HID)", busservo_command("--help")[1])

    def test_a_recordings_time_that_goes_back_is_said_with_its_line(self):
        # Every other bad line of a .jsonl says FILE, line N: this one said only "t must
        # not go back" (issue 42), from Recording.load() too.
        path = os.path.join(self.scratch, "back.jsonl")
        with open(path, "w") as f:
            f.write('{"names": ["base"], "joints": {"base": {"servo_id": 1}}}\n')
            f.write('{"t": 100, "pose": {"base": 0}}\n{"t": 50, "pose": {"base": 1}}\n')
        status, out, err = busservo_command("play", "--sim", path)
        self.assertEqual(status, 2, out + err)
        self.assertIn("%s, line 3: t must not go back, got 50 after 100" % path, err)

    def test_options_are_checked_as_the_words_are(self):
        for command, words in (
            (("positions", "--sim", 1, "--timeout", 0), "--timeout must be a number in 1..60000"),
            (("positions", "--sim", 1, "--timeout"), "--timeout wants a value: --timeout MS"),
            (("positions", "--sim", 1, "--port", 80), "positions takes no --port"),
            (("panel", "--sim", "--password", "long enough", "--json"), "panel takes no --json"),
            (("check", "--sim", "--fast"), "no option '--fast'"),
            (("scan", "--sim", 3), "scan takes PORT only"),
            (("group", "--sim"), "group wants N [TIMES]"),
            (("group", "--sim", 256), "N must be a number in 0..255, got '256'"),
            (("limp", "--sim"), "limp wants 1..252 ids, got 0"),
            (("--json",), "no command"),
        ):
            status, out, err = busservo_command(*command)
            self.assertEqual((status, out), (2, ""), command)
            self.assertIn(words, err)

    def test_the_new_commands_on_the_simulated_controller(self):
        self.assertEqual(
            busservo_command("scan", "--sim"),
            (0, "".join("%d: 500\n" % i for i in range(1, 7)), ""),
        )
        self.assertEqual(busservo_command("limp", "--sim", 1)[0], 0)
        status, out, _ = busservo_command("group", "--sim", 1)  # nothing real to check
        self.assertEqual((status, out.split("\n")[-2]), (0, "action group 1 done"))
        self.assertEqual(
            busservo_command("stop", "--sim"), (0, "no action group was running\n", "")
        )

    def test_a_command_imports_no_asyncio_it_does_not_use(self):
        # CPython's asyncio took most of a `busservo positions`: the modules that use it
        # (busservo_async, busservo_web) import it, through busservo_cpython, themselves.
        run = subprocess.run(
            [
                PYTHON,
                "-c",
                "import sys, busservo_host; busservo_host.main(['positions', '--sim', '1']); "
                "print(sorted({'asyncio', 'json'} & set(sys.modules)))",
            ],
            env=dict(os.environ, PYTHONPATH="lib"),
            capture_output=True,
            text=True,
        )
        self.assertEqual(run.stdout, "1: 500\n[]\n", run.stderr)
        run = subprocess.run(
            [PYTHON, "-c", "import busservo_async; print(busservo_async.asyncio.sleep_ms)"],
            env=dict(os.environ, PYTHONPATH="lib"),
            capture_output=True,
            text=True,
        )
        self.assertIn("function", run.stdout, run.stderr)

    def test_ports_lists_the_usb_ones_first_with_their_chip(self):
        from serial.tools import list_ports_common

        def port(device, vid=None):
            p = list_ports_common.ListPortInfo(device, skip_link_detection=True)
            p.description = "USB Serial" if vid else "n/a"
            if vid:
                p.vid, p.pid = vid
            return p

        found = [port("/dev/ttyS0"), port("/dev/ttyUSB0", (0x1A86, 0x7523))]
        from serial.tools import list_ports

        comports = list_ports.comports
        list_ports.comports = lambda: found
        try:
            self.assertEqual(
                busservo_host.ports(),
                [("/dev/ttyUSB0", "USB Serial (USB 1A86:7523, CH340)"), ("/dev/ttyS0", "n/a")],
            )
        finally:
            list_ports.comports = comports

    def test_the_panel_serves_its_page_and_a_login_from_the_computer(self):
        import json
        import socket
        from urllib.request import Request, urlopen

        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            tcp = s.getsockname()[1]
        panel = subprocess.Popen(
            [
                PYTHON,
                "-m",
                "busservo_host",
                "panel",
                "--sim",
                "--password",
                "a password!",
                "--port",
                str(tcp),
            ],
            env=dict(os.environ, PYTHONPATH=os.path.join(ROOT, "lib"), PYTHONUNBUFFERED="1"),
            cwd=self.scratch,  # where it keeps sequences/, should one be saved
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            # Ctrl-C's signal as at a terminal (a job in the background of tests/run.sh's
            # shell starts with it ignored).
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        try:
            said = ""
            while "open http" not in said and panel.poll() is None:
                said += panel.stdout.readline()
            self.assertIn("open http://127.0.0.1:%d/" % tcp, said)
            url = "http://127.0.0.1:%d" % tcp
            with urlopen(url + "/", timeout=10) as page:
                self.assertEqual(page.headers["Content-Encoding"], "gzip")
                self.assertEqual(page.read(2), b"\x1f\x8b")
            login = Request(
                url + "/api/login",
                json.dumps({"password": "a password!"}).encode(),
                {"Content-Type": "application/json"},
            )
            with urlopen(login, timeout=10) as answer:
                self.assertEqual(len(json.load(answer)["token"]), 32)
        finally:
            panel.send_signal(signal.SIGINT)  # Ctrl-C
            try:
                panel.communicate(timeout=10)
            finally:
                panel.kill()
                panel.wait()
        self.assertEqual(panel.returncode, 130)


class HIDControllers(unittest.TestCase):
    """PORT hid and hid:PATH, and `busservo ports`, with a stand-in for busservo_hid: its
    ports() and hid_port(port) (a simulated controller, as a UART)."""

    def setUp(self):
        from serial.tools import list_ports

        import busservo_sim

        self.opened = []
        fake = types.ModuleType("busservo_hid")
        fake.found = [("hid:/dev/hidraw3", "xArm controller (USB 0483:5750)")]

        def hid_port(port="hid"):
            if not fake.found:
                raise OSError(errno.ENOENT, "no HID controller found: plug it in")
            self.opened.append(port)
            return busservo_sim.SimController()

        fake.ports = lambda: list(fake.found)
        fake.hid_port = hid_port
        self.fake = fake
        self.patches = [
            mock.patch.dict(sys.modules, {"busservo_hid": fake}),
            mock.patch.object(list_ports, "comports", lambda: []),
        ]
        for patch in self.patches:
            patch.start()

    def tearDown(self):
        for patch in self.patches:
            patch.stop()

    def test_ports_lists_them_beside_the_serial_ones(self):
        self.assertEqual(
            busservo_command("ports"),
            (0, "hid:/dev/hidraw3  xArm controller (USB 0483:5750)\n", ""),
        )
        self.fake.found = []
        status, out, _ = busservo_command("ports")
        self.assertIn("no serial ports and no HID controllers: plug", out)

    def test_every_command_takes_one_as_port(self):
        self.assertEqual(busservo_command("positions", "hid", 1, 2), (0, "1: 500\n2: 500\n", ""))
        status, out, err = busservo_command("check", "hid:/dev/hidraw3")
        self.assertEqual(status, 0, out + err)
        self.assertIn("battery: 7.50 V", out)
        self.assertEqual(self.opened, ["hid", "hid:/dev/hidraw3"])
        self.fake.found = []
        self.assertEqual(
            busservo_command("check", "hid"),
            (1, "", "busservo: no HID controller found: plug it in\n"),
        )

    def test_without_busservo_hid(self):
        with mock.patch.dict(sys.modules, {"busservo_hid": None}):  # import fails
            self.assertEqual(
                busservo_command("ports"),
                (
                    0,
                    "no serial ports and no HID controllers: "
                    "plug the controller's USB cable in (a data cable)\n",
                    "",
                ),
            )
            status, out, err = busservo_command("check", "hid")
            self.assertEqual(status, 1)
            self.assertIn("no busservo_hid module for hid", err)


class OverBusservoHid(unittest.TestCase):
    """The command over lib/busservo_hid.py itself, with test_hid's fake hidapi binding: an
    xArm's controller (the simulated one behind it, at USB speed) plugged in."""

    def setUp(self):
        import busservo_sim
        import test_hid

        self.xarm = test_hid.Controller(sim=busservo_sim.SimController(baudrate=None))
        binding = test_hid.Binding(self.xarm)
        self.patch = mock.patch.dict(sys.modules, {"hid": binding, "hidraw": binding})
        self.patch.start()

    def tearDown(self):
        self.patch.stop()

    def test_ports_check_scan_positions_move(self):
        status, out, err = busservo_command("ports")
        self.assertEqual(status, 0, err)
        self.assertTrue(out.startswith("hid:/dev/hidraw3  MyUSB_HID LOBOT (USB HID 0483:5750"))
        status, out, err = busservo_command("check", "hid")
        self.assertEqual(status, 0, out + err)
        self.assertIn("battery: 7.50 V", out)
        # Each request in one 64-byte report: a scan asks for fewer ids at a time than a
        # serial port could carry (84).
        status, out, err = busservo_command("scan", "hid:/dev/hidraw3")
        self.assertEqual((status, out), (0, "".join("%d: 500\n" % i for i in range(254))), err)
        self.assertEqual(busservo_command("positions", "hid", 1, 2), (0, "1: 500\n2: 500\n", ""))
        status, out, err = busservo_command("move", "hid", 1, 800, 0, CHECKED)
        self.assertEqual((status, out.split("\n")[-2]), (0, "servo 1 is at 800"), err)

    def test_a_controller_silent_for_its_first_second_is_waited_for(self):
        # Just switched on: each command's first query was unanswered, and the checklist
        # said (--timeout 1500 did not help: no request was sent again).
        for command in (("check", "hid"), ("stop", "hid"), ("limp", "hid", 1, CHECKED)):
            self.xarm.deaf_s = 1.0  # (from when it is opened)
            status, out, err = busservo_command(*command)
            self.assertEqual(status, 0, (command, out, err))


class WhatCPythonLacks(unittest.TestCase):
    # lib/busservo_cpython.py, as MicroPython has it (the driver's tests on CPython use it all).
    def test_ticks_wrap_at_2_to_the_30_as_on_a_32_bit_board(self):
        import busservo_cpython as mp

        top = (1 << 30) - 1
        self.assertEqual(mp.ticks_add(top, 1), 0)
        self.assertEqual(mp.ticks_diff(0, top), 1)
        self.assertEqual(mp.ticks_diff(top, 0), -1)
        self.assertEqual(mp.ticks_add(5, -10), top - 4)
        with self.assertRaises(OverflowError):
            mp.ticks_add(0, 1 << 29)
        self.assertTrue(0 <= mp.time.ticks_ms() <= top)

    def test_the_frame_buffer_keeps_the_low_8_bits(self):
        import busservo_cpython as mp

        buf = mp.bytearray8(4)
        buf[0] = 0x1234
        buf[1] = -3
        buf[2:4] = b"\x01\x02"
        self.assertEqual(bytes(buf), b"\x34\xfd\x01\x02")

    def test_json_writes_text_as_it_is_as_micropython_does(self):
        import busservo_cpython as mp

        self.assertEqual(mp.json.dumps({"name": "épaule"}), '{"name": "épaule"}')

    def test_every_module_has_micropythons_time_and_asyncio_on_a_plain_cpython(self):
        # The tests' own process (tests/cpython.py) puts MicroPython's names into time and
        # asyncio, which hid a module of lib/ importing them bare: the panel's record part
        # failed on a computer (AttributeError: ticks_diff). A CPython with nothing put in:
        # each module's time and asyncio, where it has them, have what its source uses.
        check = (
            "import glob, os, re, sys\n"
            "sys.path.insert(0, 'lib')\n"
            "for path in sorted(glob.glob('lib/busservo*.py')):\n"
            "    name = os.path.basename(path)[:-3]\n"
            "    if name == 'busservo_hid':\n"
            "        continue  # (hidapi: test_hid's)\n"
            "    module = __import__(name)\n"
            "    source = open(path).read()\n"
            "    for what in ('time', 'asyncio'):\n"
            "        got = getattr(module, what, None)\n"
            "        for n in sorted(set(re.findall(r'\\b' + what + r'\\.(\\w+)', source))):\n"
            "            if got is not None and not hasattr(got, n):\n"
            "                print(name, what, n)\n"
        )
        out = subprocess.run([PYTHON, "-c", check], capture_output=True, text=True)
        self.assertEqual((out.returncode, out.stdout), (0, ""), out.stderr)


def oldest_python():
    """A CPython 3.9 on this machine (the oldest the package supports), or None."""
    import glob

    found = [shutil.which("python3.9")]
    found += sorted(
        glob.glob(os.environ.get("PYENV_ROOT", "/nonexistent") + "/versions/3.9*/bin/python3.9")
    )
    for python in filter(None, found):
        ok = subprocess.run([python, "--version"], capture_output=True, text=True)
        if ok.returncode == 0 and ok.stdout.startswith("Python 3.9"):
            return python
    return None


class Oldest(Scratch):
    def test_the_driver_and_asyncio_pass_their_tests_on_python_3_9(self):
        # 3.9's asyncio.Lock binds to the loop current when it is made: a driver made
        # before asyncio.run() raised RuntimeError there (no current event loop).
        python = oldest_python()
        if python is None:
            print("\n*** SKIPPED: no CPython 3.9 on this machine ***")
            return
        env = dict(os.environ)
        env.pop("RUN_SH_K", None)  # every test of the module, whatever -k picked here
        for module in ("test_async", "test_commands"):
            run = subprocess.run(
                [python, "tests/cpython.py", module], capture_output=True, text=True, env=env
            )
            last = run.stdout.rstrip("\n").split("\n")[-1]
            self.assertEqual(last.split()[2:], ["0", "0"], module + "\n" + run.stdout + run.stderr)


class Install(Scratch):
    def test_pip_install_gives_the_modules_the_page_and_the_command(self):
        # A copy of the checkout's files (a build writes beside them), into a fresh venv.
        source = os.path.join(self.scratch, "busservo")
        files = subprocess.run(
            ["git", "ls-files", "-co", "--exclude-standard"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.split("\n")
        for name in filter(None, files):
            if os.path.isfile(name):
                os.makedirs(os.path.join(source, os.path.dirname(name)), exist_ok=True)
                shutil.copy(name, os.path.join(source, name))
        # The README's third line, as a computer user types it in the clone (~ is a scratch
        # folder here).
        with open("README.md") as f:
            line = [t for t in f.read().split("\n") if t.startswith("python3 -m venv ")][0]
        env = dict(os.environ, HOME=self.scratch, PIP_DISABLE_PIP_VERSION_CHECK="1")
        done = subprocess.run(
            ["sh", "-c", line], capture_output=True, text=True, cwd=source, env=env
        )
        self.assertEqual(done.returncode, 0, line + "\n" + done.stdout + done.stderr)
        self.assertIn("battery", done.stdout)
        venv = os.path.join(self.scratch, "busservo-venv")
        bin_ = os.path.join(venv, "bin")
        # What the build says, in full (pip install -v .): nothing it takes is deprecated
        # (pyproject.toml's license as a table was, for an SPDX string).
        build = subprocess.run(
            [bin_ + "/pip", "wheel", "-v", "--no-deps", "-w", self.scratch + "/wheel", source],
            capture_output=True,
            text=True,
            env=env,
        )
        self.assertEqual(build.returncode, 0, build.stdout + build.stderr)
        self.assertNotIn("DeprecationWarning", build.stdout + build.stderr)
        run = subprocess.run(
            [bin_ + "/busservo", "positions", "--sim", "1", "2"],
            capture_output=True,
            text=True,
            cwd=self.scratch,
        )
        self.assertEqual((run.returncode, run.stdout), (0, "1: 500\n2: 500\n"), run.stderr)
        page = subprocess.run(
            [
                bin_ + "/python",
                "-c",
                "import busservo_web, os; print(os.path.exists("
                "busservo_web.PAGE), busservo_web.__file__)",
            ],
            capture_output=True,
            text=True,
            cwd=self.scratch,
        )
        self.assertTrue(page.stdout.startswith("True " + venv), page.stdout + page.stderr)


class APtyThatAnswersAtOnce(Scratch):
    # A controller on a pty that answers the moment a request is in (tests/pty_peer.py), as a
    # simulator a user writes does: every reply comes sooner than 9600 baud allows, and
    # nothing else can be its answer. The driver takes it, and so does the command.
    def setUp(self):
        super().setUp()
        self.link = os.path.join(self.scratch, "peer")
        self.peer = subprocess.Popen([PYTHON, "tests/pty_peer.py", self.link, "30"])
        self.assertTrue(wait_for(self.link, 10), "the peer did not start")

    def tearDown(self):
        self.peer.kill()
        self.peer.wait()
        super().tearDown()

    def test_queries_and_the_command(self):
        with busservo_host.serial_port(self.link) as uart:
            bus = busservo.BusServo(uart)
            for _ in range(3):
                self.assertEqual(bus.read_battery(timeout_ms=1000), 7500)
                self.assertEqual(bus.read_positions([1, 2], timeout_ms=1000), {1: 500, 2: 500})
            self.assertTrue(bus.early > 0, bus.early)
        status, out, err = busservo_command("positions", self.link, 1, 2)
        self.assertEqual((status, out), (0, "1: 500\n2: 500\n"), err)


def joints_line(joints):
    """A recording's first line (JSON lines): the joints {name: busservo_motion.Joint}."""
    import json

    names = sorted(joints, key=lambda name: joints[name].servo_id)
    return json.dumps({"names": names, "joints": {n: joints[n].config() for n in names}})


def write_recording(path, seconds=10, every_ms=30, degrees=90):
    """A recording (JSON lines) of the demo's arm: its base turning 0..degrees over seconds."""
    import json

    import busservo_board

    lines = [joints_line(busservo_board.joints())]
    end = int(seconds * 1000)
    for t in range(0, end + 1, every_ms):
        pose = {"base": round(degrees * t / end, 2), "shoulder": 0, "elbow": 0, "claw": 0}
        lines.append(json.dumps({"t": t, "pose": pose}))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def write_calibrations(folder, follower_trim=0):
    """leader.json (servos 1..3) and follower.json (servos 4..6), as Robot.save() writes them:
    their paths."""
    import json

    paths = []
    for name, first, trim in (("leader", 1, 0), ("follower", 4, follower_trim)):
        joints = {"base": {"servo_id": first, "trim": trim}, "shoulder": {"servo_id": first + 1}}
        joints["elbow"] = {"servo_id": first + 2}
        path = os.path.join(folder, name + ".json")
        with open(path, "w") as f:
            json.dump({"joints": joints}, f)
        paths.append(path)
    return paths


def read_until(process, text, seconds=20):
    """What process printed up to the line that holds text (or its end)."""
    said = ""
    end = time.monotonic() + seconds
    while text not in said and time.monotonic() < end:
        line = process.stdout.readline()
        if not line:
            break
        said += line
    return said


def free_tcp():
    """A TCP port no one listens on now, as a str."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return str(s.getsockname()[1])


def ctrl_c(process, sig=signal.SIGINT):
    """Ctrl-C (or the signal sig), then (status, stdout, stderr) once it has ended."""
    try:
        process.send_signal(sig)
        out, err = process.communicate(timeout=20)
    finally:
        process.kill()
        process.wait()
    return process.returncode, out, err


class RecordPlayTeleop(Scratch):
    """busservo record, play and teleop (issue 29): on the simulated controller, in the
    folder of the test's own (where robot.json would be, and the recordings go)."""

    def setUp(self):
        super().setUp()
        self.here = os.getcwd()
        os.chdir(self.scratch)

    def tearDown(self):
        os.chdir(self.here)
        super().tearDown()

    def test_record_keeps_what_it_reads_and_play_plays_it(self):
        import busservo_record

        for name in ("demo.jsonl", "demo.rec"):  # JSON lines, and the compact form
            status, out, err = busservo_command("record", "--sim", name, "--seconds", 0.5)
            self.assertEqual(status, 0, out + err)
            self.assertIn("the joints base, shoulder, elbow, claw (servos [1, 2, 3, 4]) go", out)
            recording = busservo_record.Recording.load(name)
            self.assertEqual(recording.names, ["base", "shoulder", "elbow", "claw"])
            self.assertGreater(len(recording), 5)  # a read takes ~27 ms at 9600 baud
            self.assertIn(
                "saved %s: %d samples over %.1f s, 0 reads missed"
                % (name, len(recording), recording.duration_ms / 1000),
                out,
            )
            status, out, err = busservo_command("play", "--sim", name, "--speed", 2)
            self.assertEqual(status, 0, out + err)
            self.assertIn("this plays %s (%d samples" % (name, len(recording)), out)
            self.assertIn("at 2x: into its first pose at 30 degrees/s", out)
            self.assertIn("played %s in" % name, out)

    def test_play_goes_to_the_first_pose_then_at_the_recorded_pace(self):
        write_recording("wave.jsonl", seconds=1, degrees=20)
        status, out, err = busservo_command("play", "--sim", "wave.jsonl", "--speed", 0.5)
        self.assertEqual(status, 0, out + err)
        took = float(out.split("played wave.jsonl in ")[1].split()[0])
        self.assertGreater(took, 1.9)  # 1 s at half speed: no shorter (longer on a busy machine)

    def test_ctrl_c_ends_a_recording_and_it_is_saved(self):
        record = command_process("record", "--sim", "hand.jsonl", cwd=self.scratch)
        said = read_until(record, "Ctrl-C ends it")
        time.sleep(0.5)
        status, out, err = ctrl_c(record)
        self.assertEqual(status, 0, said + out + err)  # the normal end of a recording
        self.assertIn("recording into hand.jsonl (Ctrl-C ends it)", said)
        self.assertIn("saved hand.jsonl: ", out)
        self.assertNotIn("Traceback", err)
        with open(os.path.join(self.scratch, "hand.jsonl")) as f:
            self.assertGreater(len(f.readlines()), 2)

    def test_bad_input_is_a_usage_line_not_a_traceback(self):
        write_recording("good.jsonl", seconds=1)
        with open("bad.jsonl", "w") as f:
            f.write('{"names": ["base"')
        with open("empty.jsonl", "w") as f:
            f.write(joints_line({"base": busservo_motion_joint(1)}) + "\n")
        with open("line3.jsonl", "w") as f:
            f.write(joints_line({"base": busservo_motion_joint(1)}) + "\n")
            f.write('{"t": 0, "pose": {"base": 0}}\n{"t": 30, "pose": {}}\n')
        os.mkdir("folder")
        leader, follower = write_calibrations(self.scratch)
        with open("broken.json", "w") as f:
            f.write('{"joints": ')
        calibrations = ("--leader-calibration", leader, "--follower-calibration", follower)
        for command, words in (
            (("record", "--sim"), "record wants PORT FILE"),
            (("record", "--sim", "a.jsonl", "b.jsonl"), "record wants PORT FILE"),
            (("record", "--sim", "no/such/a.jsonl"), "no folder no/such for FILE"),
            (("record", "--sim", "folder"), "folder is a folder"),
            (("record", "--sim", "a.rec", "--seconds", 0), "--seconds must be a number in 0.1"),
            (("record", "--sim", "a.rec", "--seconds", "x"), "got 'x'"),
            (("record", "--sim", "a.rec", "--speed", 1), "record takes no --speed"),
            (("play", "--sim"), "play wants PORT FILE"),
            (("play", "--sim", "good.jsonl", "--speed", 3), "--speed must be a number in 0.25..2"),
            (("play", "--sim", "good.jsonl", "--speed", 0.1), "got '0.1'"),
            (("play", "--sim", "good.jsonl", "--speed", "nan"), "got 'nan'"),
            (("play", "--sim", "missing.jsonl"), "no such file missing.jsonl"),
            (("play", "--sim", "folder"), "folder is a folder"),
            (("play", "--sim", "bad.jsonl"), "bad.jsonl: its first line must be the joints"),
            (("play", "--sim", "empty.jsonl"), "empty.jsonl holds no sample"),
            (("play", "--sim", "line3.jsonl"), "line3.jsonl, line 3: a sample must be"),
            (("play", "--sim", "good.jsonl", "--seconds", 1), "play takes no --seconds"),
            (("teleop", "COM9"), "teleop wants --leader-calibration F1 and"),
            (("teleop", "--sim") + calibrations + ("--record",), "--record wants a value"),
            (("teleop", "--sim") + calibrations + ("--record", "no/such/l.rec"), "no folder no/"),
            (("teleop", "--sim") + calibrations + ("--record", "folder"), "folder is a folder"),
            (("record", "--sim", "a.rec", "--record", "b.rec"), "record takes no --record"),
            (("teleop", "--sim", "--leader-calibration", leader), "--follower-calibration F2"),
            (("teleop", "--sim", "--sim", "--sim") + calibrations, "teleop wants LEADER [FOL"),
            (
                (
                    "teleop",
                    "--sim",
                    "--leader-calibration",
                    "no.json",
                    "--follower-calibration",
                    follower,
                ),
                "no such file no.json (--leader-calibration: a robot.json)",
            ),
            (
                (
                    "teleop",
                    "--sim",
                    "--leader-calibration",
                    leader,
                    "--follower-calibration",
                    "broken.json",
                ),
                "--follower-calibration: broken.json: not valid JSON",
            ),
            (
                (
                    "teleop",
                    "--sim",
                    "--leader-calibration",
                    leader,
                    "--follower-calibration",
                    leader,
                ),
                "on one bus the arms need their own servo ids",
            ),
        ):
            status, out, err = busservo_command(*command)
            self.assertEqual((status, out), (2, ""), command)
            self.assertIn(words, err, command)
            self.assertIn("(busservo --help)", err, command)
            self.assertNotIn("Traceback", err, command)

    def test_a_silent_controller_gets_the_checklist(self):
        peer = Peer(delay=None)
        try:
            write_recording("wave.jsonl", seconds=1)
            leader, follower = write_calibrations(self.scratch)
            for command in (
                ("record", peer.path, "r.jsonl"),
                ("play", peer.path, "wave.jsonl", CHECKED),
                (
                    "teleop",
                    peer.path,
                    "--leader-calibration",
                    leader,
                    "--follower-calibration",
                    follower,
                    CHECKED,
                ),
            ):
                status, out, err = busservo_command(*command)
                self.assertEqual(status, 1, command)
                self.assertIn("no answer from the controller on %s within" % peer.path, out + err)
                self.assertNotIn("Traceback", err)
            self.assertFalse(os.path.exists("r.jsonl"))
        finally:
            peer.close()

    def test_help_says_them(self):
        out = busservo_command("--help")[1]
        for command in ("record PORT FILE", "play PORT FILE", "teleop LEADER [FOLLOWER]"):
            self.assertIn("busservo " + command, out)

    def test_a_recording_of_joints_the_robot_has_not_is_refused_by_name(self):
        with open("other.jsonl", "w") as f:
            f.write(joints_line({"wrist": busservo_motion_joint(5)}) + "\n")
            f.write('{"t": 0, "pose": {"wrist": 0}}\n')
        status, out, err = busservo_command("play", "--sim", "other.jsonl", CHECKED)
        self.assertEqual((status, out), (2, ""), err)
        self.assertIn("other.jsonl records joints wrist, which the robot has not", err)

    def test_a_file_that_is_no_recordings_is_refused(self):
        # busservo record PORT robot.json would have replaced the calibration with a binary
        # recording, and wave.json (for .jsonl) given one silently.
        leader, follower = write_calibrations(self.scratch)
        with open(leader) as f:
            kept = f.read()
        calibrations = ("--leader-calibration", leader, "--follower-calibration", follower)
        for command, name in (
            (("record", "--sim", "leader.json", "--seconds", 0.5), "leader.json"),
            (("record", "--sim", "wave.json"), "wave.json"),
            (("record", "--sim", "wave"), "wave"),
            (("teleop", "--sim") + calibrations + ("--record", "lead.json"), "lead.json"),
        ):
            status, out, err = busservo_command(*command)
            self.assertEqual((status, out), (2, ""), command)
            self.assertIn(
                "FILE must end in .rec (the compact form) or .jsonl (JSON lines), got %r" % name,
                err,
            )
            self.assertNotIn("Traceback", err)
        with open(leader) as f:
            self.assertEqual(f.read(), kept)
        self.assertEqual(sorted(os.listdir(".")), ["follower.json", "leader.json"])

    def test_a_recording_killed_keeps_what_it_wrote(self):
        # SIGKILL: what the recorder wrote had reached the OS (CPython's buffer held ~8 KB,
        # 40 s of samples, and left a file of 0 bytes). The file reads back to its last
        # whole sample.
        import busservo_record

        record = command_process("record", "--sim", "hand.rec", cwd=self.scratch)
        said = read_until(record, "Ctrl-C ends it")
        kept = None
        end = time.monotonic() + 10  # a piece (256 bytes) is some 1.2 s of 4 joints
        while kept is None and time.monotonic() < end:
            time.sleep(0.2)
            try:
                if len(busservo_record.Recording.load("hand.rec")):
                    kept = True
            except (OSError, ValueError):
                pass
        record.kill()
        out, err = record.communicate()
        self.assertEqual(record.returncode, -signal.SIGKILL, said + out + err)
        recording = busservo_record.Recording.load("hand.rec")
        self.assertGreater(len(recording), 10, said)
        self.assertEqual(recording.names, ["base", "shoulder", "elbow", "claw"])

    def test_sigterm_and_sighup_end_a_recording_as_ctrl_c_does(self):
        # The terminal closed (SIGHUP) or the process asked to end (SIGTERM): the recording
        # is saved and said, exit status 0, as at Ctrl-C.
        import busservo_record

        for sig in (signal.SIGTERM, signal.SIGHUP):
            name = "hand%d.rec" % sig
            record = command_process("record", "--sim", name, cwd=self.scratch)
            said = read_until(record, "Ctrl-C ends it")
            time.sleep(0.5)
            try:
                record.send_signal(sig)
                out, err = record.communicate(timeout=20)
            finally:
                record.kill()
                record.wait()
            self.assertEqual(record.returncode, 0, said + out + err)
            self.assertIn("saved %s: " % name, out)
            self.assertNotIn("Traceback", err)
            self.assertGreater(len(busservo_record.Recording.load(name)), 5)

    def test_an_empty_or_cut_recording_is_said_in_words(self):
        import busservo_record

        open("empty.rec", "wb").close()
        with open("cut.rec", "wb") as f:
            f.write(busservo_record.MAGIC + b'{"names": ["base"], "joi')
        for name, words in (
            ("empty.rec", "empty.rec is empty: no samples were saved"),
            ("cut.rec", "cut.rec is cut short"),
        ):
            status, out, err = busservo_command("play", "--sim", name)
            self.assertEqual((status, out), (2, ""), err)
            self.assertIn(words, err)
            self.assertNotIn("Expecting", err)
            self.assertNotIn("Traceback", err)

    def test_teleop_on_the_simulator_needs_no_calibration(self):
        # From a fresh clone: no leader.json, no follower.json. --sim's arms are the demo's,
        # the leader on servos 1..4, the follower on 7..10.
        for ports in (("--sim",), ("--sim", "--sim")):
            teleop = command_process("teleop", *ports, cwd=self.scratch)
            said = read_until(teleop, "cycles a second")
            status, out, err = ctrl_c(teleop)
            self.assertEqual(status, 130, said + out + err)
            self.assertIn("the leader's servos are at {1: 500, 2: 500, 3: 500, 4: 500}", said)
            self.assertIn("the follower's servos are at {7: 500, 8: 500, 9: 500, 10: 500}", said)
            self.assertIn("cycles a second", said)
            self.assertNotIn("Traceback", err)
        # A real port still wants both calibrations.
        status, out, err = busservo_command("teleop", "/dev/ttyUSB9")
        self.assertEqual(status, 2, out + err)
        self.assertIn("teleop wants --leader-calibration F1 and --follower-calibration F2", err)

    def test_a_group_run_once_is_said_once(self):
        status, out, err = busservo_command("group", "--sim", 1)
        self.assertEqual(status, 0, out + err)
        self.assertIn("action group 1 runs once (Ctrl-C stops it)", out)
        status, out, err = busservo_command("group", "--sim", 1, 2)
        self.assertIn("action group 1 runs 2 times (Ctrl-C stops it)", out)

    def test_teleop_says_its_rate_warns_and_ctrl_c_stops_the_follower(self):
        # One bus (the leader's servos 1..3, the follower's 4..6) and two: the follower's
        # base calibrated 5 degrees off the leader's, which the start warns of.
        leader, follower = write_calibrations(self.scratch, follower_trim=5)
        calibrations = ("--leader-calibration", leader, "--follower-calibration", follower)
        for ports in (("--sim",), ("--sim", "--sim")):
            teleop = command_process("teleop", *ports + calibrations, cwd=self.scratch)
            said = read_until(teleop, "cycles a second")
            said += read_until(teleop, "cycles a second")  # a second's rate, whole
            status, out, err = ctrl_c(teleop)
            self.assertEqual(status, 130, said + out + err)
            self.assertIn("the leader drives the follower (Ctrl-C stops it)", said)
            self.assertIn(
                "joint 'base': at rest the leader reads 0.0 degrees and the follower -5.0", said
            )
            rate = float(said.rsplit(" cycles a second", 1)[0].rsplit("\n", 1)[1])
            self.assertGreater(rate, 5, said)  # (~26..40 a second: figures, not asserted)
            self.assertIn("stopped: the follower holds at {4: ", out)
            self.assertIn("the leader is limp", out)
            self.assertNotIn("Traceback", err)

    def test_teleop_record_keeps_each_read_of_the_leader(self):
        # Two ports and one bus: the leader's reads go into FILE as they drive the follower.
        import busservo_record

        leader, follower = write_calibrations(self.scratch)
        calibrations = ("--leader-calibration", leader, "--follower-calibration", follower)
        for ports, name in ((("--sim", "--sim"), "lead.jsonl"), (("--sim",), "lead.rec")):
            teleop = command_process(
                "teleop", *ports + calibrations + ("--record", name), cwd=self.scratch
            )
            said = read_until(teleop, "cycles a second")
            said += read_until(teleop, "cycles a second")
            status, out, err = ctrl_c(teleop)
            self.assertEqual(status, 130, said + out + err)
            self.assertIn("recording the leader into %s" % name, said)
            self.assertNotIn("Traceback", err)
            recording = busservo_record.Recording.load(name)
            self.assertEqual(recording.names, ["base", "shoulder", "elbow"])
            self.assertEqual([recording.joints[n].servo_id for n in recording.names], [1, 2, 3])
            self.assertGreater(len(recording), 10)  # ~26..28 a second for over a second
            self.assertIn(
                "saved %s: %d samples over %.1f s, "
                % (name, len(recording), recording.duration_ms / 1000),
                out,
            )

    def test_teleop_names_a_joint_that_does_not_answer(self):
        # The leader's servo 2 (its shoulder) does not answer: the follower holds, and the
        # joint is named. Ctrl-C comes from the command's loop's 300th nap.
        import busservo_sim

        class Deaf(busservo_sim.SimController):
            def __init__(self, *args, **kwargs):
                super().__init__(*args, **kwargs)
                self.missing.add(2)

        sleep = time.sleep
        naps = []

        def nap(seconds):
            naps.append(seconds)
            if len(naps) == 300:
                raise KeyboardInterrupt
            sleep(seconds)

        leader, follower = write_calibrations(self.scratch)
        with mock.patch.object(busservo_sim, "SimController", Deaf):
            with mock.patch.object(busservo_host.time, "sleep", nap):
                status, out, err = busservo_command(
                    "teleop",
                    "--sim",
                    "--sim",
                    "--leader-calibration",
                    leader,
                    "--follower-calibration",
                    follower,
                    "--timeout",
                    100,
                )
        self.assertEqual(status, 130, out + err)
        self.assertIn("the leader's servos are at {1: 500, 2: None, 3: 500}", out)
        self.assertIn(
            "busservo_teleop: joint 'shoulder': the leader's servo 2 does not answer", out
        )
        self.assertIn("the follower holds", out)
        self.assertIn("stopped: the follower holds at {4: 500, 5: 500, 6: 500}", out)


def busservo_motion_joint(servo_id):
    import busservo_motion

    return busservo_motion.Joint(servo_id)


if __name__ == "__main__":
    unittest.main()
