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


class Mpy(unittest.TestCase):
    def test_a_traceback_from_inside_the_driver_names_its_line(self):
        # In the .mpy pass busservo is the .mpy that `sh boards/unix.sh --mpy` makes: with
        # mpy-cross's default optimisation it keeps its line numbers (-O3 dropped them).
        import io
        import sys

        import busservo
        from fakeuart import FakeUART

        try:
            busservo.BusServo(FakeUART()).move(300, 500, 0)
        except ValueError as e:
            out = io.StringIO()
            sys.print_exception(e, out)
            text = out.getvalue()
        with open("lib/busservo.py") as f:  # the line that raised, in the source
            lines = f.read().split("\n")
        line = [i + 1 for i, s in enumerate(lines) if "must be an int in" in s]
        self.assertIn('busservo.py", line %d, in _check' % line[0], text)
        self.assertIn("servo_id must be an int in 0..255, got 300", text)


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
            self.assertEqual(os.listdir(target), ["busservo.py"])  # the driver alone
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
                    "busservo_motion.mpy",
                    "busservo_web.html.gz",
                    "busservo_web.mpy",
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
            sh("rm -rf %s %s %s" % (target, root, log))


class Mpremote(unittest.TestCase):
    def readme_commands(self):
        # The README's own mpremote commands that copy from lib/ and run examples/ (but the
        # web panel, which serves until Ctrl-C: test_examples.py runs it).
        with open("README.md") as f:
            lines = [line.split("#")[0].strip() for line in f]
        return [
            line[len("mpremote ") :]
            for line in lines
            if line.startswith("mpremote cp lib/")
            or line.startswith("mpremote run examples/")
            and line != "mpremote run examples/web_panel.py"
        ]

    def test_the_readme_commands_copy_and_run_on_a_repl(self):
        if not sh("command -v socat")[0]:
            print(
                "\n*** SKIPPED: socat is missing and could not be installed: mpremote untested ***"
            )
            raise unittest.SkipTest("socat is missing")
        commands = self.readme_commands()
        self.assertTrue(len(commands) >= 3, commands)
        device = scratch("device")
        pty = device + ".pty"
        os.mkdir(device)
        # The unix port's REPL behind a pty, in an empty folder: its filesystem.
        repl = start(
            "cd %s && MICROPYPATH=.frozen exec socat PTY,link=%s,raw,echo=0 "
            "EXEC:%s/%s,pty,raw,echo=0,stderr,setsid,ctty"
            % (device, pty, os.getcwd(), MICROPYTHON),
            device + ".log",
        )
        try:
            self.assertTrue(wait_for(pty), "socat made no pty")
            connect = "%s connect %s resume " % (MPREMOTE, pty)  # resume: no soft reset
            for command in commands:
                ok, out = sh(connect + command)
                self.assertTrue(ok, command + ": " + out)
            ok, out = sh(connect + "exec 'import busservo; print(busservo.__file__)'")
            self.assertEqual(out.strip(), "busservo.py")  # the copy, not lib/
            self.assertTrue("busservo.py" in os.listdir(device))
            ok, out = sh(connect + "run examples/battery.py")
            self.assertTrue(ok, out)
            lines = out.split("\n")  # no board.py on this "board": the simulator, said first
            self.assertTrue(lines[0].startswith("no board.py found: using the simulated"), out)
            self.assertIn("battery: 7500 mV", lines)
        finally:
            stop(repl)
            sh("rm -rf %s %s.log %s" % (device, device, pty))


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
        self.assertEqual(named, ["lib/busservo.py"])
        named, meta = self.run_manifest(sim=True, asyncio=True, motion=True)
        self.assertEqual(
            named,
            [
                "lib/busservo.py",
                "lib/busservo_sim.py",
                "lib/busservo_async.py",
                "lib/busservo_motion.py",
            ],
        )
        for path in named:
            os.stat(path)
        named, meta = self.run_manifest(web=True)  # the panel needs the motion layer
        self.assertEqual(
            named, ["lib/busservo.py", "lib/busservo_motion.py", "lib/busservo_web.py"]
        )
        self.assertEqual(meta["version"], version_of_package_json())

    def test_package_json_names_files_that_exist(self):
        with open("package.json") as f:
            package = json.load(f)
        self.assertEqual(package["urls"], [["busservo.py", "lib/busservo.py"]])
        for _, path in package["urls"]:
            os.stat(path)


if __name__ == "__main__":
    unittest.main()
