# tests/bench_web.py, the web panel's benchmark, in short, so that it cannot rot: it runs to
# its end and prints every figure. The figures themselves are not judged here (the machine
# is shared), except those that are not timed: the page's size and that no target was lost.
import unittest

from shell import sh


class Harness(unittest.TestCase):
    def test_the_benchmark_prints_its_figures(self):
        ok, out = sh("sh boards/unix.sh tests/bench_web.py quick")
        self.assertTrue(ok, out)
        rows = {line.split("|")[1].strip(): line for line in out.split("\n") if line[:2] == "| "}
        page = rows["page, gzipped (raw)"].split("|")[2].split()
        self.assertTrue(int(page[0]) <= 12288, out)
        for name in (
            "RAM: import busservo_web",
            "RAM: serving, one client connected",
        ):
            self.assertTrue(int(rows[name].split("|")[2].split()[0]) > 0, out)
        for joints in ("1 joint", "4 joints"):
            self.assertIn(", 0 lost", rows["latency, slider to wire, " + joints], out)
        stall = [row for name, row in rows.items() if name.startswith("longest stall")]
        self.assertEqual(len(stall), 3, out)  # capturing and streaming; jogging; calibrating
        for row in stall:
            self.assertIn("the event loop ", row, out)

    def test_help_prints_its_usage_and_runs_nothing(self):
        for option in ("--help", "-h"):
            ok, out = sh("sh boards/unix.sh tests/bench_web.py " + option)
            self.assertTrue(ok, out)
            self.assertIn("sh boards/unix.sh tests/bench_web.py quick ", out)
            self.assertFalse("| figure |" in out, out)  # no figure measured
        for args, said in (
            ("--bogus", "unknown argument '--bogus'"),
            ("--32bit", "--32bit wants a PATH"),
        ):
            ok, out = sh("sh boards/unix.sh tests/bench_web.py " + args)
            self.assertFalse(ok, out)
            self.assertEqual(
                out, "bench_web.py: %s (sh boards/unix.sh tests/bench_web.py --help)\n" % said
            )
