# Every example runs on the unix port against the simulated controller (no
# board.py: the examples fall back to it), exactly as the README runs the demo.
import os
import unittest

from shell import sh

EXPECT = {
    "async_demo.py": "action group 1 completed",
    "battery.py": "battery: 7.50 V",
    "demo.py": "action group 1 completed",
    "group.py": "frame 7 running: False group: 2 times: 0",
    "move.py": "servo 1 is at 800",
    "move_many.py": "{",
    "playback.py": "estop: group stopped, joints limp",
    "positions.py": "servo 6 at 500",
    "speed.py": "all action groups at 300 %",
    "stream.py": "updates/s (the wire's limit for 6 servos: 38.4)",
    "teach.py": "played back 3 poses",
    "unload.py": "posed at",
}


class Examples(unittest.TestCase):
    def test_every_example_runs(self):
        found = sorted(name for name in os.listdir("examples") if name.endswith(".py"))
        self.assertEqual(found, sorted(EXPECT))  # a new example needs a line above
        for name, text in EXPECT.items():
            ok, out = sh("sh boards/unix.sh examples/" + name)
            self.assertTrue(ok, name + ": " + out)
            self.assertIn(text, out, name)


if __name__ == "__main__":
    unittest.main()
