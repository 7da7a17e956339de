# busservo_motion: the calibration maths, moves in degrees, teach and play back, and the
# stream, on the wire-faithful world of tests/wire.py (a stepped clock, the rp2 and esp32
# UART models, the simulated controller). The driver and the motion layer both run on the
# world's clock: busservo.time = busservo_motion.time = w.clock.
import asyncio
import errno
import json
import math
import os
import time
import unittest

import busservo
import busservo_motion as bm
import wire
from busservo import CMD_ACTION_GROUP_STOP, CMD_MULT_SERVO_POS_READ, CMD_MULT_SERVO_UNLOAD
from busservo import CMD_SERVO_MOVE as MOVE
from fakeuart import FakeUART
from shell import scratch
from test_alloc import heap_per_call


def world(port="rp2"):
    """(world, bus), the driver and the motion layer on the world's clock."""
    w = wire.World(port)
    w.sim.pwm.add(6)  # the claw: a PWM servo, 500..2500 us
    busservo.time = bm.time = w.clock
    return w, busservo.BusServo(w.uart)


def arm(bus):
    """The issue's arm: a bus servo, a reversed and trimmed one, a PWM claw."""
    return bm.Robot(
        bus,
        {
            "base": bm.Joint(1),
            "shoulder": bm.Joint(2, direction=-1, trim=3.5, limits=(-90, 90)),
            "claw": bm.Joint(6, kind=bm.PWM_180, limits=(0, 60)),
        },
    )


def chain(bus, n, **kw):
    """A robot of n bus servos, ids 1..n, named j1..jn."""
    return bm.Robot(bus, {"j%d" % i: bm.Joint(i, **kw) for i in range(1, n + 1)})


def settle(w, bus, ms=200):
    for _ in range(ms):
        w.clock.advance_ms(1)
        while bus.poll() is not None:
            pass


def moves(w):
    """Each CMD_SERVO_MOVE the controller received: (time_ms, {id: position})."""
    out = []
    for f in w.frames():
        if f[3] == MOVE:
            out.append(
                (f[5] | f[6] << 8, {f[i]: f[i + 1] | f[i + 2] << 8 for i in range(7, len(f), 3)})
            )
    return out


def commands(w):
    return [f[3] for f in w.frames()]


def hand(w, positions):
    """Turn servos by hand: the simulated controller's servos go there at once (a frame
    written straight into it, not over the wire)."""
    frame = bytearray((0x55, 0x55, 3 * len(positions) + 5, MOVE, len(positions), 0, 0))
    for servo_id, position in positions.items():
        frame += bytes((servo_id, position & 0xFF, position >> 8))
    w.sim.write(frame)


def raises(call, *words):
    """The ValueError or TypeError call() raises: its message, which must hold words."""
    try:
        call()
    except (ValueError, TypeError) as e:
        text = str(e)
        for word in words:
            assert word in text, "%r not in %r" % (word, text)
        return text
    raise AssertionError("no error")


class Tidy(unittest.TestCase):
    def tearDown(self):
        busservo.time = bm.time = time
        bm._asyncio = None


class Calibration(Tidy):
    def test_a_bus_servo_is_0_to_1000_over_240_degrees_with_500_at_0(self):
        j = bm.Joint(1)
        self.assertEqual(
            [j.position(d) for d in (-120, -30, 0, 30, 120)], [0, 375, 500, 625, 1000]
        )
        self.assertEqual(j.limits, (-120, 120))
        self.assertAlmostEqual(j.degrees(625), 30)

    def test_pwm_servos_are_500_to_2500_us_over_180_or_270_degrees_with_1500_at_0(self):
        j = bm.Joint(1, kind=bm.PWM_180)
        self.assertEqual([j.position(d) for d in (-90, 0, 45, 90)], [500, 1500, 2000, 2500])
        j = bm.Joint(1, kind=bm.PWM_270)
        self.assertEqual([j.position(d) for d in (-135, 0, 27, 135)], [500, 1500, 1700, 2500])
        self.assertAlmostEqual(j.degrees(1700), 27)

    def test_direction_mirrors_and_trim_turns_the_servo_by_its_degrees(self):
        j = bm.Joint(2, direction=-1)
        self.assertEqual((j.position(30), j.position(-30)), (375, 625))
        j = bm.Joint(2, trim=3.6)  # 3.6 degrees = 15 positions
        self.assertEqual((j.position(0), j.position(30)), (515, 640))
        j = bm.Joint(2, direction=-1, trim=3.6)  # servo at -degrees + 3.6
        self.assertEqual((j.position(0), j.position(30)), (515, 390))
        self.assertEqual(j.limits, (-116.4, 123.6))  # what the servo can reach
        self.assertAlmostEqual(j.degrees(390), 30)

    def test_float_degrees_give_the_position_float_maths_gives(self):
        # Joint.position() scales a float's bits with ints (so as not to allocate): it
        # must agree with round() of the float maths, but for a value within a hair of .5.
        for kind in (bm.BUS, bm.PWM_180, bm.PWM_270):
            for direction in (1, -1):
                for trim in (0, 3.5, -7.25):
                    j = bm.Joint(3, kind=kind, direction=direction, trim=trim)
                    d = j.lo
                    while d <= j.hi:
                        exact = j.centre + (direction * d + trim) * j.per_degree
                        got = j.position(d)
                        if abs(exact - math.floor(exact) - 0.5) > 0.01:
                            self.assertEqual(got, math.floor(exact + 0.5), (kind, trim, d))
                        else:
                            self.assertTrue(abs(got - exact) <= 0.51, (kind, trim, d))
                        d += 0.37

    def test_a_streamed_float_goes_to_the_position_joint_position_gives(self):
        # stream() scales a float's bits inline, without Joint.position()'s call: the two
        # must agree, for every kind, direction and trim.
        class Bus:  # a wire always free, that keeps the positions of the last frame
            def wire_ms(self):
                return 0

            def move_many(self, pairs, ms):
                self.sent = [position for _, position in pairs]

        for kind in (bm.BUS, bm.PWM_180, bm.PWM_270):
            for direction in (1, -1):
                for trim in (0, 3.5, -7.25):
                    j = bm.Joint(3, kind=kind, direction=direction, trim=trim)
                    bus = Bus()
                    robot = bm.Robot(bus, {"j": j})
                    d = float(j.lo)
                    while d <= j.hi:
                        robot.stream({"j": d})
                        self.assertTrue(robot.step())
                        self.assertEqual(bus.sent, [j.position(d)], (kind, direction, trim, d))
                        d += 0.37

    def test_degrees_to_position_and_back_is_within_half_a_position(self):
        for kind in (bm.BUS, bm.PWM_180, bm.PWM_270):
            for direction in (1, -1):
                j = bm.Joint(3, kind=kind, direction=direction, trim=2.5)
                for d in (-40.3, -1, 0, 0.7, 12.25, 59.9):
                    back = j.degrees(j.position(d))
                    self.assertTrue(abs(back - d) <= 0.5 / j.per_degree + 1e-9, (kind, d, back))

    def test_a_target_beyond_the_limits_gives_the_limits_position(self):
        j = bm.Joint(6, kind=bm.PWM_180, limits=(0, 60))
        self.assertEqual((j.position(-10), j.position(75.5), j.position(1e30)), (1500, 2167, 2167))

    def test_a_target_just_past_a_limit_gives_the_limits_position(self):
        # Within a degree of it too: the limit is the end stop, not a degree past it.
        j = bm.Joint(6, kind=bm.PWM_180, limits=(0, 60))
        got = [j.position(d) for d in (-0.5, -1, 60.5, 61, 60.9)]
        self.assertEqual(got, [1500, 1500, 2167, 2167, 2167])

    def test_bad_joints_raise_saying_what_is_allowed_and_what_came(self):
        raises(lambda: bm.Joint(256), "servo_id", "0..255", "256")
        raises(lambda: bm.Joint("1"), "servo_id", "'1'")
        raises(lambda: bm.Joint(1, kind="SG90"), "kind", "BUS, PWM_180 or PWM_270", "SG90")
        raises(lambda: bm.Joint(1, direction=2), "direction", "1 or -1", "2")
        raises(lambda: bm.Joint(1, limits=(-130, 90)), "limits", "-120..120", "-130")
        raises(lambda: bm.Joint(1, kind=bm.PWM_180, limits=(0, 100)), "limits", "-90..90")
        raises(lambda: bm.Joint(1, trim=5, limits=(-120, 118)), "limits", "-125..115", "trim 5")
        raises(lambda: bm.Joint(1, limits=(30, -30)), "limits", "low <= high")
        raises(lambda: bm.Joint(1, limits=(0, float("nan"))), "limits", "finite", "nan")
        raises(lambda: bm.Joint(1, limits=5), "limits", "(low, high)")
        raises(lambda: bm.Joint(1, trim=float("inf")), "trim", "inf")
        raises(lambda: bm.Joint(1, dps=0), "dps", "more than 0")
        raises(lambda: bm.Robot(None, {"a": bm.Joint(1), "b": bm.Joint(1)}), "share servo_id 1")
        raises(lambda: bm.Robot(None, {"a": 1}), "Joint")

    def test_calibration_saves_and_loads_as_json(self):
        w, bus = world()
        path = scratch("motion") + ".json"
        try:
            arm(bus).save(path)
            again = bm.Robot.load(bus, path)
        finally:
            os.remove(path)
        self.assertEqual(again.names, ["base", "shoulder", "claw"])  # in servo_id order
        for name, joint in arm(bus).joints.items():
            self.assertEqual(again.joints[name].config(), joint.config())
        self.assertEqual(
            again.joints["shoulder"].position(-45), arm(bus).joints["shoulder"].position(-45)
        )

    def test_a_cap_given_to_load_holds_over_the_files_dps(self):
        # Robot.load(bus, path, dps): each joint at the least of the file's dps and the
        # cap (a calibration saves "dps": null: without the cap, as fast as asked);
        # least_dps() of a program's joints is the cap they ask for.
        w, bus = world()
        path = scratch("motion") + ".json"
        joints = arm(bus).joints
        joints["claw"] = bm.Joint(6, kind=bm.PWM_180, limits=(0, 60), dps=20)
        try:
            bm.Robot(bus, joints).save(path)
            for cap, want in ((None, None), (30, 30), (10, 10), (22.5, 22.5)):
                loaded = bm.Robot.load(bus, path, cap)
                self.assertEqual(loaded.joints["base"].dps, want, cap)
                self.assertEqual(loaded.joints["claw"].dps, min(20, cap or 20), cap)
                self.assertEqual(loaded.joints["claw"].limits, (0, 60))
            for bad, words in ((0, ("dps", "more than 0")), ("30", ("dps", "'30'"))):
                raises(lambda bad=bad: bm.Robot.load(bus, path, bad), *words)
        finally:
            os.remove(path)
        self.assertEqual(bm.least_dps(joints), 20)
        self.assertEqual(bm.least_dps({"a": bm.Joint(1, dps=40), "b": bm.Joint(2)}), 40)
        self.assertEqual(bm.least_dps({"a": bm.Joint(1)}), None)

    def test_save_writes_the_joints_and_keeps_what_else_the_file_holds(self):
        # An arm's links beside the joints (busservo_arm) are kept; more keys are added; a
        # file that is not a calibration is written afresh.
        w, bus = world()
        path = scratch("motion") + ".json"
        try:
            with open(path, "w") as f:
                f.write('{"joints": {"old": {"servo_id": 9}}, "links": {"hand": 60}}')
            arm(bus).save(path)
            with open(path) as f:
                saved = json.load(f)
            self.assertEqual(saved["links"], {"hand": 60})
            self.assertEqual(sorted(saved["joints"]), ["base", "claw", "shoulder"])
            arm(bus).save(path, links={"hand": 61})
            with open(path) as f:
                self.assertEqual(json.load(f)["links"], {"hand": 61})
            with open(path, "w") as f:
                f.write("[1, 2]")
            arm(bus).save(path)
            with open(path) as f:
                self.assertEqual(sorted(json.load(f)), ["joints"])
        finally:
            os.remove(path)

    def test_a_file_that_is_no_calibration_or_sequence_says_which_and_why(self):
        w, bus = world()
        path = scratch("motion") + ".json"
        try:
            for text, words in (
                ("{not json", ("not valid JSON",)),
                ('{"steps": []}', ("'joints'", "Robot.save()")),
                ('{"joints": [1, 2]}', ("joints must be {name: settings}",)),
                ('{"joints": {"base": {"id": 1}}}', ("joint 'base'",)),
            ):
                with open(path, "w") as f:
                    f.write(text)
                raises(lambda: bm.Robot.load(bus, path), path, *words)
            for text, words in (
                ("", ("not valid JSON",)),
                ('{"joints": {}}', ("'steps'", "Sequence.save()")),
                ('{"steps": [{"pose": {"base": 1}}]}', ("steps must be", "ms")),
                ('{"steps": 5}', ("steps must be",)),
            ):
                with open(path, "w") as f:
                    f.write(text)
                raises(lambda: bm.Sequence.load(path), path, *words)
        finally:
            os.remove(path)


class Moves(Tidy):
    def test_a_move_in_degrees_is_one_frame_for_all_its_joints(self):
        w, bus = world()
        a = arm(bus)
        self.assertEqual(a.move({"base": 30, "shoulder": -45, "claw": 45}, ms=500), 500)
        settle(w, bus, 50)
        self.assertEqual(moves(w), [(500, {1: 625, 2: 702, 6: 2000})])
        self.assertEqual(a.clamped, 0)

    def test_a_target_beyond_the_limits_is_clamped_and_counted(self):
        w, bus = world()
        a = arm(bus)
        a.move({"base": 30, "shoulder": -100, "claw": 90}, ms=200)
        settle(w, bus, 50)
        self.assertEqual(moves(w), [(200, {1: 625, 2: 890, 6: 2167})])
        self.assertEqual(a.clamped, 2)
        self.assertEqual(a.stream({"claw": -5}), 1)
        self.assertEqual(a.clamped, 3)

    def test_a_target_exactly_at_a_limit_is_not_counted_as_clamped(self):
        # The limits are reachable (changed to count them, nothing failed): ints and floats,
        # move() and stream(), each end; and the teleop, a leader at the follower's limit.
        w, bus = world()
        a = arm(bus)
        for pose in ({"shoulder": -90, "claw": 60}, {"shoulder": 90.0, "claw": 0.0}):
            a.move(pose, ms=200)
            self.assertEqual(a.stream(pose), 0, pose)
        self.assertEqual(a.clamped, 0)
        a.move({"shoulder": 90.5, "claw": -0.01}, ms=200)
        self.assertEqual(a.clamped, 2)

    def test_a_speed_limited_move_reads_the_positions_first_when_none_are_known(self):
        w, bus = world()
        a = arm(bus)
        hand(w, {1: 375})  # the base is at -30 degrees
        self.assertEqual(a.move({"base": 30}, dps=60), 1000)  # 60 degrees at 60 per s
        settle(w, bus, 50)
        self.assertEqual(commands(w), [CMD_MULT_SERVO_POS_READ, MOVE])
        self.assertEqual(moves(w), [(1000, {1: 625})])

    def test_a_speed_limited_move_times_the_joint_that_goes_furthest(self):
        w, bus = world()
        a = arm(bus)
        a.move({"base": 0, "shoulder": 0, "claw": 0}, ms=0)  # now they are known
        settle(w, bus, 50)
        took = a.move({"base": 12, "shoulder": -45, "claw": 30}, dps=90)
        # The shoulder goes furthest, from 515 to 702: 187 positions, 44.88 degrees.
        self.assertEqual(took, 499)
        settle(w, bus, 50)
        self.assertEqual(commands(w), [MOVE, MOVE])  # known: nothing read
        self.assertEqual(moves(w)[-1][0], 499)

    def test_a_joints_own_dps_lengthens_a_move_too_fast_for_it(self):
        w, bus = world()
        a = bm.Robot(bus, {"wrist": bm.Joint(4, dps=45), "base": bm.Joint(1)})
        a.move({"wrist": 0, "base": 0}, ms=0)
        self.assertEqual(a.move({"wrist": 90, "base": 10}, ms=300), 2000)
        self.assertEqual(a.slowed, 1)
        self.assertEqual(a.move({"base": 20}, ms=300), 300)  # the wrist is not in it
        self.assertEqual(a.slowed, 1)

    def test_where_reads_the_joints_in_degrees(self):
        w, bus = world()
        a = arm(bus)
        hand(w, {1: 624, 2: 702, 6: 2000})
        self.assertEqual(a.where(), {"base": 29.8, "shoulder": -45.0, "claw": 45.0})
        self.assertEqual(a.where(["claw"]), {"claw": 45.0})

    def test_where_from_positions_read_before_sends_nothing(self):
        # After the driver's ask() (a query that never blocks the loop), bus.positions holds
        # the answer: where() makes the angles of it and sends nothing. A joint whose servo
        # has no position there is refused by name.
        w, bus = world()
        a = arm(bus)
        hand(w, {1: 624, 2: 702, 6: 2000})
        for _ in bus.ask([1, 2, 6]):
            w.clock.advance_ms(1)
        sent = len(w.frames())
        self.assertEqual(
            a.where(positions=bus.positions), {"base": 29.8, "shoulder": -45.0, "claw": 45.0}
        )
        self.assertEqual(a.where(["claw"], {6: 2000}), {"claw": 45.0})
        try:
            a.where(positions={1: 624, 6: 2000})
            error = None
        except OSError as e:
            error = e
        self.assertIn("joint 'shoulder': servo 2 does not answer", str(error))
        self.assertEqual(len(w.frames()), sent)

    def test_a_servo_that_does_not_answer_is_refused_by_name(self):
        # It reads 65535 (None to the driver): no angle is made of it, and nothing moves.
        w, bus = world()
        a = arm(bus)
        w.sim.missing.add(2)
        for call in (a.where, a.capture, lambda: a.move({"shoulder": 10}, dps=30), a.home):
            try:
                call()
                error = None
            except OSError as e:
                error = e
            self.assertEqual(error.args[0], errno.ENODEV)
            self.assertIn("joint 'shoulder': servo 2 does not answer", str(error))
        settle(w, bus, 20)
        self.assertEqual(moves(w), [])
        self.assertEqual(a.where(["base"]), {"base": 0.0})  # the others still read

    def test_limp_then_capture_reads_the_pose_made_by_hand(self):
        w, bus = world()
        a = arm(bus)
        a.limp()
        settle(w, bus, 30)
        self.assertEqual(w.sim.limp, {1, 2, 6})
        hand(w, {1: 750, 2: 500, 6: 1500})
        self.assertEqual(a.capture(), {"base": 60.0, "shoulder": 3.5, "claw": 0.0})

    def test_bad_input_raises_naming_it_and_sends_nothing(self):
        w, bus = world()
        a = arm(bus)
        settle(w, bus, 10)
        for call, words in (
            (lambda: a.move({"elbow": 10}, ms=100), ("elbow", "base, shoulder, claw")),
            (lambda: a.move({"base": float("nan")}, ms=100), ("targets['base']", "nan")),
            (lambda: a.move({"base": float("inf")}, ms=100), ("targets['base']", "inf")),
            (lambda: a.move({"base": "30"}, ms=100), ("targets['base']", "number", "'30'")),
            (lambda: a.move({"base": True}, ms=100), ("targets['base']", "True")),
            (lambda: a.move({"base": 10}, ms=100, dps=30), ("ms or dps",)),
            (lambda: a.move({"base": 10}), ("ms or dps",)),
            (lambda: a.move({"base": 10}, ms=-1), ("ms", "0..65535", "-1")),
            (lambda: a.move({"base": 10}, ms=70000), ("ms", "0..65535", "70000")),
            (lambda: a.move({"base": 10}, ms=1.5), ("ms", "1.5")),
            (lambda: a.move({"base": 10}, dps=0), ("dps", "more than 0")),
            (lambda: a.move({"base": 10}, dps=-5), ("dps", "-5")),
            (lambda: a.move({}, ms=100), ("targets",)),
            (lambda: a.move([("base", 10)], ms=100), ("targets", "dict")),
            (lambda: a.move({"base": 120}, dps=0.001), ("more than 65535",)),
            (lambda: a.home({"base": 0}, dps=0), ("dps",)),
            (lambda: a.home({"nose": 0}), ("nose",)),
            (lambda: a.stream({"base": 5, "elbow": 1}), ("elbow",)),
            (lambda: a.stream({"base": float("nan")}), ("targets['base']", "nan")),
            (lambda: a.where(["elbow"]), ("elbow",)),
            (lambda: a.limp(["elbow"]), ("elbow",)),
        ):
            raises(call, *words)
        self.assertFalse(a.step())  # the bad stream() stored nothing
        settle(w, bus, 50)
        # One read, for the dps=0.001 move that had to know where the base is: it moved nothing.
        self.assertEqual(commands(w), [CMD_MULT_SERVO_POS_READ])


class Safety(Tidy):
    def test_estop_stops_the_group_and_lets_every_joint_go(self):
        w, bus = world()
        a = arm(bus)
        bus.run_group(1, 0)
        player = bm.Sequence([({"base": 10}, 100), ({"base": 20}, 100)]).play(a)
        player.step()
        a.stream({"base": 5})
        a.estop()
        settle(w, bus, 50)
        self.assertEqual(commands(w)[-2:], [CMD_ACTION_GROUP_STOP, CMD_MULT_SERVO_UNLOAD])
        self.assertEqual(w.frames()[-1][5:], bytes((1, 2, 6)))
        self.assertEqual(w.sim.limp, {1, 2, 6})
        self.assertEqual(w.sim.running, None)
        self.assertTrue(player.done)
        self.assertFalse(player.step())
        self.assertFalse(a.step())  # the stream's target is forgotten
        settle(w, bus, 50)
        self.assertEqual(len(moves(w)), 1)

    def test_home_reads_where_the_joints_are_then_goes_there_slowly(self):
        w, bus = world()
        a = arm(bus)
        a.move({"base": 0, "shoulder": 0, "claw": 0}, ms=0)  # known, but the hand moved them
        settle(w, bus, 50)
        hand(w, {1: 250, 2: 500, 6: 1500})  # base -60, shoulder 3.5, claw 0
        self.assertEqual(a.home(), 2000)  # the base: 60 degrees at 30 per s
        settle(w, bus, 50)
        self.assertEqual(commands(w), [MOVE, CMD_MULT_SERVO_POS_READ, MOVE])
        self.assertEqual(moves(w)[-1], (2000, {1: 500, 2: 515, 6: 1500}))
        settle(w, bus, 2000)
        self.assertEqual(a.home({"base": 30}, dps=60), 500)

    def test_a_limp_joint_is_not_moved_by_old_stream_targets(self):
        w, bus = world()
        a = arm(bus)
        a.stream({"base": 20, "shoulder": 10})
        self.assertTrue(a.step())
        settle(w, bus, 100)
        a.limp(["shoulder"])
        a.stream({"base": 25})
        self.assertTrue(a.step())
        settle(w, bus, 100)
        self.assertEqual(moves(w)[-1][1], {1: 604})
        self.assertEqual(w.sim.limp, {2})

    def test_estop_lets_every_joint_go_even_when_the_stop_cannot_be_sent(self):
        # The UART fails once (an unplugged adapter's EIO): the stop of the action group is
        # lost, and the joints must still be let go.
        for port in wire.PORTS:
            w, bus = world(port)
            a = arm(bus)
            a.move({"base": 10}, ms=0)
            w.uart.fail("write", OSError(5))
            with self.assertRaises(OSError):
                a.estop()
            settle(w, bus, 50)
            self.assertEqual((commands(w)[-1], w.sim.limp), (CMD_MULT_SERVO_UNLOAD, {1, 2, 6}))

    def test_a_move_after_limp_is_timed_from_where_the_hand_left_the_joint(self):
        w, bus = world()
        a = arm(bus)
        a.move({"base": 0}, ms=0)  # known: at 0
        settle(w, bus, 50)
        a.limp(["base"])
        hand(w, {1: 250})  # -60 degrees
        self.assertEqual(a.move({"base": 0}, dps=30), 2000)  # read first: 60 degrees away
        settle(w, bus, 50)
        self.assertEqual(commands(w)[-2:], [CMD_MULT_SERVO_POS_READ, MOVE])
        self.assertEqual(moves(w)[-1], (2000, {1: 500}))

    def test_hold_drops_the_targets_not_yet_sent_and_sends_nothing(self):
        w, bus = world()
        a = arm(bus)
        a.stream({"base": 20})
        self.assertTrue(a.step())
        settle(w, bus, 100)
        a.stream({"base": 40})  # not yet sent: a dead-man's hold() drops it
        a.hold()
        self.assertFalse(a.step())
        settle(w, bus, 100)
        self.assertEqual([m[1] for m in moves(w)], [{1: 583}])
        a.stream({"shoulder": 0})  # afresh: only what comes after
        self.assertTrue(a.step())
        settle(w, bus, 100)
        self.assertEqual(moves(w)[-1][1], {2: 515})


class Stream(Tidy):
    def run_loop(self, w, bus, robot, seconds, tick_ms=10):
        """A 100 Hz control loop: new targets (sine waves) every tick, then step() and
        poll(). Returns (the last targets' positions, the longest step() in us)."""
        targets = {name: 0 for name in robot.names}
        longest = 0
        for tick in range(seconds * 1000 // tick_ms):
            start = w.clock.now_us
            for k, name in enumerate(robot.names):
                targets[name] = 60 * math.sin(tick * tick_ms / 500 + k)
            robot.stream(targets)
            before = w.clock.now_us
            robot.step()
            longest = max(longest, w.clock.now_us - before)
            while bus.poll() is not None:
                pass
            w.clock.now_us = start + tick_ms * 1000
        self.arrived = len(moves(w))
        last = {robot.joints[n].servo_id: robot.joints[n].position(targets[n]) for n in targets}
        return last, longest

    def test_the_stream_reaches_the_controller_at_the_wires_limit_on_every_port(self):
        for port in wire.PORTS:
            for n in (6, 18):
                w, bus = world(port)
                robot = chain(bus, n)
                last, longest = self.run_loop(w, bus, robot, 3)
                for _ in range(20):  # the loop goes on with no new target: the last one goes
                    robot.step()
                    settle(w, bus, 10)
                got = moves(w)
                limit = 960 / (3 * n + 7)  # frames a second at 9600 baud
                rate = self.arrived / 3  # frames the controller had at the loop's end
                print("\n    %s, %d servos: %.1f updates/s of %.1f" % (port, n, rate, limit))
                self.assertTrue(rate >= 0.95 * limit, (port, n, rate))
                self.assertEqual((w.garbled, w.sim.beeps), (0, 0), port)
                self.assertEqual(got[-1][1], last, (port, n))  # the last target arrived
                self.assertEqual(robot.updates, len(got))
                self.assertTrue(longest <= 1000, (port, n, longest))  # never waits on the UART
                # Each frame's time is its time on the wire, rounded up: the servos glide
                # from one update to the next.
                wire_ms = (3 * n + 7) * 10000 / 9600
                self.assertEqual(robot.frame_ms, math.ceil(wire_ms))
                self.assertTrue(all(t == robot.frame_ms for t, _ in got[3:]), got)

    def test_only_the_latest_targets_are_sent_never_stale_ones_behind_them(self):
        w, bus = world()
        robot = chain(bus, 2)
        for x in range(100):
            robot.stream({"j1": x, "j2": -x})
        self.assertTrue(robot.step())
        for x in range(100, 200, 10):
            robot.stream({"j1": x / 10})
            self.assertFalse(robot.step())  # the wire is busy: nothing queued
        settle(w, bus, 30)
        self.assertTrue(robot.step())
        self.assertFalse(robot.step())  # nothing new
        settle(w, bus, 30)
        self.assertEqual([m[1] for m in moves(w)], [{1: 913, 2: 88}, {1: 579, 2: 88}])

    def test_a_slow_stream_sets_the_move_time_to_its_pace(self):
        w, bus = world()
        robot = chain(bus, 1)
        for x in range(10):  # a new target every 50 ms: each frame glides for 50 ms
            robot.stream({"j1": x})
            robot.step()
            settle(w, bus, 50)
        self.assertTrue(all(m[0] in (50, 51) for m in moves(w)[1:]), moves(w))

    def test_the_stream_moves_no_joint_faster_than_its_dps(self):
        w, bus = world()
        robot = bm.Robot(bus, {"j1": bm.Joint(1, dps=60)})
        raises(lambda: robot.stream({"j1": 90}), "j1", "home() or where() first")
        robot.where()  # at 0 degrees
        for _ in range(200):
            robot.stream({"j1": 90})
            robot.step()
            settle(w, bus, 10)
        got = moves(w)
        for (_, before), (ms, after) in zip(got, got[1:]):
            step = abs(after[1] - before[1]) / 1000 * 240  # degrees
            self.assertTrue(step <= 60 * ms / 1000 + 0.25, (step, ms))
        self.assertEqual(got[-1][1], {1: 875})  # and it got there, after 1.5 s
        self.assertTrue(robot.slowed > 0)

    def test_a_joints_dps_holds_however_fast_step_runs_and_at_whatever_pace_targets_come(self):
        # A slider dragged at 20 or 50 updates a second, step() called every ms: frames go
        # whenever the wire is free. Once, each carried a step worth the stream's pace, so a
        # joint of 30 degrees/s ran at 58 (at 20 ms) or more: its own servo, sampled every ms,
        # must turn no faster than 30 degrees/s (125 positions/s) over any 200 ms, however the
        # targets come: 25 positions, and 2 for the rounding to whole positions at each end.
        for pace in (10, 20, 50, 100):
            w, bus = world()
            robot = bm.Robot(bus, {"j1": bm.Joint(1, dps=30)})
            robot.where()
            seen = []
            for ms in range(1500):
                if ms % pace == 0:
                    robot.stream({"j1": 100})
                robot.step()
                settle(w, bus, 1)
                seen.append(w.sim.position(1))
            fastest = max(abs(seen[t + 200] - seen[t]) for t in range(len(seen) - 200))
            self.assertTrue(fastest <= 25 + 2, (pace, fastest))
            self.assertTrue(seen[-1] - seen[0] > 150, (pace, seen[-1]))  # and it went on

    def test_a_target_beyond_a_joints_dps_is_reached_in_steps_down_and_up(self):
        # stream() once; step() goes on until the joint is there, no faster than its dps
        # (60 degrees/s: 250 positions/s, less the rounding down), whichever way it goes.
        w, bus = world()
        robot = bm.Robot(bus, {"j1": bm.Joint(1, dps=60)})
        robot.where()  # at 0 degrees
        for target, position in ((-90, 125), (30, 625)):
            robot.stream({"j1": target})
            for _ in range(400):  # 4 s: 500 positions take 2 to 2.5 s
                robot.step()
                settle(w, bus, 10)
            got = [(0, {1: 500})] + moves(w)  # from where it was read
            for (_, before), (ms, after) in zip(got, got[1:]):
                step = abs(after[1] - before[1])
                self.assertTrue(step <= 250 * ms // 1000 + 1, (target, step, ms))
            self.assertEqual(got[-1][1], {1: position}, target)
            self.assertEqual(w.sim.position(1), position, target)

    def slowed(self, dps, loop_ms, pace, phases):
        """A joint of dps at 0 degrees (read), then phases of (ms, target): step() every
        loop_ms, target streamed every pace ms (None: nothing). The servo's position each
        ms, the ms each phase starts at, and the ms the wire was idle."""
        w, bus = world()
        robot = bm.Robot(bus, {"j1": bm.Joint(1, dps=dps)})
        robot.where()
        seen, starts, idle = [], [], 0
        for ms, target in phases:
            starts.append(len(seen))
            for t in range(ms):
                if target is not None and t % pace == 0:
                    robot.stream({"j1": target})
                if len(seen) % loop_ms == 0:
                    robot.step()
                idle += bus.wire_ms() == 0
                settle(w, bus, 1)
                seen.append(w.sim.position(1))
        return seen, starts, idle

    def test_a_joints_dps_holds_through_its_arrival(self):
        # A joint of 60 degrees/s (25 positions in 100 ms) streamed to 90 (or -90): the
        # step that reaches the target glides at the dps, and the next frame (the same
        # target again) must not cut that glide short. Found by the mutation pass: 35
        # positions in 100 ms at the end of the way.
        for loop_ms, pace in ((10, 10), (10, 50)):
            for target in (90, -90):
                seen, _, _ = self.slowed(60, loop_ms, pace, [(2500, target)])
                fastest = max(abs(seen[t + 100] - seen[t]) for t in range(len(seen) - 100))
                self.assertTrue(fastest <= 25 + 2, (loop_ms, pace, target, fastest))

    def test_a_slowed_joint_turns_back_within_two_frames_when_its_target_does(self):
        # A slider dragged to 90 degrees (or -90), then back, a joint of 60 degrees/s
        # following it (a 100 Hz loop, a target every 20 ms): the servo turns back within
        # 60 ms of the new target, 15 positions (3.6 degrees) past where it was, from
        # mid-way, after the loop ran a second with nothing streamed, or after a second held
        # at its target. A step that took the whole pause's way, or what was owed while it
        # waited, or the whole way down, would commit it to a glide of a second and more,
        # deaf to the slider meanwhile.
        for way in (1, -1):
            for name, before in (
                ("mid-way", []),
                ("paused", [(1000, None)]),
                ("held", [(1000, 0)]),
            ):
                phases = before + [(400, 90 * way), (300, -90 * way)]
                seen, starts, _ = self.slowed(60, 10, 20, phases)
                turn = starts[-1]
                peak = max(range(turn, len(seen)), key=lambda t: way * seen[t])
                why = (way, name, peak - turn, seen[turn], seen[peak])
                self.assertTrue(peak - turn <= 60 and way * (seen[peak] - seen[turn]) <= 15, why)
                went = way * (seen[turn] - seen[starts[-2]])
                self.assertTrue(went >= 80, why)  # it went, 100 at most

    def test_a_joints_dps_holds_sampled_every_ms_whatever_the_loops_period(self):
        # As above, with step() every 10 or 20 ms, and targets every 10 to 100 ms, up and
        # down: over any 100 ms on its way, the servo turns no more than its dps allows (250
        # positions/s at 60 degrees/s: 25), and 2 for the rounding to whole positions at each
        # end. A frame that went before the servo was there would send it the rest of its
        # glide and the next step in one frame's time: faster than its dps.
        for loop_ms, pace in ((10, 10), (10, 50), (20, 20), (20, 100)):
            for target in (120, -120):  # 2 s to get there
                seen, _, _ = self.slowed(60, loop_ms, pace, [(1200, target)])
                fastest = max(abs(seen[t + 100] - seen[t]) for t in range(len(seen) - 100))
                self.assertTrue(fastest <= 25 + 2, (loop_ms, pace, target, fastest))

    def test_a_slowed_joint_goes_at_its_dps_not_slower(self):
        # 60 degrees/s with a 100 Hz loop and a target every tick, 30 with a 50 Hz loop: over
        # any 500 ms of its way the servo goes 90 % of what its dps allows (125 and 62
        # positions), at least. A step() that let the loop's period go unpaid each frame
        # would run it at four fifths of its dps, or three fifths.
        for dps, loop_ms, most in ((60, 10, 125), (30, 20, 62)):
            seen, _, _ = self.slowed(dps, loop_ms, loop_ms, [(1200, 120)])
            slowest = min(seen[t + 500] - seen[t] for t in range(100, len(seen) - 500))
            self.assertTrue(slowest >= 0.9 * most, (dps, loop_ms, slowest))

    def test_a_long_slow_way_keeps_its_glides_short_enough_to_hear_a_new_target(self):
        # 10 degrees/s for 10 s, a 100 Hz loop, a target every 50 ms: each frame's glide
        # grows by the loop's lateness, but no further than 10 loop periods (100 ms) and the
        # whole position it rounds to (24 ms at this dps), so a slider turned back is heard
        # within them. Found by the mutation pass: 220 ms.
        w, bus = world()
        robot = bm.Robot(bus, {"j1": bm.Joint(1, dps=10)})
        robot.where()
        for t in range(10000):
            if t % 50 == 0:
                robot.stream({"j1": 110})
            if t % 10 == 0:
                robot.step()
            settle(w, bus, 1)
        glides = [ms for ms, _ in moves(w)]
        self.assertTrue(len(glides) > 50 and max(glides) <= 125, (len(glides), max(glides)))

    def test_a_slowed_joint_leaves_the_wire_free_between_its_frames(self):
        # 30 degrees/s, a target every 50 ms, step() every ms: a frame goes once the servo is
        # where the last one sent it, about one a glide, and the wire is idle most of the time,
        # for queries and the panel's reads. Frames at every free moment would fill it.
        seen, _, idle = self.slowed(30, 1, 50, [(1000, 120)])
        self.assertTrue(idle >= 700, idle)
        self.assertTrue(seen[-1] - seen[0] >= 110, seen[-1])  # and it went on

    def test_a_move_ends_the_stream_and_its_old_targets_never_follow(self):
        w, bus = world()
        a = arm(bus)
        a.stream({"base": 20})
        a.step()
        settle(w, bus, 50)
        a.stream({"base": 25})  # not sent yet
        a.move({"base": -30}, ms=100)
        settle(w, bus, 50)
        self.assertFalse(a.step())
        settle(w, bus, 200)
        self.assertEqual(moves(w)[-1], (100, {1: 375}))
        self.assertEqual(w.sim.position(1), 375)

    def test_stream_and_step_allocate_nothing(self):
        # The world's UART models allocate (they are Python): here the driver writes to the
        # fake UART of tests/test_alloc.py, which does not, on a clock the test steps.
        clock = wire.Clock()
        busservo.time = bm.time = clock
        uart = FakeUART()
        robot = chain(busservo.BusServo(uart), 6)
        floats = {name: 12.5 for name in robot.names}
        ints = {name: -7 for name in robot.names}
        robot.stream(floats)
        self.assertEqual(heap_per_call(lambda: robot.stream(floats)), 0)
        self.assertEqual(heap_per_call(lambda: robot.stream(ints)), 0)
        sent = robot.updates

        def send():  # outside the measurement: the wire is free again, with a new target
            clock.advance_ms(40)
            uart.clear()
            robot.stream(floats)

        self.assertEqual(heap_per_call(robot.step, send), 0)
        self.assertEqual(robot.updates, sent + 21)  # each step() sent a frame
        self.assertEqual(heap_per_call(robot.step), 0)  # and with nothing to send
        self.assertEqual(robot.updates, sent + 21)


class Sequences(Tidy):
    POSES = [({"base": 30, "claw": 10}, 800), ({"base": -30.5}, 500), ({"claw": 60}, 300)]

    def test_a_sequence_saves_and_loads_as_json(self):
        seq = bm.Sequence(self.POSES)
        path = scratch("sequence") + ".json"
        try:
            seq.save(path)
            again = bm.Sequence.load(path)
        finally:
            os.remove(path)
        self.assertEqual(again.steps, seq.steps)
        self.assertEqual(len(again), 3)

    def test_bad_sequences_raise_before_anything_is_sent(self):
        w, bus = world()
        a = arm(bus)
        raises(lambda: bm.Sequence([({"base": 1}, -5)]), "ms", "-5")
        raises(lambda: bm.Sequence([({"base": "x"}, 5)]), "pose['base']")
        raises(lambda: bm.Sequence([{"base": 1}]), "(pose, ms)")
        raises(lambda: bm.Sequence([({"base": 1}, 5), ({"nose": 1}, 5)]).play(a), "nose")
        raises(lambda: bm.Sequence(self.POSES).play(a, speed=0), "speed")
        raises(lambda: bm.Sequence([({"base": 1}, 60000)]).play(a, speed=0.5), "ms / speed")
        settle(w, bus, 10)
        self.assertEqual(w.frames(), [])

    def play(self, w, bus, player, ms):
        """player.step() every ms for ms: when (ms from the start) each pose was sent, and
        when it was done."""
        sent = []
        done = None
        start = w.clock.now_us
        for _ in range(ms):
            t = (w.clock.now_us - start) // 1000
            if player.step():
                sent.append(t)
            if player.done and done is None:
                done = t
            settle(w, bus, 1)
        return sent, done

    def test_playback_sends_each_pose_when_the_one_before_is_reached(self):
        w, bus = world()
        a = arm(bus)
        player = bm.Sequence(self.POSES).play(a)
        sent, done = self.play(w, bus, player, 2000)
        self.assertEqual(sent, [0, 800, 1300])
        self.assertEqual(done, 1600)
        self.assertEqual(moves(w), [(800, {1: 625, 6: 1611}), (500, {1: 373}), (300, {6: 2167})])

    def test_playback_at_double_speed_halves_the_times_and_loops_until_stopped(self):
        w, bus = world()
        a = arm(bus)
        player = bm.Sequence(self.POSES).play(a, speed=2.0, loop=True)
        sent, done = self.play(w, bus, player, 2000)
        self.assertEqual(sent[:5], [0, 400, 650, 800, 1200])
        self.assertEqual((done, player.loops), (None, 2))
        player.stop()
        self.assertFalse(player.step())
        self.assertEqual([m[0] for m in moves(w)][:3], [400, 250, 150])

    def test_a_pose_a_joints_dps_slows_is_waited_for_its_real_time_not_its_ms(self):
        # The base at 60 degrees/s needs 1000 ms to turn from 0 to 60 degrees, though the
        # pose asks for 100: the move takes 1000 ms (Robot.move() says so), and the next pose
        # goes when the base is there, not 100 ms in while it is still turning.
        w, bus = world()
        a = bm.Robot(bus, {"base": bm.Joint(1, dps=60), "claw": bm.Joint(6, kind=bm.PWM_180)})
        player = bm.Sequence([({"base": 60}, 100), ({"claw": 30}, 100)]).play(a)
        sent, done = self.play(w, bus, player, 1500)
        self.assertEqual(len(sent), 2, sent)
        self.assertTrue(1000 <= sent[1] - sent[0] <= 1005, sent)
        self.assertTrue(100 <= done - sent[1] <= 105, (sent, done))
        self.assertEqual([m[0] for m in moves(w)], [1000, 100])
        self.assertEqual(a.slowed, 1)

    def test_a_new_player_stops_the_one_playing(self):
        w, bus = world()
        a = arm(bus)
        first = bm.Sequence(self.POSES).play(a)
        self.assertTrue(first.step())
        second = bm.Sequence([({"base": 0}, 100)]).play(a)
        self.assertTrue(first.done)
        self.assertIs(a.player, second)
        settle(w, bus, 900)  # the first's next pose is due
        self.assertFalse(first.step())
        self.assertTrue(second.step())
        settle(w, bus, 200)
        self.assertEqual(moves(w)[-1], (100, {1: 500}))

    def test_await_player_plays_to_the_end_under_asyncio(self):
        class SimAsyncio:  # sleeping moves the world's clock, then the other tasks run
            def __init__(self, w):
                self.w = w

            async def sleep_ms(self, ms):
                settle(self.w, bus, ms)
                await asyncio.sleep_ms(0)

        w, bus = world()
        a = arm(bus)
        bm._asyncio = SimAsyncio(w)
        ticks = []

        async def control_loop():
            while True:
                ticks.append(w.clock.now_us)
                await bm._asyncio.sleep_ms(10)

        async def main():
            asyncio.create_task(control_loop())
            start = w.clock.now_us
            await bm.Sequence(self.POSES).play(a)
            first = w.clock.now_us - start
            await bm.Sequence(self.POSES).play(a, speed=2).run()
            return first, w.clock.now_us - start

        first, both = asyncio.run(main())
        self.assertTrue(1600000 <= first <= 1610000, first)  # 800 + 500 + 300 ms
        self.assertTrue(2400000 <= both <= 2420000, both)  # and again at twice the speed
        self.assertEqual(len(moves(w)), 6)
        self.assertTrue(len(ticks) > 50)  # the other task ran meanwhile


if __name__ == "__main__":
    unittest.main()
