# The documentation does what it says: the front page (README.md) stays short and leads to every
# page of docs/; the code the pages show runs on the unix port as shown (the front page's
# example, the REPL session, the tour, the motion layer's example); every link and #anchor leads
# somewhere; every example is listed; and the wiring pictures are well-formed SVG, name the pins
# the board files use, and render (with resvg, which tests/run.sh installs into .venv/; without
# it that test skips, saying so).
import os
import struct
import unittest

from shell import scratch, sh

PYTHON = ".venv/bin/python"  # CPython, for the XML parser and the renderer
FRONT = "README.md"
FRONT_LINES = 120  # a screen or two
PAGES = sorted("docs/" + name for name in os.listdir("docs") if name.endswith(".md"))
PICTURES = {
    "boards/wiring-pico.svg": "boards/rp2.py",
    "boards/wiring-esp32.svg": "boards/esp32.py",
}


def read(path):
    with open(path) as f:
        return f.read()


def block(text, heading, fence):
    """The lines of the first code block that opens with fence after heading."""
    lines = text.split("\n")
    i = lines.index(heading)
    start = lines.index(fence, i) + 1
    return lines[start : lines.index("```", start)]


def outside_code(text):
    """text's lines that are not in a code block (a fence may be indented, in a list item)."""
    kept = []
    fenced = False
    for line in text.split("\n"):
        if line.strip().startswith("```"):
            fenced = not fenced
        elif not fenced:
            kept.append(line)
    return kept


def anchors(text):
    """The anchors of text's headings."""
    return [slug(line.lstrip("#").strip()) for line in outside_code(text) if line[:1] == "#"]


def run(code, expect, folder=None):
    """Run code with `sh boards/unix.sh`, from folder if given; what it printed, if it has
    expect in it."""
    script = scratch("doc") + ".py"
    with open(script, "w") as f:
        f.write(code)
    try:
        where = "cd %s && " % folder if folder else ""
        ok, out = sh("%ssh %s/boards/unix.sh %s" % (where, os.getcwd(), script))
    finally:
        os.remove(script)
    if not ok or expect not in out:
        raise AssertionError("%r not printed:\n%s" % (expect, out))
    return out


def links(text):
    """The targets of the markdown links and images in text: [label](target)."""
    found = []
    at = text.find("](")
    while at >= 0:
        end = text.find(")", at)
        found.append(text[at + 2 : end])
        at = text.find("](", end)
    return found


def slug(heading):
    """A heading's anchor, as GitHub makes it."""
    kept = "".join(c for c in heading.lower() if c.isalpha() or c.isdigit() or c in " -_")
    return kept.replace(" ", "-")


def pins(board):
    """The pin names a board file's uart() uses, as the pictures write them."""
    source = read(board)
    uart = source[source.index("UART(", source.index("def uart")) :]
    uart = uart[: uart.index(")\n") + 1]
    number = uart[len("UART(") : uart.index(",")]
    tx = uart[uart.index("tx=") + 3 :].split(",")[0].strip(")")
    rx = uart[uart.index("rx=") + 3 :].split(",")[0].strip(")")

    def value(name):  # esp32.py: UART(UART_ID, ...), with UART_ID = 2 at its top
        for line in source.split("\n"):
            if line.startswith(name + " = "):
                return line[len(name) + 3 :].split()[0]
        return name

    number, tx, rx = value(number), value(tx), value(rx)
    if "Pin(" in tx:  # rp2.py: tx=Pin(0), rx=Pin(1): the Pico's names are GP0, GP1
        return ["UART" + number, "GP" + tx[4:] + " ", "GP" + rx[4:] + " "]
    return ["UART" + number, "GPIO" + tx + " TX", "GPIO" + rx + " RX"]


class FrontPage(unittest.TestCase):
    def test_it_fits_a_screen_or_two_and_leads_to_every_page(self):
        text = read(FRONT)
        self.assertTrue(text.count("\n") <= FRONT_LINES, "README.md: %d lines" % text.count("\n"))
        self.assertTrue(len(PAGES) >= 8, PAGES)
        for page in PAGES:
            self.assertIn("](%s)" % page, text, "README.md links to " + page)
            title = read(page).split("\n")[0]
            self.assertTrue(title.startswith("# "), page + " opens with its title")

    def test_its_example_runs_on_the_unix_port(self):
        # As written: on the unix port there is no board.py, so the simulator answers.
        code = block(read(FRONT), "## In a few lines", "```python")
        self.assertTrue(len(code) <= 20, "a few lines, not %d" % len(code))
        out = run("\n".join(code) + "\n", "7500\n{1: ")
        self.assertIn(", 2: 500, 3: 500}", out)

    def test_its_five_steps_come_in_order(self):
        text = read(FRONT)
        steps = text[text.index("## Your first board in five steps") :]
        steps = steps[: steps.index("\n## ")]
        at = [steps.index("\n%d. **" % n) for n in range(1, 6)]
        self.assertEqual(at, sorted(at))
        wires, install, board, check, demo = [
            steps[start:end] for start, end in zip(at, at[1:] + [len(steps)])
        ]
        self.assertIn("wiring-pico.svg", wires)
        self.assertIn("not 5 V tolerant", wires)
        self.assertIn("mpremote mip install package.json", install)
        self.assertIn(":board.py", board)
        self.assertIn("mpremote run examples/check_wiring.py", check)
        self.assertIn("mpremote run examples/demo.py", demo)


class Pages(unittest.TestCase):
    def test_the_repl_session_runs_as_shown(self):
        # Each ">>> " line is typed into `sh boards/unix.sh`'s REPL (-i -c "": the REPL, reading
        # a file as typed lines); what it prints after the banner is the block itself. A
        # traceback's "  ..." stands for its "  File" lines, which name lines of lib/.
        shown = [
            line.rstrip() for line in block(read("docs/repl.md"), "## The session", "```text")
        ]
        shown = shown[[line.startswith(">>> ") for line in shown].index(True) :]
        # In a home of its own: the REPL keeps its history there (.micropython.history).
        home = scratch("home")
        os.mkdir(home)
        typed = home + "/typed"
        with open(typed, "w") as f:
            f.write("".join(line[4:] + "\n" for line in shown if line.startswith(">>> ")))
        try:
            ok, out = sh('HOME=%s sh boards/unix.sh -i -c "" <%s' % (home, typed))
        finally:
            sh("rm -rf " + home)
        self.assertTrue(ok, out)
        got = [line.rstrip() for line in out.split("\n")]
        got = got[[line.startswith(">>> ") for line in got].index(True) :]
        while got and got[-1] in ("", ">>>"):  # the prompt that waits for more
            got.pop()
        expect = []
        for line in shown:
            if line == "  ...":
                while got[len(expect)].startswith("  File "):
                    expect.append(got[len(expect)])
            else:
                expect.append(line)
        self.assertEqual(got, expect, "\n".join(got))

    def test_the_tour_runs_on_the_unix_port(self):
        # As written, with one change: its control loop, `while True:`, goes round 100 times
        # rather than for ever. On the unix port there is no board.py: the simulator answers.
        tour = block(read("docs/driver.md"), "## A short tour", "```python")
        self.assertIn("while True:                             # a control loop", tour)
        code = "\n".join(tour).replace("while True:", "for _ in range(100):")
        code += '\nprint("tour done", bus.battery, sorted(bus.positions.items()))\n'
        run(code, "tour done 7500 [(1, ")

    def test_the_motion_layers_example_runs_on_the_simulator(self):
        # Its uart() is board.py's; here the simulator's, told that servo 6 is a PWM servo, as
        # the page says. It saves arm.json where it runs: in a folder of the test's own.
        code = block(read("docs/motion.md"), "# Joints in degrees: the motion layer", "```python")
        stand_in = (
            "import busservo_sim\n\n\ndef uart():\n"
            "    sim = busservo_sim.SimController()\n    sim.pwm.add(6)\n    return sim\n\n\n"
        )
        folder = scratch("motion")
        os.mkdir(folder)
        try:
            out = run(
                stand_in + "\n".join(code) + '\nprint("where", arm.where())\n', "where {", folder
            )
            self.assertEqual(os.listdir(folder), ["arm.json"])
        finally:
            sh("rm -rf " + folder)
        for joint in ("base", "shoulder", "claw"):
            self.assertIn("'%s': " % joint, out)

    def test_links_and_anchors_lead_somewhere(self):
        for doc in [FRONT] + PAGES + ["boards/README.md"]:
            text = read(doc)
            folder = doc.rpartition("/")[0]
            own = anchors(text)
            self.assertEqual(len(own), len(set(own)), doc + ": two headings, one anchor")
            for target in links(text):
                if target.startswith("http"):
                    continue
                path, _, anchor = target.partition("#")
                if path:
                    path = (folder + "/" if folder else "") + path
                    try:
                        os.stat(path)
                    except OSError:
                        self.fail("%s links to %s, which is not there" % (doc, target))
                if anchor:
                    heads = anchors(read(path)) if path else own
                    self.assertIn(anchor, heads, doc + ": " + target)

    def test_every_example_is_listed(self):
        text = read("docs/basics.md")
        for name in os.listdir("examples"):
            if name.endswith(".py"):
                self.assertIn("\n| `%s` | " % name, text, "docs/basics.md's examples table")

    def test_every_package_has_its_row_and_each_example_its_package(self):
        # docs/boards.md's table of the packages: lib/busservo_teleop.json had no row, though
        # teleop.py's header names it (issue 42). Each package file a row; each example's
        # package (its header's mip line) one whose row names the example.
        with open("docs/boards.md") as f:
            rows = [line for line in f if line.startswith("| `")]
        packages = ["package.json"] + sorted(
            "lib/" + name for name in os.listdir("lib") if name.endswith(".json")
        )
        for package in packages:
            row = [line for line in rows if line.startswith("| `%s` |" % package)]
            self.assertEqual(len(row), 1, package)
        for name in sorted(os.listdir("examples")):
            if not name.endswith(".py"):
                continue
            with open("examples/" + name) as f:
                head = [line for line in f if line.startswith("#   mpremote mip install ")]
            if not head:
                continue
            package = head[0].split()[4]
            row = [line for line in rows if line.startswith("| `%s` |" % package)][0]
            self.assertIn("`%s`" % name[:-3], row.split("|")[3], (name, package))

    def test_the_wiring_warns_of_5_v(self):
        # (assertTrue, not assertIn: a failure names what is missing, not the whole page)
        for doc in (FRONT, "docs/boards.md", "boards/README.md"):
            text = " ".join(read(doc).split())
            for words in ("not 5 V tolerant", "1 kΩ in series", "examples/check_wiring.py"):
                self.assertTrue(words in text, "%s: no %r" % (doc, words))
        text = read("docs/troubleshooting.md")
        for symptom in (
            "`OSError: [Errno 110] ETIMEDOUT: no reply`",
            "`bus.noise` grows",
            "`OSError: [E",
            "`mpremote: no device found`",
        ):
            self.assertTrue("\n| " + symptom in text, "no troubleshooting row " + symptom)

    def test_linux_asks_for_the_dialout_group(self):
        # A USB-serial port opens only for its group's members: the front page says how to
        # join, docs/boards.md also how to see the group.
        for doc in (FRONT, "docs/boards.md"):
            text = " ".join(read(doc).split())
            for words in ("sudo usermod -aG dialout $USER", "log out and in"):
                self.assertTrue(words in text, "%s: no %r" % (doc, words))
        self.assertIn("ls -l /dev/ttyUSB0", read("docs/boards.md"))


class Pictures(unittest.TestCase):
    def test_the_pictures_are_well_formed_svg_with_the_board_files_pins(self):
        # CPython's XML parser (set-up needs Python 3, so it is there wherever the tests run).
        check = (
            "import sys, xml.etree.ElementTree as E; r = E.parse(sys.argv[1]).getroot(); "
            "print(r.tag, r.get('width'), r.get('height'))"
        )
        for svg, board in PICTURES.items():
            ok, out = sh('%s -c "%s" %s' % (PYTHON, check, svg))
            self.assertTrue(ok, svg + ": " + out)
            self.assertEqual(out.split(), ["{http://www.w3.org/2000/svg}svg", "800", "500"])
            text = read(svg)
            for name in pins(board):
                self.assertIn(name, text, "%s names %s's pins" % (svg, board))
            for doc in (FRONT, "docs/boards.md", "boards/README.md"):
                self.assertIn(svg.rpartition("/")[2] + ")", read(doc), doc + " shows " + svg)

    def test_the_pin_table_matches_the_board_files(self):
        table = read("boards/README.md")
        self.assertIn(
            "| `esp32.py` | ESP32 (WROOM modules, ESP32-S3) | UART2 | GPIO17 | GPIO16 |", table
        )
        self.assertIn(
            "| `rp2.py` | Raspberry Pi Pico (rp2) | UART0 | GP0 (pin 1) | GP1 (pin 2) |", table
        )
        self.assertEqual(pins("boards/esp32.py"), ["UART2", "GPIO17 TX", "GPIO16 RX"])
        self.assertEqual(pins("boards/rp2.py"), ["UART0", "GP0 ", "GP1 "])

    def test_the_pictures_render(self):
        for svg in PICTURES:
            png = scratch("wiring") + ".png"
            try:
                ok, out = sh("%s tests/render_svg.py %s %s" % (PYTHON, svg, png))
                if out.startswith("no renderer"):
                    print(
                        "\n*** SKIPPED: %s: %s (tests/run.sh installs it) ***" % (svg, out.strip())
                    )
                    raise unittest.SkipTest(out.strip())
                self.assertTrue(ok, svg + ": " + out)
                with open(png, "rb") as f:
                    data = f.read()
            finally:
                sh("rm -f " + png)
            self.assertEqual(data[:8], b"\x89PNG\r\n\x1a\n", svg)
            self.assertEqual(struct.unpack(">II", data[16:24]), (800, 500), svg)
            self.assertTrue(len(data) > 10000, "%s: a PNG of %d bytes" % (svg, len(data)))
            # "800x500 colours=N ink=P": text and lines in many colours, on a white ground.
            size, colours, ink = out.split()
            self.assertEqual(size, "800x500")
            self.assertTrue(int(colours[len("colours=") :]) > 50, out)
            self.assertTrue(10 < float(ink[len("ink=") :]) < 80, out)


if __name__ == "__main__":
    unittest.main()
