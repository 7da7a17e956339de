# The simulated controller, driven by the real driver, on a clock the tests step.
import time
import unittest

import busservo
from busservo import (
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_RUN,
    CMD_ACTION_GROUP_STOP,
)
from busservo_sim import SimController
from test_frames import drain as events


class Clock:
    def __init__(self):
        self.now = 1000

    def __call__(self):
        return self.now

    def step(self, ms):
        self.now += ms


class Simulator(unittest.TestCase):
    def setUp(self):
        self.clock = Clock()
        self.sim = SimController(groups={1: 500, 2: 2000, 8: 1500}, ticks_ms=self.clock)
        self.bus = busservo.BusServo(self.sim)

    def test_servos_move_linearly_to_their_targets(self):
        self.bus.move_many([(1, 900), (2, 100)], 1000)
        self.assertEqual(self.bus.read_positions([1, 2]), {1: 500, 2: 500})
        self.clock.step(250)
        self.assertEqual(self.bus.read_positions([1, 2]), {1: 600, 2: 400})
        self.clock.step(750)
        self.assertEqual(self.bus.read_positions([1, 2]), {1: 900, 2: 100})
        self.clock.step(5000)
        self.assertEqual(self.bus.read_positions([2]), {2: 100})

    def test_a_new_move_starts_from_where_the_servo_is(self):
        self.bus.move(3, 1000, 1000)
        self.clock.step(500)  # at 750
        self.bus.move(3, 250, 500)
        self.clock.step(250)
        self.assertEqual(self.bus.read_positions([3]), {3: 500})

    def test_move_with_no_time_is_there_at_once(self):
        self.bus.move(4, 42, 0)
        self.assertEqual(self.sim.position(4), 42)

    def test_a_group_runs_then_completes(self):
        self.bus.run_group(8, 2)
        self.assertEqual(events(self.bus), [CMD_ACTION_GROUP_RUN])
        self.assertEqual((self.bus.running, self.bus.group, self.bus.times), (True, 8, 2))
        self.clock.step(2999)
        self.assertEqual(events(self.bus), [])
        self.clock.step(1)
        self.assertEqual(events(self.bus), [CMD_ACTION_GROUP_COMPLETE])
        self.assertEqual((self.bus.running, self.bus.group, self.bus.times), (False, 8, 2))

    def test_a_forever_group_runs_until_stopped(self):
        self.bus.run_group(2, 0)
        self.clock.step(10**6)
        self.assertEqual(events(self.bus), [CMD_ACTION_GROUP_RUN])
        self.assertEqual(self.sim.running, 2)
        self.bus.stop_group()
        self.assertEqual(events(self.bus), [CMD_ACTION_GROUP_STOP])
        self.assertIsNone(self.sim.running)
        self.assertFalse(self.bus.running)

    def test_stop_with_nothing_running_does_nothing(self):
        self.bus.stop_group()
        self.assertEqual(events(self.bus), [])

    def test_a_run_stops_the_group_before(self):
        self.bus.run_group(2, 0)
        self.bus.run_group(1, 1)
        self.assertEqual(
            events(self.bus), [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_STOP, CMD_ACTION_GROUP_RUN]
        )
        self.assertEqual(self.bus.group, 1)

    def test_speed_scales_a_group(self):
        self.bus.set_group_speed(1, 200)  # 500 ms at 200 %: 250 ms
        self.bus.run_group(1)
        self.clock.step(250)
        self.assertEqual(events(self.bus), [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_COMPLETE])
        self.assertEqual(self.sim.speed(2), 100)

    def test_speed_for_all_groups_is_lost_at_power_off(self):
        self.bus.set_group_speed(busservo.ALL_GROUPS, 50)
        self.assertEqual([self.sim.speed(g) for g in (1, 2, 8)], [50, 50, 50])
        self.sim.power_cycle()
        self.assertEqual([self.sim.speed(g) for g in (1, 2, 8)], [100, 100, 100])

    def test_unload_lets_servos_go_limp_where_they_are(self):
        self.bus.move(5, 900, 1000)
        self.clock.step(500)
        self.bus.unload([5, 6])
        self.assertEqual(self.sim.limp, {5, 6})
        self.clock.step(1000)
        self.assertEqual(self.bus.read_positions([5]), {5: 700})
        self.bus.move(5, 100, 0)
        self.assertEqual(self.sim.limp, {6})

    def test_battery(self):
        self.assertEqual(self.bus.read_battery(), 7500)
        self.sim.battery = 6800
        self.assertEqual(self.bus.read_battery(), 6800)

    def test_malformed_frames_beep(self):
        self.sim.write(bytes((0x55, 0x55, 0x09, 0x07)))  # STOP of the wrong length
        self.sim.write(bytes((0x55, 0x55, 0x05, 0x06, 0x63, 0x01, 0x00)))  # no group 99
        self.assertEqual(self.sim.beeps, 2)
        self.bus.request_battery()  # and the controller still answers
        self.assertEqual(events(self.bus), [busservo.CMD_GET_BATTERY_VOLTAGE])
        self.assertEqual(self.sim.beeps, 2)

    def test_commands_split_across_writes(self):
        sent = bytes((0x55, 0x55, 0x05, 0x06, 0x08, 0x01, 0x00))
        for b in sent:
            self.sim.write(bytes((b,)))
        self.assertEqual(self.sim.running, 8)

    def test_silent_answers_nothing(self):
        self.sim.write(bytes((0x55, 0x55, 0x03, 0xF0, 0x01)))
        self.assertTrue(self.sim.silent)
        try:
            self.bus.read_battery(timeout_ms=0)
        except OSError:
            pass
        else:
            self.fail("a silent simulator answered")
        self.sim.silent = False
        self.assertEqual(self.bus.read_battery(), 7500)

    # As a UART: the stream protocol's forms, and no surprises for the caller.

    def test_readinto_never_resizes_the_callers_buffer(self):
        self.sim.write(bytes((0x55, 0x55, 0x02, 0x0F)))  # 6 bytes come back
        buf = bytearray(2)
        self.assertEqual(self.sim.readinto(buf, 10), 2)
        self.assertEqual(len(buf), 2)
        self.assertEqual(self.sim.any(), 4)

    def test_write_takes_the_stream_protocols_forms(self):
        run_8 = bytes((0x55, 0x55, 0x05, 0x06, 0x08, 0x01, 0x00))
        self.assertEqual(self.sim.write(b"xx" + run_8, 2, 3), 3)
        self.assertEqual(self.sim.write(run_8, 3, 100), 4)  # clamped to the buffer
        self.assertEqual(self.sim.running, 8)
        self.assertEqual(self.sim.write(run_8 + b"zz", 7), 7)
        self.assertEqual(self.sim.beeps, 0)

    def test_a_group_longer_than_the_ticks_can_tell_does_not_wedge_it(self):
        # On a board, ticks_add() refuses a span of half the ticks' period
        # (2**29 ms, 6 days): 65535 runs of a 2 s group at 1 % is 150 years.
        import busservo_sim
        import wire

        clock = wire.Clock()
        busservo_sim.time = clock
        try:
            sim = SimController(ticks_ms=clock.ticks_ms)
            bus = busservo.BusServo(sim)
            bus.set_group_speed(2, 1)
            bus.run_group(2, 65535)
            self.assertEqual(sim.running, 2)  # until stopped
            bus.stop_group()
            self.assertIsNone(sim.running)
            bus.run_group(8)
            self.assertEqual(sim.running, 8)
        finally:
            busservo_sim.time = time


if __name__ == "__main__":
    unittest.main()
