# tests/bench_record.py, busservo_record's figures, in short (a few seconds of recording, one
# port), so that it cannot rot: its figures obey the goals, and the same run gives the same
# figures. No figure of real time is checked.
import time
import unittest

import bench_record
import busservo
import busservo_motion
import busservo_record


class Harness(unittest.TestCase):
    def tearDown(self):
        busservo.time = busservo_motion.time = busservo_record.time = time

    def test_a_recording_plays_for_its_length_and_follows_it(self):
        w, robot, recording, rec = bench_record.record("esp32", 3000)
        self.assertTrue(len(recording) > 60 and rec.missed == 0, len(recording))
        for speed in (0.25, 2.0):
            length, rms, worst, sent = bench_record.play(w, robot, recording, speed)
            want = recording.duration_ms / speed
            self.assertTrue(abs(length - want) <= want / 100, (speed, length, want))
            self.assertTrue(rms <= 1.5 and worst <= 3, (speed, rms, worst))
            self.assertTrue(2 <= sent <= len(recording), sent)
            w.run_ms(100)

    def test_the_same_run_gives_the_same_figures(self):
        def figures():
            w, robot, recording, rec = bench_record.record("rp2", 2000)
            return recording.data, bench_record.play(w, robot, recording, 1.0)

        self.assertEqual(figures(), figures())

    def test_no_step_allocates(self):
        # Not even the one that asks again: the recorder's query is made once.
        steps, move_us = bench_record.step_figures()
        kinds = ("asks", "waits", "keeps", "packs")
        self.assertEqual([steps[kind][0] for kind in kinds], [0, 0, 0, 0])
        self.assertTrue(move_us > 0)


if __name__ == "__main__":
    unittest.main()
