# The driver on a computer (CPython only: tests/run.sh runs this module in its CPython pass).
# pyserial on a pty with the simulated controller at the far end (sh boards/unix.sh
# --sim-pty), as a controller on USB is; the busservo command on good and bad input; and
# pip install . of a copy of the checkout into a scratch venv, then the command it installs.
import errno
import io
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from contextlib import redirect_stderr, redirect_stdout

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
            (("positions", "--sim"), "positions wants one id or more"),
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
            login = Request(url + "/api/login", json.dumps({"password": "a password!"}).encode())
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
                "busservo_web._PAGE), busservo_web.__file__)",
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


if __name__ == "__main__":
    unittest.main()
