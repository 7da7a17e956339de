# tests/bench_arm.py, the arm's figures, in short (a coarse grid, one port, one speed, a few
# real-time calls), so that it cannot rot: its figures obey what the positions' resolution and
# the wire allow, and the same run gives the same figures. No figure of real time is checked.
import unittest

import bench_arm
import busservo
from bench_arm import limit

GRID = (range(0, 301, 100), range(-200, 201, 100), range(0, 201, 100), (None, -45))


class Harness(unittest.TestCase):
    def test_the_round_trip_is_within_the_positions_resolution(self):
        r = bench_arm.round_trip(GRID)
        self.assertEqual(r["tried"], 4 * 5 * 3 * 2)
        self.assertTrue(0 < r["reached"] < r["tried"], r)
        self.assertTrue(0 < r["mean_mm"] <= r["max_mm"] <= 2, r)
        self.assertTrue(r["max_pitch"] <= 0.5, r)

    def test_a_line_comes_at_the_wires_pace_and_keeps_to_the_line(self):
        for n in (4, 6):
            r = bench_arm.line("rp2", n, 200)
            self.assertEqual(r["ms"], 1000)  # 200 mm at 200 mm/s
            self.assertTrue(0.95 * limit(n) <= r["rate"] <= 1.01 * limit(n), r)
            self.assertTrue(r["frames"] >= r["updates"], r)
            self.assertTrue(r["at_frames_mm"] <= 1 and r["between_mm"] <= 1, r)
            self.assertTrue(r["on_the_way_mm"] <= 3 and r["end_mm"] <= 0.5, r)
            self.assertTrue(r["blocked_us"] <= 1000, r)  # simulated time: step() never waits
            self.assertEqual(r["lost"], 0)

    def test_the_same_run_gives_the_same_figures(self):
        self.assertEqual(bench_arm.line("esp32", 4, 200), bench_arm.line("esp32", 4, 200))

    def test_the_clocks_are_given_back(self):
        clock = busservo.time
        bench_arm.line("rp2", 4, 200)
        bench_arm.solve(10)
        self.assertIs(busservo.time, clock)

    def test_the_solve_is_put_beside_move_many_and_its_heap_counted(self):
        rows = bench_arm.solve(50)
        self.assertEqual(rows[0]["what"], "move_many() of the 4 joints")
        self.assertEqual((rows[0]["ratio"], rows[0]["heap"]), (1, 0))
        heap = {r["what"]: r["heap"] for r in rows}
        self.assertEqual(heap["a line's step(), the wire busy"], 0)
        self.assertTrue(heap["a line's step() that sends"] > 0)  # floats are heap objects
        for r in rows:
            self.assertEqual(r["us"] is None, r["ratio"] is None)

    def test_main_prints_each_table(self):
        lines = []
        bench_arm.main(("esp32",), (200,), GRID, 50, lines.append)
        for row in (
            "| 70 / 105 / 98 / 150 mm |",
            "| esp32 | 4 | 200 |",
            "| esp32 | 6 | 200 |",
            "| move_to(x, y, z, pitch, ms=) |",
        ):
            self.assertEqual(len([s for s in lines if s.startswith(row)]), 1, row)


if __name__ == "__main__":
    unittest.main()
