# The ways busservo gets onto a board, each through the real tool: mip (from a
# local HTTP server), mpremote (to the unix port's REPL behind a pty), and the
# manifest for frozen firmware. The .mpy path is tests/run.sh's second pass.
import json
import os
import unittest

from shell import MICROPYTHON, MPREMOTE, scratch, sh, start, stop, wait_for


def version_of_package_json():
    with open("package.json") as f:
        return json.load(f)["version"]


class Mip(unittest.TestCase):
    def test_mip_installs_the_driver_from_package_json(self):
        log = scratch("http") + ".log"
        server = start(".venv/bin/python -u -m http.server --bind 127.0.0.1 0", log)
        target = scratch("mip")
        try:
            banner = wait_for(log, 10000, "port ")
            self.assertTrue(banner, "the HTTP server did not start")
            url = "http://127.0.0.1:%d" % int(banner.split("port ")[1].split()[0])
            ok, out = sh(
                "%s -m mip install --target %s %s/package.json" % (MICROPYTHON, target, url)
            )
            self.assertTrue(ok, out)
            # The driver, and the examples' way to find board.py (or the simulator)
            self.assertEqual(sorted(os.listdir(target)), ["busservo.py", "busservo_board.py"])
            # Optional modules are single files: mip install .../lib/busservo_sim.py
            ok, out = sh(
                "%s -m mip install --target %s %s/lib/busservo_sim.py" % (MICROPYTHON, target, url)
            )
            self.assertTrue(ok, out)
            use = (
                "import busservo, busservo_sim;"
                "print(busservo.__file__);"
                "print(busservo.BusServo(busservo_sim.SimController()).read_battery())"
            )
            ok, out = sh("MICROPYPATH=.frozen:%s %s -c '%s'" % (target, MICROPYTHON, use))
            self.assertTrue(ok, out)
            self.assertEqual(out.split(), [target + "/busservo.py", "7500"])
        finally:
            stop(server)
            sh("rm -rf %s %s" % (target, log))


class MipWeb(unittest.TestCase):
    # The web panel's package, lib/busservo_web.json: the driver, the motion layer and the panel,
    # compiled (lib/mpy/), and its page, in one mip command, from this repository alone.
    def test_the_web_package_needs_nothing_from_elsewhere(self):
        with open("lib/busservo_web.json") as f:
            package = json.load(f)
        self.assertEqual(package.get("deps", []), [])
        for _, path in package["urls"]:
            os.stat("lib/" + path)
        self.assertEqual(package["version"], version_of_package_json())

    def test_mip_installs_the_web_panel_and_all_it_needs(self):
        root = scratch("www")
        target = scratch("mip")
        log = root + ".log"
        sh("mkdir -p %s/lib && cp -R lib/* %s/lib/" % (root, root))
        server = start(".venv/bin/python -u -m http.server --bind 127.0.0.1 -d %s 0" % root, log)
        try:
            banner = wait_for(log, 10000, "port ")
            self.assertTrue(banner, "the HTTP server did not start")
            port = int(banner.split("port ")[1].split()[0])
            url = "http://127.0.0.1:%d/lib/busservo_web.json" % port
            ok, out = sh("%s -m mip install --target %s %s" % (MICROPYTHON, target, url))
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
                    "busservo_web_calibrate.mpy",  # its parts
                    "busservo_web_jog.mpy",
                    "busservo_web_sliders.mpy",
                    "busservo_web_teach.mpy",
                ],
            )
            use = (
                "import busservo_web, os;"
                "print(busservo_web.__file__, os.stat(busservo_web.PAGE)[6])"
            )
            ok, out = sh("MICROPYPATH=.frozen:%s %s -c '%s'" % (target, MICROPYTHON, use))
            self.assertTrue(ok, out)
            size = os.stat("lib/busservo_web.html.gz")[6]
            self.assertEqual(out.split(), [target + "/busservo_web.mpy", str(size)])
        finally:
            stop(server)
            sh("rm -rf %s %s %s" % (target, root, log))


class Mpremote(unittest.TestCase):
    def setUp(self):
        if not sh("command -v socat")[0]:
            print(
                "\n*** SKIPPED: socat is missing and could not be installed: mpremote untested ***"
            )
            raise unittest.SkipTest("socat is missing")
        self.device = device = scratch("device")
        self.pty = device + ".pty"
        os.mkdir(device)
        # The unix port's REPL behind a pty, in an empty folder: its filesystem.
        self.repl = start(
            "cd %s && MICROPYPATH=.frozen exec socat PTY,link=%s,raw,echo=0 "
            "EXEC:%s/%s,pty,raw,echo=0,stderr,setsid,ctty"
            % (device, self.pty, os.getcwd(), MICROPYTHON),
            device + ".log",
        )
        self.assertTrue(wait_for(self.pty), "socat made no pty")
        self.connect = "%s connect %s resume " % (MPREMOTE, self.pty)  # resume: no soft reset

    def tearDown(self):
        stop(self.repl)
        sh("rm -rf %s %s.log %s" % (self.device, self.device, self.pty))

    def page_commands(self, page):
        # A page's own mpremote commands that copy from lib/ and run examples/, in its order
        # (but the web panel, which serves until Ctrl-C: test_examples.py runs it).
        with open(page) as f:
            lines = [line.split("#")[0].strip() for line in f]
        return [
            line[len("mpremote ") :]
            for line in lines
            if line.startswith("mpremote cp lib/")
            or line.startswith("mpremote run examples/")
            and line != "mpremote run examples/web_panel.py"
        ]

    def run_commands(self, commands):
        outs = []
        for command in commands:
            ok, out = sh(self.connect + command)
            self.assertTrue(ok, command + ": " + out)
            outs.append(out)
        return outs

    def test_the_front_pages_five_steps_copy_and_run_on_a_repl(self):
        # README.md's steps 2, 4 and 5. Step 3's board file opens a real board's UART: this
        # "board" has none, so the simulated controller stands in for the controller.
        commands = self.page_commands("README.md")
        self.assertEqual(
            commands,
            [
                "cp lib/busservo.py :busservo.py",
                "cp lib/busservo_board.py :busservo_board.py",
                "run examples/check_wiring.py",
                "run examples/demo.py",
            ],
        )
        commands.insert(2, "cp lib/busservo_sim.py :busservo_sim.py")
        outs = self.run_commands(commands)
        self.assertIn("battery: 7.50 V", outs[3])
        self.assertIn("action group 1 completed", outs[4])

    def test_the_boards_pages_commands_copy_and_run_on_a_repl(self):
        commands = self.page_commands("docs/boards.md")
        self.assertTrue(len(commands) >= 3, commands)
        self.run_commands(commands)
        ok, out = sh(self.connect + "exec 'import busservo; print(busservo.__file__)'")
        self.assertEqual(out.strip(), "busservo.py")  # the copy, not lib/
        self.assertTrue("busservo.py" in os.listdir(self.device))
        ok, out = sh(self.connect + "run examples/battery.py")
        self.assertTrue(ok, out)
        lines = out.split("\n")  # no board.py on this "board": the simulator, said first
        self.assertTrue(lines[0].startswith("no board.py found: using the simulated"), out)
        self.assertIn("battery: 7500 mV", lines)

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
        self.assertEqual(route, ["cp examples/teach.py :teach.py", "repl"])
        self.assertIn("then type: import teach", header[1])
        files = scratch("teach")
        os.mkdir(files)
        try:
            with open("examples/teach.py") as f:
                text = f.read()
            with open(files + "/teach.py", "w") as f:
                f.write(
                    text.replace(
                        "I_HAVE_CHECKED_MY_ROBOT = False", "I_HAVE_CHECKED_MY_ROBOT = True"
                    )
                )
            with open(files + "/board.py", "w") as f:
                f.write("from busservo_sim import SimController as uart\n")
            for command in (
                "cp lib/busservo.py :busservo.py",
                "cp lib/busservo_board.py :busservo_board.py",
                "cp lib/busservo_motion.py :busservo_motion.py",
                "cp lib/busservo_sim.py :busservo_sim.py",
                "cp %s/board.py :board.py" % files,
                route[0].replace("examples/", files + "/"),  # the opted-in copy
            ):
                ok, out = sh(self.connect + command)
                self.assertTrue(ok, command + ": " + out)
        finally:
            sh("rm -rf " + files)
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
            ".venv/bin/python tests/typist.py 30 %s -- %s" % (typed, self.connect + route[1])
        )
        self.assertTrue(ok, out)
        for line in ("captured pose 1: ", "captured pose 2: ", "saved 2 poses to teach.json"):
            self.assertIn(line, out)
        self.assertIn("teach.json", os.listdir(self.device))  # on the board, not here


class Tagged(unittest.TestCase):
    # A release is a tag, "v" and package.json's version, and the pages' mip lines for one ask
    # for that tag's package.json: mpremote's "@tag" (its own code, in CPython) and a board's
    # version= (the unix port's mip, which reads no "@"). Neither can reach GitHub here: each
    # records the address it asks for, and is told it is not there.
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
        lines = self.lines("mpremote mip install github:OWNER/busservo@")
        self.assertTrue(len(lines) >= 2, lines)  # the front page's step 2, docs/boards.md
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
                tag = package.split("@")[1]
                self.assertIn("/OWNER/busservo/%s/package.json\n" % tag, out)
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
    def run_manifest(self, **given):
        named = []
        meta = {}

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
                "lib/busservo_web_sliders.py",  # its parts
                "lib/busservo_web_teach.py",
                "lib/busservo_web_jog.py",
                "lib/busservo_web_calibrate.py",
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
        self.assertEqual(meta["version"], version_of_package_json())

    def test_the_driver_says_the_version_package_json_says(self):
        import busservo

        self.assertEqual(busservo.__version__, version_of_package_json())

    def test_package_json_names_files_that_exist(self):
        with open("package.json") as f:
            package = json.load(f)
        self.assertEqual(
            package["urls"],
            [["busservo.py", "lib/busservo.py"], ["busservo_board.py", "lib/busservo_board.py"]],
        )
        for _, path in package["urls"]:
            os.stat(path)


if __name__ == "__main__":
    unittest.main()
