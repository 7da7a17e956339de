# The documentation does what it says: the README's REPL session and its tour run on the unix
# port as shown, its links lead somewhere, every example is listed, and the wiring pictures are
# well-formed SVG, name the pins the board files use, and render (with resvg, which
# tests/run.sh installs into .venv/; without it that test skips, saying so).
import os
import struct
import unittest

from shell import scratch, sh

PYTHON = ".venv/bin/python"  # CPython, for the XML parser and the renderer
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
    if "Pin(" in tx:  # rp2.py: tx=Pin(0), rx=Pin(1): the Pico's names are GP0, GP1
        return ["UART" + number, "GP" + tx[4:] + " ", "GP" + rx[4:] + " "]
    return ["UART" + number, "GPIO" + tx + " TX", "GPIO" + rx + " RX"]


class Readme(unittest.TestCase):
    def test_the_repl_session_runs_as_shown(self):
        # Each ">>> " line is typed into `sh boards/unix.sh`'s REPL (-i -c "": the REPL, reading
        # a file as typed lines); what it prints after the banner is the block itself. A
        # traceback's "  ..." stands for its "  File" lines, which name lines of lib/.
        shown = [line.rstrip() for line in block(read("README.md"), "## At the REPL", "```text")]
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
        tour = block(read("README.md"), "## A short tour", "```python")
        self.assertIn("while True:                             # a control loop", tour)
        code = "\n".join(tour).replace("while True:", "for _ in range(100):")
        script = scratch("tour") + ".py"
        with open(script, "w") as f:
            f.write(code + '\nprint("tour done", bus.battery, sorted(bus.positions.items()))\n')
        try:
            ok, out = sh("sh boards/unix.sh " + script)
        finally:
            os.remove(script)
        self.assertTrue(ok, out)
        self.assertIn("tour done 7500 [(1, ", out)

    def test_links_lead_somewhere(self):
        for doc in ("README.md", "boards/README.md"):
            text = read(doc)
            folder = doc.rpartition("/")[0]
            anchors = [
                slug(line.lstrip("#").strip()) for line in text.split("\n") if line[:1] == "#"
            ]
            for target in links(text):
                if target.startswith("http"):
                    continue
                if target.startswith("#"):
                    self.assertIn(target[1:], anchors, doc + ": " + target)
                    continue
                path = (folder + "/" if folder else "") + target
                try:
                    os.stat(path)
                except OSError:
                    self.fail("%s links to %s, which is not there" % (doc, target))

    def test_every_example_is_listed(self):
        text = read("README.md")
        for name in os.listdir("examples"):
            if name.endswith(".py"):
                self.assertIn("\n| `%s` | " % name, text, "the README's examples table")

    def test_the_wiring_warns_of_5_v(self):
        # (assertTrue, not assertIn: a failure names what is missing, not the whole README)
        for doc in ("README.md", "boards/README.md"):
            text = read(doc).replace("\n", " ")
            for words in ("not 5 V tolerant", "1 kΩ in series", "examples/check_wiring.py"):
                self.assertTrue(words in text, "%s: no %r" % (doc, words))
        text = read("README.md")
        for symptom in ("`OSError: [Errno 110] ETIMEDOUT`", "`bus.noise` grows", "`OSError: [E"):
            self.assertTrue("\n| " + symptom in text, "no troubleshooting row " + symptom)


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
            for doc in ("README.md", "boards/README.md"):
                self.assertIn(svg.rpartition("/")[2] + ")", read(doc), doc + " shows " + svg)

    def test_the_pin_table_matches_the_board_files(self):
        table = read("boards/README.md")
        self.assertIn("| `esp32.py` | ESP32 | UART2 | GPIO17 | GPIO16 |", table)
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
