# The scripts a maker meets on the first day: boards/unix.sh (from any folder,
# --help, the caller's MICROPYPATH, Ctrl-C, the set-up's progress),
# boards/simpty.py (its --link never deletes what it did not make),
# tests/run.sh's summary, and that every script is executable.
import os
import unittest

from shell import scratch, sh

REPO = os.getcwd()  # tests/run.sh runs every test from the repository's root
UNIX_SH = REPO + "/boards/unix.sh"

# Runs a command as from a terminal: SIGINT not ignored (sh ignores it in what it
# starts in the background) and in a process group of its own, so that
# `kill -s INT -- -PID` is a Ctrl-C to that command and its children alone.
AS_FROM_A_TERMINAL = (
    REPO + "/.venv/bin/python -c 'import os, signal, sys; "
    "signal.signal(signal.SIGINT, signal.SIG_DFL); os.setsid(); "
    "os.execvp(sys.argv[1], sys.argv[1:])'"
)


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def read(path):
    with open(path) as f:
        return f.read()


def folder(name):
    path = scratch(name)
    os.mkdir(path)
    return path


def up_to_repo(path):
    """The repository's path relative to folder path: ../../home/you/busservo, say."""
    return "/".join([".."] * path.count("/")) + REPO


def lexists(path):
    return sh("test -L %s || test -e %s" % (path, path))[0]


def readlink(path):
    ok, out = sh("readlink " + path)
    return out.strip() if ok else None


def launch(command, base, terminal=False):
    """Start command in the background: its output goes to base.log, its pid to
    base.pid, and its exit status to base.rc once it has ended."""
    if terminal:
        command = AS_FROM_A_TERMINAL + " " + command
    os.system(
        "(%s >%s.log 2>&1 & echo $! >%s.pid; wait $!; echo $? >%s.rc) >/dev/null 2>&1 &"
        % (command, base, base, base)
    )
    return int(wait_until(base + ".pid", "\n", 5000))


def wait_until(path, text, ms):
    """path's content once it holds text, or None after ms."""
    # shell.wait_for() with text is the same, but returns None for an empty text.
    import time

    start = time.ticks_ms()
    while time.ticks_diff(time.ticks_ms(), start) < ms:
        try:
            content = read(path)
            if text in content:
                return content
        except OSError:
            pass
        time.sleep_ms(20)
    return None


def wait_until_false(test, ms):
    """True once test() is false, or False if it is still true after ms."""
    import time

    start = time.ticks_ms()
    while test():
        if time.ticks_diff(time.ticks_ms(), start) > ms:
            return False
        time.sleep_ms(20)
    return True


def ended(base, pid, ms=10000):
    """The exit status of what launch() started (killed if it has not ended in ms)."""
    rc = wait_until(base + ".rc", "\n", ms)
    if rc is None:
        os.system("kill -s KILL -- -%d 2>/dev/null; kill -s KILL %d 2>/dev/null" % (pid, pid))
        wait_until(base + ".rc", "\n", 5000)
        return None
    return int(rc)


class FromAnyFolder(unittest.TestCase):
    def setUp(self):
        self.dir = folder("robot")

    def tearDown(self):
        sh("rm -rf " + self.dir)

    def test_a_script_runs_in_the_callers_folder_with_the_callers_micropypath(self):
        d = self.dir
        os.mkdir(d + "/mods")
        write(d + "/mods/mymod.py", "X = 42\n")
        write(d + "/mods/busservo.py", "raise ImportError('a stale copy came first')\n")
        write(d + "/data.txt", "from the caller's folder\n")
        write(
            d + "/robot.py",
            "import sys\nimport busservo\nimport mymod\n"
            "print(busservo.__file__)\nprint(mymod.X, sys.argv[1:])\n"
            "print(open('data.txt').read().strip())\n",
        )
        # As `cd robot && sh ../busservo/boards/unix.sh robot.py a b`:
        command = "cd %s && MICROPYPATH=mods sh %s/boards/unix.sh robot.py a b"
        ok, out = sh(command % (d, up_to_repo(d)))
        self.assertTrue(ok, out)
        lines = out.split("\n")
        self.assertTrue(lines[0].startswith(REPO + "/"), out)  # the checkout's driver
        self.assertEqual(lines[1:4], ["42 ['a', 'b']", "from the caller's folder", ""], out)

    def test_a_clone_folder_beside_the_script_does_not_hide_the_driver(self):
        # As `git clone .../busservo` then a robot.py of one's own beside the clone.
        d = self.dir
        os.mkdir(d + "/busservo")  # the clone: to MicroPython, a namespace package
        write(d + "/robot.py", "import busservo\nprint(busservo.BusServo.__name__)\n")
        write(d + "/neighbour.py", "X = 'beside it'\n")
        write(d + "/uses.py", "import neighbour\nprint(neighbour.X)\n")
        for script, said in (("robot.py", "BusServo"), ("uses.py", "beside it")):
            ok, out = sh("cd %s && sh %s %s" % (d, UNIX_SH, script))
            self.assertEqual((ok, out), (True, said + "\n"), script)
        # (HOME: the REPL keeps its history there, in this test's folder)
        command = "cd %s && echo 'import busservo; busservo.BusServo' | HOME=%s sh %s"
        ok, out = sh(command % (d, d, UNIX_SH))
        self.assertTrue(ok, out)
        self.assertIn("<class 'BusServo'>", out)  # the REPL too

    def test_a_board_py_in_the_folder_run_from_is_found(self):
        d = self.dir
        # As `sh boards/unix.sh examples/check_wiring.py` with a board.py where one stands.
        write(d + "/board.py", "def uart():\n    return 'the one here'\n")
        os.mkdir(d + "/sub")
        write(d + "/sub/which.py", "from board import uart\nprint(uart())\n")
        ok, out = sh("cd %s && sh %s sub/which.py" % (d, UNIX_SH))
        self.assertEqual((ok, out), (True, "the one here\n"))

    def test_with_no_micropypath_micropythons_default_path_still_counts(self):
        # ~/.micropython/lib is where `micropython -m mip install` puts packages.
        d = self.dir
        sh("mkdir -p %s/.micropython/lib" % d)
        write(d + "/.micropython/lib/installed.py", "X = 'mip-installed'\n")
        ok, out = sh(
            "cd %s && unset MICROPYPATH && HOME=%s sh %s -c 'import installed; print(installed.X)'"
            % (d, d, UNIX_SH)
        )
        self.assertEqual((ok, out), (True, "mip-installed\n"))

    def test_sim_pty_makes_its_link_in_the_callers_folder(self):
        base = self.dir + "/sim"
        pid = launch("cd %s && exec sh %s --sim-pty --link bus" % (self.dir, UNIX_SH), base)
        try:
            self.assertTrue(wait_until(base + ".log", "Ctrl-C stops it", 15000))
            pty = readlink(self.dir + "/bus")
            self.assertTrue(pty and pty.startswith("/dev/pts/"), read(base + ".log"))
        finally:
            os.system("kill %d" % pid)
        self.assertEqual(ended(base, pid), 0)
        self.assertFalse(lexists(self.dir + "/bus"))

    def test_help_prints_the_forms_and_other_options_go_to_micropython(self):
        for option in ("--help", "-h"):
            ok, out = sh("cd %s && sh %s %s" % (self.dir, UNIX_SH, option))
            self.assertTrue(ok, option + ": " + out)
            for form in ("sh boards/unix.sh examples/demo.py", "--setup", "--sim-pty", "--mpy"):
                self.assertIn(form, out, option)
            self.assertEqual(os.listdir(self.dir), [])  # and no set-up in the caller's folder
        ok, out = sh("sh boards/unix.sh -c 'print(6 * 7)'")
        self.assertEqual((ok, out), (True, "42\n"))
        ok, out = sh("sh boards/unix.sh --no-such-option")
        self.assertFalse(ok)
        self.assertIn("Invalid command line arguments", out)  # micropython's own answer


class CtrlC(unittest.TestCase):
    def setUp(self):
        self.dir = folder("ctrl-c")

    def tearDown(self):
        sh("rm -rf " + self.dir)

    def interrupt(self, command, ready):
        """Start command as from a terminal, press Ctrl-C once it has printed
        ready; return (its exit status, its output)."""
        base = self.dir + "/run"
        pid = launch(command, base, terminal=True)
        if wait_until(base + ".log", ready, 15000) is None:
            ended(base, pid, 0)
            self.fail("%r never printed %r: %s" % (command, ready, read(base + ".log")))
        os.system("kill -s INT -- -%d" % pid)
        return ended(base, pid), read(base + ".log")

    def test_ctrl_c_ends_a_script_quietly_with_status_130(self):
        loop = self.dir + "/loop.py"
        write(loop, "import time\nprint('looping')\nwhile True:\n    time.sleep_ms(10)\n")
        rc, out = self.interrupt("sh %s -X heapsize=256K %s" % (UNIX_SH, loop), "looping")
        self.assertEqual(rc, 130, out)
        self.assertEqual(out, "looping\n")  # no traceback, no KeyboardInterrupt

    def test_a_script_that_catches_ctrl_c_still_cleans_up(self):
        robot = self.dir + "/robot.py"
        write(
            robot,
            "import time\nprint('moving')\ntry:\n    while True:\n        time.sleep_ms(10)\n"
            "except KeyboardInterrupt:\n    print('servos unloaded')\n",
        )
        rc, out = self.interrupt("sh %s %s" % (UNIX_SH, robot), "moving")
        self.assertEqual((rc, out), (0, "moving\nservos unloaded\n"))

    def test_an_error_is_reported_as_micropython_itself_reports_it(self):
        bad = self.dir + "/bad.py"
        write(bad, "def f():\n    raise ValueError('boom')\n\n\nf()\n")
        direct = sh("MICROPYPATH= .venv/bin/micropython %s; echo status $?" % bad)[1]
        self.assertIn("ValueError: boom", direct)
        self.assertEqual(sh("sh boards/unix.sh %s; echo status $?" % bad)[1], direct)

    def test_ctrl_c_stops_the_simulator_quietly_and_removes_its_link(self):
        link = self.dir + "/bus"
        command = "sh %s --sim-pty --link %s" % (UNIX_SH, link)
        rc, out = self.interrupt(command, "Ctrl-C stops it")
        self.assertEqual(rc, 130, out)
        self.assertFalse("Traceback" in out or "KeyboardInterrupt" in out, out)
        self.assertFalse(lexists(link))


class SimPtyLink(unittest.TestCase):
    def setUp(self):
        self.dir = folder("link")

    def tearDown(self):
        sh("rm -rf " + self.dir)

    def test_what_is_at_the_link_path_is_refused_and_kept(self):
        d = self.dir
        write(d + "/target", "keep me\n")
        sh("ln -s %s/target %s/to-a-file && mkdir %s/dir" % (d, d, d))
        write(d + "/file", "keep me too\n")
        for name in ("file", "to-a-file", "dir"):
            path = d + "/" + name
            ok, out = sh("timeout 10 sh %s --sim-pty --link %s" % (UNIX_SH, path))
            self.assertFalse(ok, name)
            self.assertIn(path, out, name)
            self.assertIn("--link", out, name)
            self.assertFalse("Traceback" in out, out)
        self.assertEqual(read(d + "/file"), "keep me too\n")
        self.assertEqual(readlink(d + "/to-a-file"), d + "/target")
        self.assertEqual(read(d + "/target"), "keep me\n")
        self.assertEqual(sorted(os.listdir(d + "/dir")), [])

    def test_a_stale_link_is_replaced_and_one_not_its_own_is_left_at_exit(self):
        d = self.dir
        sh("ln -s /dev/pts/999999 %s/bus" % d)  # an earlier run's, its pty long gone
        base = d + "/sim"
        pid = launch("sh %s --sim-pty --link %s/bus" % (UNIX_SH, d), base)
        try:
            self.assertTrue(wait_until(base + ".log", "Ctrl-C stops it", 15000))
            pty = readlink(d + "/bus")
            self.assertTrue(pty.startswith("/dev/pts/"), pty)
            self.assertNotEqual(pty, "/dev/pts/999999")
            self.assertIn(pty, read(base + ".log"))
            # The user points the link elsewhere while the simulator runs.
            sh("rm %s/bus && ln -s %s/mine %s/bus" % (d, d, d))
        finally:
            os.system("kill %d" % pid)
        self.assertEqual(ended(base, pid), 0)
        self.assertEqual(readlink(d + "/bus"), d + "/mine")


FAKE_PYTHON3 = """#!/bin/sh
# python3 -m venv DIR, and no more: a venv whose pip and micropython note what
# they are asked and pretend it is done.
[ "$1 $2" = "-m venv" ] || exit 3
mkdir -p "$3/bin"
cat >"$3/bin/pip" <<'EOF'
#!/bin/sh
echo "$*" >>"$(dirname "$0")/../pip-args"
EOF
cat >"$3/bin/micropython" <<'EOF'
#!/bin/sh
[ "$1 $2 $3 $4 $6" = "-m mip install --target unittest" ] || exit 3
echo "# unittest" >"$5/unittest.py"
EOF
chmod +x "$3/bin/pip" "$3/bin/micropython"
"""


class SetUp(unittest.TestCase):
    def test_the_set_up_says_what_it_does_step_by_step(self):
        # A copy of boards/unix.sh in a fresh checkout, with a python3 that
        # makes a stand-in venv: the set-up's own steps, in a second.
        repo = folder("setup")
        elsewhere = folder("elsewhere")
        try:
            sh("mkdir %s/boards %s/bin && cp boards/unix.sh %s/boards/" % (repo, repo, repo))
            write(repo + "/bin/python3", FAKE_PYTHON3)
            sh("chmod +x %s/bin/python3" % repo)
            command = "cd %s && PATH=%s/bin:$PATH sh %s/boards/unix.sh --setup" % (
                elsewhere,
                repo,
                repo,
            )
            ok, out = sh(command)
            self.assertTrue(ok, out)
            lines = out.strip().split("\n")
            steps = [line for line in lines if "/3]" in line]
            self.assertEqual([s.split("[")[1][:3] for s in steps], ["1/3", "2/3", "3/3"], out)
            self.assertTrue(len(lines) <= 5, out)  # and quiet otherwise
            self.assertEqual(os.listdir(elsewhere), [])  # .venv/ is the repository's
            pins = [line for line in read(UNIX_SH).split("\n") if line.startswith("PINS=")]
            pins = pins[0][len('PINS="') : -1].split()
            asked = read(repo + "/.venv/pip-args").split()
            for pin in pins:
                self.assertIn(pin, asked)
            self.assertIn(" ".join(pins), read(repo + "/.venv/ready"))
            self.assertEqual(sh(command), (True, ""))  # ready: silent, and at once
        finally:
            sh("rm -rf %s %s" % (repo, elsewhere))


MIXED = """import unittest


class Mixed(unittest.TestCase):
    def test_bad(self):
        self.assertEqual(1, 2)

    def test_good(self):
        pass

    def test_noisy_error(self):
        print("\\na line of its own")
        raise ValueError("no")
"""

DIES = """import os
import unittest


class Dies(unittest.TestCase):
    def test_dies(self):
        raise KeyboardInterrupt  # no Exception: the module ends here
"""


FINE = """import unittest


class Fine(unittest.TestCase):
    def test_one(self):
        pass

    def test_two(self):
        pass
"""


# A module that runs beside another or fails: each says it has started, then waits (10 s at
# most) for what the other says.
TOGETHER = """import os
import time
import unittest

HERE = %r


def say(name):
    open(HERE + "/" + name, "w").close()


def heard(name):
    for _ in range(500):
        try:
            os.stat(HERE + "/" + name)
            return True
        except OSError:
            time.sleep_ms(20)
    return False


class Together(unittest.TestCase):
    def test_together(self):
        say(%r)
        self.assertTrue(heard(%r))
        %s
"""


# A module whose tests print other runs' summaries, as a failed browser test prints
# Selenium's: its own counts are still its own.
NOISY = """import unittest


class Noisy(unittest.TestCase):
    def test_prints_other_runs_summaries(self):
        print("Ran 3 tests\\n\\nFAILED (failures=2, errors=1)")
        print("Ran 4 tests\\n\\nFAILED (failures=1, errors=0)")

    def test_fails_saying_so(self):
        self.fail("Ran 5 tests\\n\\nFAILED (failures=2, errors=2)")
"""


# A module that leaves a process running in the background (its pid in the file "sleeper"),
# then waits.
SLOW = """import os
import time
import unittest


class Slow(unittest.TestCase):
    def test_slow(self):
        os.system("sleep 600 >/dev/null 2>&1 & echo $! >%s/sleeper")
        time.sleep(600)
"""


# A module whose test writes in the checkout it runs from: a maker's teach.json
# overwritten, and a folder made and removed again.
WRITES = """import os
import unittest


class Writes(unittest.TestCase):
    def test_writes(self):
        with open("teach.json", "w") as f:
            f.write("[[1, 2]]")
        os.mkdir("tests/sequences")
        os.rmdir("tests/sequences")
"""


class RunSh(unittest.TestCase):
    # tests/run.sh in a checkout of its own, with the set-up borrowed from this one and two
    # test modules that fail in every way they can, and one that passes.
    def setUp(self):
        repo = self.repo = folder("suite")
        self.talk = folder("talk")  # where the modules below talk: not in their checkout
        for sub in ("boards", "tests", "lib", "examples", ".venv"):
            os.mkdir(repo + "/" + sub)
        ok, out = sh(
            "cp boards/unix.sh {0}/boards/ && cp tests/run.sh {0}/tests/ && "
            "cp .ruff.toml .venv/ready {0}/ && mv {0}/ready {0}/.venv/ && "
            "ln -s {1}/.venv/bin {0}/.venv/bin && "
            "ln -s {1}/.venv/micropython {0}/.venv/micropython".format(repo, REPO)
        )
        self.assertTrue(ok, out)
        write(repo + "/lib/driver.py", "X = 1\n")
        write(repo + "/tests/typecheck.sh", "exit 0\n")  # the types: not what is tested
        write(repo + "/tests/test_mixed.py", MIXED)
        write(repo + "/tests/test_dies.py", DIES)  # `import os`, unused: style fails too
        write(repo + "/tests/test_fine.py", FINE)

    def tearDown(self):
        sh("rm -rf %s %s" % (self.repo, self.talk))

    def run_sh(self, args=""):
        """(ok, its lines) of tests/run.sh args, in the checkout of its own."""
        ok, out = sh("unset BUSSERVO_LIB MICROPYPATH; sh %s/tests/run.sh %s" % (self.repo, args))
        return ok, out.rstrip("\n").split("\n")

    def test_the_summary_names_each_failed_test_and_its_pass(self):
        ok, lines = self.run_sh("--mpy-all")  # every module against the .mpy files too
        out = "\n".join(lines)
        self.assertFalse(ok)
        self.assertEqual(lines[-1], "7 passed, 7 failed", out)
        self.assertIn("test_mixed: test_good (Mixed) ... ok", lines)  # a failed module: all
        self.assertIn("test_fine: 2 passed", lines)  # a module that passed: one line
        self.assertIn("test_fine (.mpy): 2 passed", lines)
        self.assertFalse("test_fine: test_one (Fine) ... ok" in lines)
        last = max(i for i, line in enumerate(lines) if line.startswith("types: mypy"))
        summary = lines[last + 1 : -1]
        for words in (
            ("test_mixed", "test_bad", "(.py)"),
            ("test_mixed", "test_bad", "(.mpy)"),
            ("test_mixed", "test_noisy_error", "(.py)"),
            ("test_mixed", "test_noisy_error", "(.mpy)"),
            ("test_dies", "test_dies", "(.py)"),
            ("test_dies", "test_dies", "(.mpy)"),
            ("style",),
        ):
            found = [s for s in summary if all(w in s for w in words)]
            self.assertEqual(len(found), 1, "%s in %s" % (words, summary))
        self.assertTrue(len(summary) <= 9, summary)
        ok, lines = self.run_sh("-v")
        self.assertIn("test_fine: test_one (Fine) ... ok", lines)  # -v: every test
        # The .mpy pass runs only the modules run.sh's MPY names: none of these.
        self.assertEqual(lines[-1], "4 passed, 4 failed", lines)
        self.assertFalse([line for line in lines if "(.mpy)" in line], lines)

    def test_modules_named_run_alone_in_the_order_given(self):
        ok, lines = self.run_sh("tests/test_fine.py test_mixed")  # a path, or a name
        self.assertFalse(ok)
        self.assertEqual(lines[-1], "3 passed, 2 failed", lines)
        self.assertEqual(lines[0], "test_fine: 2 passed")
        self.assertFalse([line for line in lines if "test_dies" in line or ": ruff" in line])
        self.assertEqual(
            self.run_sh("test_fine"), (True, ["test_fine: 2 passed", "2 passed, 0 failed"])
        )
        ok, lines = self.run_sh("style")
        self.assertEqual(
            (ok, lines[-2:]),
            (False, ["  style: ruff (see its output above)", "0 passed, 1 failed"]),
        )

    def test_k_runs_the_tests_whose_name_or_class_holds_the_pattern(self):
        self.assertEqual(
            self.run_sh("-k good"), (True, ["test_mixed: 1 passed", "1 passed, 0 failed"])
        )
        self.assertEqual(
            self.run_sh("-k Fine"), (True, ["test_fine: 2 passed", "2 passed, 0 failed"])
        )
        # No test of that name: nothing but the summary, no style nor types.
        self.assertEqual(self.run_sh("-k no_such_test"), (True, ["0 passed, 0 failed"]))
        ok, lines = self.run_sh("-k bad test_mixed test_fine")
        self.assertEqual((ok, lines[-1]), (False, "0 passed, 1 failed"), lines)

    def test_modules_run_at_once_and_are_printed_in_their_order(self):
        # test_first ends after test_second, yet is printed first. One at a time, neither
        # would hear from the other.
        first = TOGETHER % (self.talk, "first started", "second started", 'heard("second ended")')
        second = TOGETHER % (self.talk, "second started", "first started", 'say("second ended")')
        write(self.repo + "/tests/test_first.py", first)
        write(self.repo + "/tests/test_second.py", second)
        self.assertEqual(
            self.run_sh("-j 2 test_first test_second"),
            (True, ["test_first: 1 passed", "test_second: 1 passed", "2 passed, 0 failed"]),
        )

    def test_a_module_that_prints_other_runs_summaries_is_counted_by_its_own(self):
        write(self.repo + "/tests/test_noisy.py", NOISY)
        ok, lines = self.run_sh("test_noisy")
        self.assertFalse(ok)
        self.assertEqual(
            lines[-3:],
            ["Failed:", "  test_noisy (.py): test_fails_saying_so (Noisy)", "1 passed, 1 failed"],
            lines,
        )

    def test_ctrl_c_stops_each_module_and_what_it_left_running(self):
        write(self.repo + "/tests/test_slow.py", SLOW % self.talk)
        base = self.talk + "/run"
        pid = launch("sh %s/tests/run.sh test_slow" % self.repo, base, terminal=True)
        sleeper = wait_until(self.talk + "/sleeper", "\n", 15000)
        self.assertTrue(sleeper, read(base + ".log"))
        os.system("kill -s INT -- -%d" % pid)  # Ctrl-C
        self.assertEqual(ended(base, pid), 130, read(base + ".log"))
        # Gone (once reaped: a process just killed may linger a moment as a zombie).
        alive = "ps -o stat= -p %s | grep -qv Z" % sleeper.strip()
        gone = wait_until_false(lambda: sh(alive)[0], 5000)
        os.system("kill %s 2>/dev/null" % sleeper.strip())
        self.assertTrue(gone, "the module's sleeper is still running")

    def test_a_test_that_writes_in_the_checkout_fails_the_run_naming_what_it_changed(self):
        # A maker's own teach.json overwritten, a sequences/ folder made and removed again:
        # every test passed, and the run fails all the same.
        write(self.repo + "/teach.json", "[]")
        write(self.repo + "/tests/test_writes.py", WRITES)
        ok, lines = self.run_sh("test_writes test_fine")
        self.assertFalse(ok, lines)
        self.assertEqual(lines[0:2], ["test_writes: 1 passed", "test_fine: 2 passed"], lines)
        self.assertEqual(
            lines[-3:],
            [
                "Failed:",
                "  the checkout: the run changed what it holds (see above)",
                "3 passed, 1 failed",
            ],
            lines,
        )
        self.assertIn("  ./teach.json", lines)
        self.assertIn("  ./tests", lines)  # where the sequences/ folder was made and removed
        self.assertEqual(
            self.run_sh("test_fine"), (True, ["test_fine: 2 passed", "2 passed, 0 failed"])
        )

    def test_bad_arguments_are_refused_saying_why(self):
        for args, said in (
            ("test_nothing", "no test module test_nothing (no tests/test_nothing.py)"),
            ("tests/fine.py", "no test module tests/fine.py: a module's name starts test_"),
            ("-x", "no option -x"),
            ("-k", "-k wants a PATTERN"),
            ("-j 0", "-j wants a number of modules at once, 1 or more, got '0'"),
        ):
            ok, lines = self.run_sh(args)
            self.assertFalse(ok, args)
            self.assertEqual(lines, ["tests/run.sh: %s (sh tests/run.sh --help)" % said], args)
        ok, lines = self.run_sh("--help")
        self.assertTrue(ok, lines)
        for form in ("run.sh test_frames", "run.sh -k ", "run.sh -v", "run.sh -j ", "--mpy-all"):
            self.assertTrue([line for line in lines if form in line], form)


class Modes(unittest.TestCase):
    def test_every_script_is_executable(self):
        for path in ("boards/unix.sh", "boards/simpty.py", "tests/run.sh", ".ci/run"):
            self.assertTrue(os.stat(path)[0] & 0o100, path + " is not executable")


if __name__ == "__main__":
    unittest.main()
