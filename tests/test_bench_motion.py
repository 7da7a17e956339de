# tests/bench_motion.py, the benchmark of the 100 Hz control loop, in short (1 s of
# simulated time, one port, 6 servos), so that it cannot rot: its figures obey what the
# wire allows, its frames are whole, and the same run gives the same figures.
import unittest

import bench_motion
import busservo
import wire
from bench_motion import frame_ms, limit

N = 6


def run(way, port="rp2"):
    return bench_motion.measure(port, N, way, seconds=1)


class Harness(unittest.TestCase):
    def test_no_way_is_faster_than_the_wire(self):
        for way in bench_motion.WAYS:
            r = run(way)
            self.assertTrue(0 < r["rate"] <= limit(N), (way, r["rate"]))
            self.assertTrue(r["percent"] <= 100, way)
        # The naive way sends N 10-byte frames a pose: 960 / (10N) a second at most.
        self.assertTrue(run("move")["rate"] <= 96 / N)

    def test_a_pose_is_never_younger_than_its_bytes_take_on_the_wire(self):
        for way in bench_motion.WAYS:
            r = run(way)
            least = 10 * N * 10 / 9.6 if way == "move" else frame_ms(N)
            self.assertTrue(r["age_min_ms"] >= least, (way, r["age_min_ms"], least))
            self.assertTrue(r["age_min_ms"] <= r["age_mean_ms"] <= r["age_max_ms"], way)

    def test_every_frame_is_whole_and_carries_one_ticks_targets(self):
        for way in bench_motion.WAYS:
            r = run(way)
            self.assertEqual(r["whole"], r["frames"], way)
            self.assertEqual((r["wrong"], r["lost"], r["beeps"], r["errors"]), (0, 0, 0, 0), way)
        r = run("move")  # N frames a tick, every one of them sent
        self.assertEqual(r["frames"], N * r["ticks"])
        self.assertTrue(r["poses"] <= r["ticks"])

    def test_the_naive_loop_is_late_and_blocked_for_its_frames_time(self):
        r = run("move")
        self.assertTrue(r["ticks"] < 100)  # 1 s at 100 Hz, had it kept its pace
        self.assertTrue(0 <= r["blocked_mean_ms"] <= r["blocked_max_ms"])
        self.assertTrue(r["blocked_max_ms"] >= 10 * N * 10 / 9.6 - 10)

    def test_a_frames_targets_name_one_tick(self):
        target, match = bench_motion.target, bench_motion.match
        starts = list(range(0, 3000000, 10000))  # 300 ticks
        for k in range(1, 300):
            for s in range(1, 19):
                self.assertTrue(abs(target(k, s) - target(k - 1, s)) >= 3, (k, s))
        pairs = [(s, target(42, s)) for s in range(1, N + 1)]
        self.assertEqual(match(pairs, starts, 0, 0), 42)
        self.assertEqual(match(pairs, starts, 43, 1), None)  # an older tick's: not found
        near = [(s, p + 1) for s, p in pairs]  # rounded up: way 3's tolerance only
        self.assertEqual((match(near, starts, 0, 0), match(near, starts, 0, 1)), (None, 42))
        mixed = pairs[:3] + [(s, target(43, s)) for s in range(4, N + 1)]
        self.assertEqual(match(mixed, starts, 0, 1), None)

    def test_the_same_run_gives_the_same_figures(self):
        for port in wire.PORTS:
            self.assertEqual(run("move_many", port), run("move_many", port), port)

    def test_the_driver_gets_its_clock_back(self):
        clock = busservo.time
        run("stream")
        self.assertIs(busservo.time, clock)

    def test_main_prints_a_row_a_case_and_stream_s_goals(self):
        lines = []
        results = bench_motion.main(1, ("esp32",), (N,), lines.append)
        self.assertEqual(len(results), 3)
        rows = [s for s in lines if s.startswith("| esp32 | 6 |")]
        self.assertEqual(len(rows), 3)
        self.assertEqual(len([s for s in lines if s.startswith("- esp32, 6 servos:")]), 1)


if __name__ == "__main__":
    unittest.main()
