# tests/bench_links.py, the link's figures (docs/computer.md, docs/benchmarks.md), in short (4
# s of simulated time a model), so that it cannot rot: on simulated time its counts are the
# same run after run, and this driver's rows have no wrong answer and no timeout without a
# fault, and one timeout a reply a fault made late or lost. No figure of real time (queries a
# second, CPU) is checked.
import unittest

from shell import PYTHON, sh


class Bench(unittest.TestCase):
    def test_the_benchmark_runs_and_every_link_answers_every_query(self):
        ok, out = sh(PYTHON + " tests/bench_links.py quick")
        self.assertTrue(ok, out)
        rows = {}
        for line in out.split("\n"):
            cells = [c.strip() for c in line.strip("| ").split("|")]
            if len(cells) >= 4:
                rows[cells[0]] = cells[1:]
        for name in (
            "CH340, a quiet computer",
            "FTDI, a quiet computer",
            "FTDI, a busy computer (0..8 ms more a hand-over)",
            "FTDI, a very busy computer (0..20 ms more)",
            "CH340, the program preempted 0..30 ms after 1 write in 5",
            "HID, a quiet computer",
            "HID, a very busy computer (0..20 ms more)",
            "a board's UART (rp2), for reference",
        ):
            self.assertEqual(rows[name][1:3], ["0 (0.0 %)", "0"], (name, out))
        for name in (
            "FTDI, very busy; a reply 300 ms late every 2 s",
            "FTDI, very busy; a reply lost every 2 s",
            "HID, very busy; a reply 300 ms late every 2 s",
        ):
            faults, timeouts, wrong = (int(c) for c in rows[name][:3])
            self.assertEqual(wrong, 0, (name, out))
            # A late battery reply holds the positions reply behind it late too: two.
            self.assertTrue(1 <= timeouts <= 2 * faults, (name, out))
        self.assertIn("| a serial port (busservo_host, a pty) | ", out)
        self.assertIn("| a HID controller (busservo_hid, test_hid's binding) | ", out)


if __name__ == "__main__":
    unittest.main()
