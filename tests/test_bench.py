# docs/benchmarks.md's benchmark command runs to its end: tests/bench.py, in short (300 calls a
# figure), so that it cannot rot between the runs that give the docs their figures.
import unittest

from shell import sh


class Bench(unittest.TestCase):
    def test_the_benchmark_runs_and_prints_its_tables(self):
        ok, out = sh("sh boards/unix.sh tests/bench.py quick")
        self.assertTrue(ok, out)
        for line in (
            "| move | ",
            "| poll(), idle | ",
            "| request and decode 6 positions | ",
            "| busservo.mpy (mpy-cross, line numbers kept: as built) | ",
            "| CPython 3.",  # the CPython column's heading, then its figures
            "(vendor-style ",
            "Six positions read end to end on CPython (busservo_host's port, pyserial, a pty",
        ):
            self.assertIn(line, out)


if __name__ == "__main__":
    unittest.main()
