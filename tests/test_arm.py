# busservo_arm: the arm's conventions, the round trip from millimetres to positions and back,
# refusals (nothing sent), the calibration file, and lines streamed at the wire's pace, on the
# wire-faithful world of tests/wire.py. The driver, the motion layer and the arm all run on the
# world's clock: busservo.time = busservo_motion.time = busservo_arm.time = w.clock.
import asyncio
import json
import math
import os
import time
import unittest

import busservo
import busservo_arm as ba
import busservo_motion as bm
import wire
from busservo import CMD_MULT_SERVO_POS_READ, CMD_MULT_SERVO_UNLOAD
from busservo import CMD_SERVO_MOVE as MOVE
from fakeuart import FakeUART
from shell import scratch, sh
from test_alloc import heap_per_call
from test_docs import PYTHON, block, run
from test_motion import commands, hand, moves, raises, settle

# A typical desktop arm (LOBOT/xArm-like), in mm: table to shoulder, shoulder to elbow, elbow
# to wrist, wrist to the tool point.
LINKS = {"base_height": 70, "upper_arm": 105, "forearm": 98, "hand": 150}
REACH = 105 + 98  # the wrist's furthest from the shoulder's axis: the elbow straight


def links_of(text):
    """The first links dict {"base_height": ...} written in text, in floats."""
    at = text.index('{"base_height"')
    return {k: float(v) for k, v in json.loads(text[at : text.index("}", at) + 1]).items()}


def world(port="rp2"):
    """(world, bus), with the driver, the motion layer and the arm on the world's clock."""
    w = wire.World(port)
    busservo.time = bm.time = ba.time = w.clock
    return w, busservo.BusServo(w.uart)


def robot(bus, more=False):
    """The arm's joints: a shoulder mounted the other way round and trimmed, limits as a real
    arm's; with more, a roll and a gripper too."""
    joints = {
        "base": bm.Joint(1),
        "shoulder": bm.Joint(2, direction=-1, trim=3.5, limits=(-90, 90)),
        "elbow": bm.Joint(3, limits=(-30, 120)),
        "wrist": bm.Joint(4, limits=(-120, 120)),
    }
    if more:
        joints["roll"] = bm.Joint(5)
        joints["gripper"] = bm.Joint(6, limits=(0, 60))
    return bm.Robot(bus, joints)


def arm(bus, more=False, **kw):
    return ba.Arm(robot(bus, more), LINKS, **kw)


def near(a, b, mm=1e-6):
    return all(abs(p - q) <= mm for p, q in zip(a, b))


def sent_point(a, frame_positions):
    """(x, y, z, pitch) of the tool point at the positions a frame carried, {id: position}."""
    pose = {}
    for name in ba.JOINTS:
        joint = a.robot.joints[name]
        pose[name] = joint.degrees(frame_positions[joint.servo_id])
    return a.point(pose)


def off_line(p, start, end):
    """The distance in mm of point p from the segment start..end."""
    d = [e - s for s, e in zip(start, end)]
    q = [a - s for s, a in zip(start, p)]
    dd = sum(c * c for c in d)
    u = max(0.0, min(1.0, sum(a * b for a, b in zip(q, d)) / dd)) if dd else 0.0
    return math.sqrt(sum((a - u * b) ** 2 for a, b in zip(q, d)))


class Tidy(unittest.TestCase):
    def tearDown(self):
        busservo.time = bm.time = ba.time = time
        bm._asyncio = None


class Geometry(Tidy):
    def test_the_conventions_are_the_pictures(self):
        # docs/arm.svg: x forward at base 0, y to the left, z up from the table at the base's
        # axis; shoulder 0 upright; shoulder, elbow and wrist positive tilt forward and down.
        a = arm(None)
        for pose, point in (
            ((0, 0, 0, 0), (0, 0, 423, 90)),  # all upright: the hand points up
            ((0, 90, 0, 0), (353, 0, 70, 0)),  # straight out forward, level with the shoulder
            ((90, 90, 0, 0), (0, 353, 70, 0)),  # base +90: counter-clockwise, to the left
            ((-90, 90, 0, 0), (0, -353, 70, 0)),
            ((0, 0, 90, 90), (98, 0, 25, -90)),  # forearm out, hand straight down
            ((0, 45, 45, 0), (105 * 0.5**0.5 + 248, 0, 70 + 105 * 0.5**0.5, 0)),
        ):
            got = a.point(dict(zip(ba.JOINTS, pose)))
            self.assertTrue(near(got, point, 1e-3), (pose, got))

    def test_pose_then_point_is_the_point_asked_for(self):
        a = arm(None)
        for target in (
            (150, 0, 40, -90),
            (100, -100, 0, -90),
            (250, 50, 100, -30),
            (0, 120, 200, 0),
        ):
            pose = a.pose(*target)
            self.assertTrue(near(a.point(pose), target, 1e-6), (target, pose))

    def test_elbow_up_is_the_default_and_elbow_down_reaches_the_same_point(self):
        up = arm(None)
        joints = {name: bm.Joint(i + 1) for i, name in enumerate(ba.JOINTS)}  # no limits
        down = ba.Arm(bm.Robot(None, joints), LINKS, elbow_up=False)
        for target in ((250, 50, 100, -30), (250, 0, 120, 0)):
            a, b = up.pose(*target), down.pose(*target)
            self.assertTrue(a["elbow"] > 0 > b["elbow"], (a, b))
            self.assertTrue(near(down.point(b), target, 1e-6))

    def test_reach_gives_the_nearest_point_the_wrist_reaches(self):
        a = arm(None)
        inside = (150.0, 20.0, 80.0, -30.0)
        self.assertEqual(a.reach(*inside), inside[:3])  # in reach: the point itself
        for x, y, z, pitch in ((300.0, 0.0, 300.0, 0.0), (0.0, 5.0, 423.0, 90.0)):
            got = a.reach(x, y, z, pitch)
            pose = a.pose(got[0], got[1], got[2], pitch)  # reachable now
            self.assertTrue(near(a.point(pose)[:3], got, 1e-6))
            self.assertTrue(
                abs(pose["elbow"]) < 2, pose
            )  # at the edge: the elbow (nearly) straight
            # and on the line from the shoulder's axis through the point's wrist
            self.assertTrue(math.atan2(got[1], got[0]) == math.atan2(y, x))

    def test_no_pitch_is_the_reachable_pitch_nearest_straight_down(self):
        a = arm(None)
        self.assertTrue(near(a.point(a.pose(150, 0, 40)), (150, 0, 40, -90), 1e-6))
        # Further out the hand cannot point down: the pitch the limits allow nearest -90, to
        # 1/32 degree; a tenth of a degree nearer is refused, a tenth further is not.
        for target in ((300, 0, 70), (200, 50, 100), (250, -120, 0)):
            pitch = a.point(a.pose(*target))[3]
            self.assertTrue(-90 < pitch < 0, (target, pitch))
            raises(lambda t=target, p=pitch: a.pose(*t, pitch=p - 0.1), "out of reach")
            a.pose(*target, pitch=pitch + 0.1)

    def test_where_a_joints_limit_is_in_the_way_the_pitch_is_at_its_edge(self):
        # Near the base, the wrist's limit (120 degrees) keeps the hand from pointing down,
        # not the reach: the pitch is the limit's edge, to 1/32 degree. 1/16 nearer -90 is
        # refused, naming the wrist.
        a = arm(None)
        for target in ((0, 50, 100), (0, -120, 125), (0, 0, 175)):
            pitch = a.point(a.pose(*target))[3]
            self.assertTrue(-90 < pitch < 0, (target, pitch))
            a.pose(*target, pitch=pitch)
            raises(lambda t=target, p=pitch: a.pose(*t, pitch=p - 1 / 16), "the wrist would be")

    def test_a_point_on_the_base_axis_keeps_the_base_where_it_is(self):
        w, bus = world()
        a = arm(bus)
        a.move_to(100, 100, 0, ms=0)
        self.assertEqual(a.pose(0, 0, 250)["base"], 45)


class RoundTrip(Tidy):
    def test_the_grid_round_trips_through_the_positions_sent_within_2_mm(self):
        # Every target of a grid over the space around the arm that pose() takes: move_to(),
        # then the positions in the frame the controller received, back to millimetres. The
        # positions' resolution is the limit: 0.24 degree a position, 0.12 at most by rounding,
        # 0.74 mm at 353 mm for each joint.
        w, bus = world()
        a = arm(bus)
        reached = worst = 0
        for x in range(-100, 351, 50):
            for y in range(-300, 301, 75):
                for z in range(-50, 351, 50):
                    for pitch in (None, -45, 0):
                        try:
                            a.pose(x, y, z, pitch)
                        except ValueError:
                            continue
                        first = w.frames_total
                        a.move_to(x, y, z, pitch, ms=0)
                        w.run_ms(21)  # a 4-servo frame's 19 bytes
                        [frame] = w.frames(first)
                        got = sent_point(a, frame_positions(frame))
                        off = math.sqrt(sum((g - t) ** 2 for g, t in zip(got, (x, y, z))))
                        worst = max(worst, off)
                        self.assertTrue(off <= 2, (x, y, z, pitch, got))
                        if pitch is not None:
                            self.assertTrue(abs(ba._wrap(got[3] - pitch)) <= 0.5, (pitch, got))
                        reached += 1
        self.assertTrue(reached >= 800, reached)
        print("\n    %d targets: within %.2f mm" % (reached, worst))
        self.assertEqual((w.garbled, w.sim.beeps), (0, 0))


def frame_positions(frame):
    return {frame[i]: frame[i + 1] | frame[i + 2] << 8 for i in range(7, len(frame), 3)}


class Refusals(Tidy):
    def test_a_point_out_of_reach_or_past_a_limit_names_it_the_reach_and_the_joint(self):
        w, bus = world()
        a = arm(bus)
        settle(w, bus, 10)
        for call, words in (
            (
                lambda: a.move_to(500, 0, 40, ms=500),
                (
                    "(x, y, z) = (500.0, 0.0, 40.0) mm: no pitch reaches it",
                    "out of reach",
                    "the elbow straight reaches 203.0 mm",
                ),
            ),
            (
                lambda: a.move_to(10, 0, 400, -90, ms=500),
                ("(10.0, 0.0, 400.0) mm, pitch -90.0", "480.1 mm from the shoulder's axis"),
            ),
            (
                lambda: a.move_to(5, 0, -80, -90, ms=500),  # the wrist on the shoulder's axis
                ("(5.0, 0.0, -80.0)", "the elbow folded reaches no closer than 7.0 mm"),
            ),
            (
                lambda: a.move_to(150, 0, 40, 60, ms=500),
                ("pitch 60.0", "the shoulder would be at 126.4 degrees", "limits -90.0..90.0"),
            ),
            (
                lambda: a.move_to(-100, 10, 50, ms=500),
                ("(-100.0, 10.0, 50.0) mm", "the base would be at 174.3 degrees", "-120.0..120.0"),
            ),
            (
                lambda: arm(bus, elbow_up=False).move_to(150, 0, 40, -90, ms=500),
                ("the elbow would be at -37.8 degrees", "limits -30.0..120.0"),
            ),
            (
                lambda: a.line_to(500, 0, 40),
                ("(500.0, 0.0, 40.0)", "out of reach", "reaches 203.0 mm"),
            ),
        ):
            raises(call, *words)
        settle(w, bus, 50)
        self.assertEqual(w.frames(), [])

    def test_bad_input_raises_naming_it_and_sends_nothing(self):
        w, bus = world()
        a = arm(bus)
        settle(w, bus, 10)
        for call, words in (
            (lambda: a.move_to(float("nan"), 0, 40, ms=100), ("x", "nan")),
            (lambda: a.move_to(100, "0", 40, ms=100), ("y", "number", "'0'")),
            (lambda: a.move_to(100, 0, float("inf"), ms=100), ("z", "inf")),
            (lambda: a.move_to(100, 0, 40, "down", ms=100), ("pitch", "'down'")),
            (lambda: a.move_to(100, 0, 40), ("ms or mm_s",)),
            (lambda: a.move_to(100, 0, 40, ms=100, mm_s=50), ("ms or mm_s",)),
            (lambda: a.move_to(100, 0, 40, ms=-1), ("ms", "0..65535", "-1")),
            (lambda: a.move_to(100, 0, 40, ms=1.5), ("ms", "1.5")),
            (lambda: a.move_to(100, 0, 40, mm_s=0), ("mm_s", "more than 0")),
            (lambda: a.move_to(100, 0, 40, mm_s=0.001), ("more than 65535",)),
            (lambda: a.line_to(100, 0, 40, mm_s=-5), ("mm_s", "-5")),
            (lambda: a.point({"base": 0}), ("shoulder",)),
            (lambda: ba.Arm(bm.Robot(bus, {"base": bm.Joint(1)}), LINKS), ("shoulder, elbow",)),
            (lambda: ba.Arm(bus, LINKS), ("busservo_motion.Robot",)),
            (lambda: ba.Arm(robot(bus), {"hand": 150}), ("'base_height' is missing",)),
            (lambda: ba.Arm(robot(bus), dict(LINKS, claw=20)), ("no link 'claw'",)),
            (lambda: ba.Arm(robot(bus), dict(LINKS, forearm=-98)), ("forearm", "-98")),
            (lambda: ba.Arm(robot(bus), dict(LINKS, upper_arm=0)), ("upper_arm", "more than 0")),
            (lambda: ba.Arm(robot(bus), dict(LINKS, forearm=0)), ("forearm", "more than 0")),
            (lambda: ba.Arm(robot(bus), dict(LINKS, hand=10001)), ("hand", "0..10000")),
        ):
            raises(call, *words)
        settle(w, bus, 50)
        # One read, for the move at mm_s=0.001 that had to know where the arm is: no move.
        self.assertEqual(commands(w), [CMD_MULT_SERVO_POS_READ])

    def test_after_a_refusal_or_an_interrupt_the_next_move_and_step_go(self):
        # move_to() and a line's step() work in a generator made once (busservo_arm): what
        # one call raised, Ctrl-C too, is raised again and leaves it ready for the next.
        w, bus = world()
        a = arm(bus)
        settle(w, bus, 10)
        raises(lambda: a.move_to(500, 0, 40, ms=500), "out of reach")
        raises(lambda: a.pose(100, 0, 40, "down"), "pitch")
        self.assertEqual(a.move_to(150, 0, 40, -90, ms=30), 30)
        robot = a.robot

        def interrupted(*args):
            del robot.move  # the Robot's own again
            raise KeyboardInterrupt

        robot.move = interrupted
        with self.assertRaises(KeyboardInterrupt):
            a.move_to(150, 0, 20, -90, ms=30)
        self.assertEqual(a.move_to(150, 0, 20, -90, ms=30), 30)
        settle(w, bus, 50)
        self.assertEqual(len(moves(w)), 2)
        line = a.line_to(150, 50, 20, mm_s=100)

        def broken():
            del robot.step
            raise OSError(110, "the UART took nothing")

        robot.step = broken
        with self.assertRaises(OSError):
            line.step()
        self.assertTrue(line.step())
        settle(w, bus, 50)
        self.assertEqual(len(moves(w)), 3)

    def test_a_line_whose_robot_has_no_bus_for_a_while_raises_each_step_then_goes_on(self):
        # A program that closes its port on an error (robot.bus = None) and opens it again
        # (a new BusServo): each step() meanwhile raises what it met, and the line goes on
        # on the new bus once it is there, even if the bus went before the line's first step.
        w, bus = world()
        a = arm(bus)
        a.move_to(150, 0, 40, -90, ms=0)
        settle(w, bus, 50)
        first = w.frames_total
        line = a.line_to(150, 50, 40, mm_s=100)
        a.robot.bus = None
        for _ in range(2):
            with self.assertRaises(AttributeError):
                line.step()
        a.robot.bus = bus = busservo.BusServo(w.uart)
        for _ in range(2000):
            if line.done:
                break
            line.step()
            settle(w, bus, 1)
        self.assertTrue(line.done)
        self.assertTrue(w.frames_total - first >= 10, w.frames_total - first)

    def test_a_line_leaving_the_reach_is_refused_whole_and_nothing_is_sent(self):
        # Both ends in reach, with the base at +-116.6 degrees; the line between them passes
        # behind the base, which turns 240 degrees at most.
        w, bus = world()
        a = arm(bus)
        a.move_to(-50, -100, 0, ms=0)
        settle(w, bus, 50)
        raises(
            lambda: a.line_to(-50, 100, 0),
            "the line from (-50.0, -100.0, 0.0) to (-50.0, 100.0, 0.0) mm leaves the reach at",
            "(x, y, z) = (-50.0, -",
            "the base would be at -120.",
            "beyond its limits -120.0..120.0",
        )
        settle(w, bus, 50)
        self.assertEqual(len(w.frames()), 1)  # the move_to()'s
        self.assertIs(a.robot.player, None)


class Moves(Tidy):
    def test_move_to_is_one_frame_for_the_four_joints(self):
        w, bus = world()
        a = arm(bus, more=True)
        pose = a.pose(150, 0, 40)
        self.assertEqual(a.move_to(150, 0, 40, ms=800), 800)
        settle(w, bus, 50)
        joints = a.robot.joints
        positions = {joints[n].servo_id: joints[n].position(pose[n]) for n in ba.JOINTS}
        self.assertEqual(moves(w), [(800, positions)])
        self.assertEqual(a.robot.clamped, 0)

    def test_move_to_at_mm_s_times_the_way_from_where_the_arm_went(self):
        w, bus = world()
        a = arm(bus)
        # Upright, but the shoulder's trim makes its position 515 -0.1 degrees: the tool point
        # at (-0.6, 0, 423).
        hand(w, {1: 500, 2: 515, 3: 500, 4: 500})
        # Nothing known: it reads where the joints are, then goes 411.5 mm at 100 mm/s.
        self.assertEqual(a.move_to(150, 0, 40, -90, mm_s=100), 4116)
        settle(w, bus, 50)
        self.assertEqual(commands(w), [CMD_MULT_SERVO_POS_READ, MOVE])
        self.assertEqual(a.move_to(250, 0, 50, pitch=0, ms=0), 0)
        # The tool point and the wrist go 100 mm at 50 mm/s: 2 s, nothing read.
        self.assertEqual(a.move_to(350, 0, 50, pitch=0, mm_s=50), 2000)
        self.assertEqual(a.move_to(300, 0, 50, pitch=0, mm_s=50), 1000)
        # The pitch alone: the wrist goes round the tool point, 30 degrees at 150 mm, a
        # chord of 77.6 mm.
        self.assertEqual(a.move_to(300, 0, 50, pitch=-30, mm_s=50), 1553)
        settle(w, bus, 150)
        self.assertEqual(commands(w), [CMD_MULT_SERVO_POS_READ] + [MOVE] * 5)

    def test_the_pitch_alone_turns_no_faster_than_mm_s_degrees_a_second(self):
        # A hand of length 0 (the tool point on the wrist's axis): the pitch alone moves no
        # point at all, yet the wrist turns. A degree of pitch counts as a mm of the way, so
        # it turns at mm_s degrees/s, not at once.
        w, bus = world()
        links = dict(LINKS, hand=0)
        a = ba.Arm(robot(bus), links)
        hand(w, {1: 500, 2: 515, 3: 500, 4: 500})
        a.move_to(150, 0, 100, pitch=0, ms=0)
        self.assertEqual(a.move_to(150, 0, 100, pitch=-30, mm_s=40), 750)
        line = a.line_to(150, 0, 100, pitch=-60, mm_s=40)
        self.assertEqual(round(line.ms), 750)

    def test_where_reads_the_tool_point(self):
        w, bus = world()
        a = arm(bus)
        pose = a.pose(150, -60, 40, -80)
        joints = a.robot.joints
        hand(w, {joints[n].servo_id: joints[n].position(pose[n]) for n in ba.JOINTS})
        x, y, z, pitch = a.where()
        self.assertTrue(near((x, y, z, pitch), (150, -60, 40, -80), 1.5), (x, y, z, pitch))
        self.assertEqual(round(x, 1), x)
        bus.read_positions([1, 2, 3, 4])
        self.assertEqual(a.where(bus.positions), (x, y, z, pitch))  # not blocking: read before

    def test_a_servo_that_does_not_answer_is_refused_by_name(self):
        w, bus = world()
        a = arm(bus)
        w.sim.missing.add(3)
        for call in (a.where, lambda: a.move_to(150, 0, 40, mm_s=50), lambda: a.line_to(1, 0, 0)):
            try:
                call()
                error = None
            except OSError as e:
                error = e
            self.assertIn("joint 'elbow': servo 3 does not answer", str(error))
        settle(w, bus, 20)
        self.assertEqual(moves(w), [])


class Calibration(Tidy):
    def test_the_arm_saves_and_loads_beside_the_joints(self):
        w, bus = world()
        path = scratch("arm") + ".json"
        try:
            arm(bus, more=True).save(path)
            with open(path) as f:
                saved = json.load(f)
            again = ba.Arm.load(bus, path)
            joints_only = bm.Robot.load(bus, path)  # the motion layer ignores the links
            on_robot = ba.Arm.load(joints_only, path)
        finally:
            os.remove(path)
        self.assertEqual(sorted(saved), ["joints", "links"])
        self.assertEqual(saved["links"], LINKS)
        self.assertEqual(again.links, LINKS)
        self.assertEqual(again.robot.names, arm(bus, more=True).robot.names)
        for name, joint in arm(bus, more=True).robot.joints.items():
            self.assertEqual(again.robot.joints[name].config(), joint.config())
        self.assertIs(on_robot.robot, joints_only)
        self.assertEqual(again.pose(150, 0, 40), arm(bus).pose(150, 0, 40))

    def test_saving_keeps_what_else_the_file_holds(self):
        w, bus = world()
        path = scratch("arm") + ".json"
        try:
            with open(path, "w") as f:
                json.dump({"joints": {}, "links": {}, "checked": "2024-05-01"}, f)
            arm(bus).save(path)
            with open(path) as f:
                saved = json.load(f)
        finally:
            os.remove(path)
        self.assertEqual(saved["checked"], "2024-05-01")
        self.assertEqual(saved["links"], LINKS)

    def test_the_default_file_is_the_calibration_every_example_loads(self):
        self.assertEqual(bm.CALIBRATION, "robot.json")  # one name, busservo_motion's
        w, bus = world()
        folder = scratch("arm")
        os.mkdir(folder)
        here = os.getcwd()
        try:
            os.chdir(folder)
            arm(bus).save()
            self.assertEqual(ba.Arm.load(bus).links, LINKS)
            self.assertEqual(os.listdir("."), ["robot.json"])
        finally:
            os.chdir(here)
            sh("rm -rf " + folder)

    def test_an_arm_loaded_elbow_down_solves_elbow_down(self):
        w, bus = world()
        path = scratch("arm") + ".json"
        joints = {name: bm.Joint(i + 1) for i, name in enumerate(ba.JOINTS)}  # no limits
        try:
            ba.Arm(bm.Robot(bus, joints), LINKS).save(path)
            down = ba.Arm.load(bus, path, elbow_up=False)
        finally:
            os.remove(path)
        self.assertFalse(down.elbow_up)
        self.assertTrue(down.pose(250, 50, 100, -30)["elbow"] < 0)

    def test_a_file_that_is_no_arm_says_which_and_why(self):
        w, bus = world()
        path = scratch("arm") + ".json"
        joints = {"joints": {n: j.config() for n, j in robot(bus).joints.items()}}
        try:
            for config, words in (
                ("{not json", ("not valid JSON",)),
                (joints, ("no 'links' in it", "Arm.save()")),
                (dict(joints, links=[70]), ("links must be {name: mm}",)),
                (dict(joints, links=dict(LINKS, hand="150")), ("links['hand']", "'150'")),
                ({"joints": {"base": {"servo_id": 1}}, "links": LINKS}, ("shoulder",)),
            ):
                with open(path, "w") as f:
                    f.write(config if type(config) is str else json.dumps(config))
                raises(lambda: ba.Arm.load(bus, path), path, *words)
        finally:
            os.remove(path)


class Lines(Tidy):
    START = (120, -100, 20)
    END = (120, 100, 20)

    def follow(self, w, bus, line, extra=None):
        """A loop stepping the line every ms (and streaming the extra joints, if given, with
        robot.step()), until it is done: (how long in ms, the longest step() in us)."""
        start = w.clock.now_us
        longest = 0
        tick = 0
        while not line.done:
            before = w.clock.now_us
            if extra:
                line.robot.stream({"roll": tick % 60, "gripper": 30})
            line.step()
            longest = max(longest, w.clock.now_us - before)
            while bus.poll() is not None:
                pass
            w.clock.advance_ms(1)
            tick += 1
            self.assertTrue(tick < 100000)
        settle(w, bus, 50)
        return (w.clock.now_us - start) // 1000, longest

    def test_the_line_streams_at_the_wires_pace_and_keeps_to_the_line(self):
        # The frames the controller got, back to millimetres: each within 1 mm of the line,
        # the last at its end; as many as the wire allows, and step() never waits.
        for port in wire.PORTS:
            for more in (False, True):
                w, bus = world(port)
                a = arm(bus, more)
                a.move_to(*self.START, pitch=-90, ms=0)
                settle(w, bus, 50)
                first = w.frames_total
                line = a.line_to(*self.END, pitch=-90, mm_s=50)
                self.assertEqual(line.ms, 4000)
                self.assertIs(a.robot.player, line)
                took, longest = self.follow(w, bus, line, more)
                got = [frame_positions(f) for f in w.frames(first)]
                n = 6 if more else 4
                rate = len(got) / (took / 1000)
                limit = 960 / (3 * n + 7)
                print("\n    %s, %d servos: %.1f updates/s of %.1f" % (port, n, rate, limit))
                self.assertTrue(rate >= 0.95 * limit, (port, n, rate))
                self.assertTrue(4000 <= took <= 4100, took)
                self.assertEqual(line.updates, len(got))
                self.assertTrue(longest <= 1000, (port, longest))
                for positions in got:
                    self.assertEqual(len(positions), n)
                    p = sent_point(a, positions)
                    self.assertTrue(off_line(p[:3], self.START, self.END) <= 1, p)
                    self.assertTrue(abs(p[3] + 90) <= 0.5, p)
                end = a.pose(*self.END, pitch=-90)
                for name in ba.JOINTS:
                    joint = a.robot.joints[name]
                    self.assertEqual(got[-1][joint.servo_id], joint.position(end[name]))
                self.assertTrue(line.done)
                self.assertIs(a.robot.player, None)
                self.assertEqual((w.garbled, w.sim.beeps, a.robot.clamped), (0, 0, 0))

    def test_a_line_past_the_bases_axis_keeps_to_the_line(self):
        # 10 mm from the base's axis, the base turns 11 degrees a mm there, and a step goes
        # straight in the joints between points solved 2 mm apart: each frame still within
        # 1 mm of the line (a position's rounding), going forward, the last at the end.
        w, bus = world()
        a = arm(bus)
        start, end = (10, -60, 40), (10, 60, 40)
        a.move_to(*start, pitch=-90, ms=0)
        settle(w, bus, 50)
        first = w.frames_total
        line = a.line_to(*end, pitch=-90, mm_s=50)
        self.follow(w, bus, line)
        points = [sent_point(a, frame_positions(f)) for f in w.frames(first)]
        self.assertTrue(len(points) >= 110, len(points))
        for p in points:
            self.assertTrue(off_line(p[:3], start, end) <= 1, p)
            self.assertTrue(abs(p[3] + 90) <= 0.5, p)
        ys = [p[1] for p in points]
        self.assertTrue(all(b > a for a, b in zip(ys, ys[1:])), ys)
        self.assertTrue(near(points[-1][:3], end, 0.5), points[-1])
        self.assertEqual(a.robot.clamped, 0)

    def test_a_line_from_a_position_reported_turns_out_starts_where_the_arm_is(self):
        # A servo may report a position far outside its range (positions are signed 16-bit):
        # the base read as 3560 degrees, ten turns past where it is. The line starts from
        # where the arm is (the angle within a turn), so every frame keeps to the line and
        # nothing is clamped.
        w, bus = world()
        a = arm(bus)
        a.move_to(*self.START, pitch=-90, ms=0)
        settle(w, bus, 50)
        joints = a.robot.joints
        positions = {j.servo_id: w.sim.position(j.servo_id) for j in joints.values()}
        base = joints["base"]
        positions[base.servo_id] += round(3600 * base.per_degree)  # 10 turns on
        self.assertTrue(near(a.where(positions)[:3], self.START, 0.5))
        first = w.frames_total
        line = a.line_to(*self.END, pitch=-90, mm_s=50)
        self.follow(w, bus, line)
        points = [sent_point(a, frame_positions(f)) for f in w.frames(first)]
        self.assertTrue(len(points) >= 190, len(points))
        for p in points:
            self.assertTrue(off_line(p[:3], self.START, self.END) <= 1, p)
        self.assertEqual(a.robot.clamped, 0)

    def test_no_pitch_turns_the_hand_evenly_to_the_ends_own(self):
        w, bus = world()
        a = arm(bus)
        a.move_to(150, 0, 40, pitch=-90, ms=0)
        settle(w, bus, 50)
        first = w.frames_total
        line = a.line_to(300, 0, 70, mm_s=100)
        end_pitch = a.point(a.pose(300, 0, 70))[3]
        self.assertTrue(near(line.end, (300, 0, 70, end_pitch)))
        self.follow(w, bus, line)
        pitches = [sent_point(a, frame_positions(f))[3] for f in w.frames(first)]
        self.assertTrue(all(b >= a - 0.3 for a, b in zip(pitches, pitches[1:])), pitches)
        self.assertTrue(abs(pitches[-1] - end_pitch) <= 0.5, (pitches[-1], end_pitch))

    def test_a_pitch_turn_in_place_keeps_the_tool_point_still(self):
        # No travel, the hand turning 67 degrees to the end's own pitch (the wrist at the
        # edge of the reach, the elbow straight): the wrist goes 176 mm round the tool point,
        # 2.6 mm a degree. Points 2 degrees apart were 5 mm apart for the wrist, and going
        # straight in the joints between them took the tool point 1.24 mm off (1.63 mm in
        # the frames sent) near the edge, where the elbow straightens.
        w, bus = world()
        a = arm(bus)
        here = (102.1, -229.5, -6.7)
        a.move_to(*here, pitch=0, ms=0)
        settle(w, bus, 50)
        streamed = []
        stream = a.robot.stream

        def spy(pose):
            streamed.append(a.point(pose))
            return stream(pose)

        a.robot.stream = spy  # before line_to(): the line binds it when it is made
        line = a.line_to(*here, mm_s=50)
        self.assertTrue(line.end[3] < -60, line.end)
        self.follow(w, bus, line)
        self.assertTrue(len(streamed) >= 150, len(streamed))
        off = max(math.sqrt(sum((p - q) ** 2 for p, q in zip(s[:3], here))) for s in streamed)
        self.assertTrue(off <= 0.5, off)  # what the line streamed, before a position's rounding
        self.assertEqual(a.robot.clamped, 0)

    def test_a_joints_dps_slows_the_whole_line(self):
        # The base turns fastest where the line passes nearest its axis, 0.48 degree a mm: at
        # 90 % of 60 degrees/s (a margin for the robot's rounding) the line goes at 113 mm/s,
        # 1.77 s rather than 1 s.
        w, bus = world()
        r = robot(bus)
        r.joints["base"].dps = 60
        r = bm.Robot(bus, {n: bm.Joint(**j.config()) for n, j in r.joints.items()})
        a = ba.Arm(r, LINKS)
        a.move_to(*self.START, pitch=-90, ms=0)
        settle(w, bus, 50)
        slowed = r.slowed  # the move_to(), which the base's dps made longer
        line = a.line_to(120, 100, 20, pitch=-90, mm_s=200)
        self.assertTrue(1765 <= line.ms <= 1775, line.ms)
        first = w.frames_total
        self.follow(w, bus, line)
        # Never too fast: the robot held the base back by a position (its rounding: 0.24
        # degree, 12 degrees/s over a frame) in one frame at most. Without the line's plan
        # it holds back most frames along the middle.
        self.assertTrue(r.slowed - slowed <= 1, r.slowed - slowed)
        frames = len(w.frames(first))
        self.assertTrue(frames >= 85, frames)

    def test_a_late_loop_slows_the_line_rather_than_jumping_along_it(self):
        # The loop is away for 500 ms (a garbage collection, a blocking read) mid-line: the
        # next frame goes on by 100 ms of the line (5 mm at 50 mm/s), not by the 500 ms
        # missed (25 mm in one frame's 20 ms: a lurch), and the line ends 400 ms late.
        w, bus = world()
        a = arm(bus)
        a.move_to(*self.START, pitch=-90, ms=0)
        settle(w, bus, 50)
        first = w.frames_total
        line = a.line_to(*self.END, pitch=-90, mm_s=50)
        for _ in range(1000):
            line.step()
            settle(w, bus, 1)
        settle(w, bus, 500)
        took, _ = self.follow(w, bus, line)
        points = [sent_point(a, frame_positions(f)) for f in w.frames(first)]
        pairs = zip(points, points[1:])
        steps = [math.sqrt(sum((b - a) ** 2 for a, b in zip(p[:3], q[:3]))) for p, q in pairs]
        self.assertTrue(max(steps) <= 5.2, max(steps))
        self.assertTrue(1000 + 500 + took >= 4400, took)

    def test_stop_drops_the_point_streamed_but_not_yet_sent(self):
        # A loop that steps the robot for the gripper, then the line: the line streams a
        # point the robot's own step() then holds back (the wire was busy just now). After
        # line.stop(), the gripper's frames carry the gripper alone: the arm stays where the
        # line's last frame put it.
        w, bus = world()
        a = arm(bus, more=True)
        r = a.robot
        a.move_to(*self.START, pitch=-90, ms=0)
        settle(w, bus, 50)
        line = a.line_to(*self.END, mm_s=50)
        for _ in range(2000):
            r.step()
            sent = line.updates
            line.step()
            held = line.updates == sent and r._fresh  # streamed, not sent
            if held:
                break
            settle(w, bus, 1)
        self.assertTrue(held)
        line.stop()
        settle(w, bus, 50)
        first = w.frames_total
        for k in range(10):
            r.stream({"gripper": 30 + k})
            r.step()
            settle(w, bus, 30)
        got = [frame_positions(f) for f in w.frames(first)]
        self.assertEqual(len(got), 10)
        self.assertTrue(all(sorted(p) == [6] for p in got), got)

    def test_stop_and_estop_end_the_line_and_send_nothing_more(self):
        w, bus = world()
        a = arm(bus)
        a.move_to(*self.START, pitch=-90, ms=0)
        settle(w, bus, 50)
        line = a.line_to(*self.END, mm_s=50)
        for _ in range(100):
            line.step()
            settle(w, bus, 1)
        line.stop()
        settle(w, bus, 50)  # the frame on its way arrives
        sent = w.frames_total
        for _ in range(100):
            self.assertFalse(line.step())
            settle(w, bus, 1)
        self.assertEqual(w.frames_total, sent)
        line = a.line_to(*self.START, mm_s=50)
        line.step()
        a.robot.estop()
        self.assertTrue(line.done)
        self.assertFalse(line.step())
        settle(w, bus, 50)
        self.assertEqual(commands(w)[-1], CMD_MULT_SERVO_UNLOAD)

    def test_a_line_started_while_a_sequence_plays_stops_the_sequence(self):
        # A loop that still steps the player after starting a line: the player is done, so
        # only the line drives the joints (its frames carry all four), and estop() stops all.
        w, bus = world()
        a = arm(bus)
        a.move_to(*self.START, pitch=-90, ms=0)
        settle(w, bus, 50)
        poses = [({"wrist": 20}, 200), ({"wrist": -20}, 200)]
        player = bm.Sequence(poses).play(a.robot, loop=True)
        self.assertTrue(player.step())
        settle(w, bus, 50)
        first = w.frames_total
        line = a.line_to(*self.END, pitch=-90, mm_s=200)
        self.assertTrue(player.done)
        self.assertIs(a.robot.player, line)
        for _ in range(1200):
            self.assertFalse(player.step())
            line.step()
            settle(w, bus, 1)
        got = [frame_positions(f) for f in w.frames(first)]
        self.assertTrue(line.done and len(got) >= 45, len(got))
        self.assertTrue(all(sorted(p) == [1, 2, 3, 4] for p in got), got)
        self.assertTrue(near(sent_point(a, got[-1])[:3], self.END, 1), got[-1])
        line = a.line_to(*self.START, pitch=-90, mm_s=200)
        line.step()
        a.robot.estop()
        self.assertTrue(line.done and player.done)
        self.assertIs(a.robot.player, None)

    def test_a_move_to_ends_a_line(self):
        w, bus = world()
        a = arm(bus)
        a.move_to(*self.START, pitch=-90, ms=0)
        line = a.line_to(*self.END, mm_s=50)
        a.move_to(150, 0, 40, ms=500)
        self.assertTrue(line.done)

    def test_await_line_runs_it_to_its_end_under_asyncio(self):
        class SimAsyncio:  # sleeping moves the world's clock, then the other tasks run
            async def sleep_ms(self, ms):
                settle(w, bus, ms)
                await asyncio.sleep_ms(0)

        w, bus = world()
        a = arm(bus)
        a.move_to(*self.START, pitch=-90, ms=0)
        settle(w, bus, 50)
        bm._asyncio = SimAsyncio()  # busservo_motion.aio() gives it to the arm
        ticks = []

        async def control_loop():
            while True:
                ticks.append(w.clock.now_us)
                await bm._asyncio.sleep_ms(10)

        async def main():
            asyncio.create_task(control_loop())
            start = w.clock.now_us
            await a.line_to(*self.END, mm_s=100)
            first = w.clock.now_us - start
            await a.line_to(*self.START, mm_s=200).run()
            return first, w.clock.now_us - start

        first, both = asyncio.run(main())
        settle(w, bus, 50)  # the last frame arrives
        # Each is done when its last frame is sent: about a frame before its ms.
        self.assertTrue(1950000 <= first <= 2050000, first)
        self.assertTrue(2950000 <= both <= 3100000, both)
        self.assertTrue(len(ticks) > 50, len(ticks))  # the other task ran meanwhile
        frames = w.frames()
        print("\n    %d frames, %d ticks" % (len(frames), len(ticks)))
        self.assertTrue(len(frames) >= 0.95 * 3 * 960 / 19, len(frames))
        self.assertTrue(near(sent_point(a, frame_positions(frames[-1]))[:3], self.START, 1))

    def test_a_step_while_the_wire_is_busy_solves_nothing_and_allocates_nothing(self):
        # The world's UART models allocate (they are Python): here the driver writes to the
        # fake UART of tests/test_alloc.py, which does not, on a clock the test steps.
        clock = wire.Clock()
        busservo.time = bm.time = ba.time = clock
        uart = FakeUART()
        a = arm(busservo.BusServo(uart))
        a.move_to(*self.START, pitch=-90, ms=0)
        clock.advance_ms(40)
        line = a.line_to(*self.END, mm_s=50)
        self.assertTrue(line.step())  # a frame: the wire is busy for 20 ms
        self.assertEqual(heap_per_call(line.step), 0)
        self.assertEqual(line.updates, 1)

    def test_a_step_that_sends_allocates_only_the_four_degrees_it_streams(self):
        # It goes straight in the joints between points the line solved when it was made, in
        # ints: its only heap objects are the four floats it streams (a solve took 20 and more).
        clock = wire.Clock()
        busservo.time = bm.time = ba.time = clock
        a = arm(busservo.BusServo(FakeUART()))
        a.move_to(*self.START, pitch=-90, ms=0)
        clock.advance_ms(40)
        line = a.line_to(*self.END, mm_s=1)  # 200 s: every step below sends
        x = 1.5
        one = heap_per_call(lambda: x * 3)  # a float

        def free():
            clock.advance_ms(25)

        updates = line.updates
        self.assertEqual(heap_per_call(line.step, free), 4 * one)
        self.assertTrue(line.updates - updates >= 10, line.updates)


class Docs(unittest.TestCase):
    def test_the_pages_example_runs_on_the_simulator(self):
        # As written, but its uart() is board.py's: here the simulator's. It saves robot.json
        # only on a real arm: on the simulator it leaves the folder it runs in as it was.
        code = block(open("docs/arm.md").read(), "## In a few lines", "```python")
        stand_in = "from busservo_sim import SimController as uart\n\n\n"
        folder = scratch("arm")
        os.mkdir(folder)
        try:
            out = run(
                stand_in + "\n".join(code) + '\nprint("where", arm.where())\n', "where (", folder
            )
            self.assertEqual(os.listdir(folder), [])
        finally:
            sh("rm -rf " + folder)
        self.assertTrue("Traceback" not in out, out)

    def test_the_pages_example_keeps_the_links_a_maker_saved(self):
        # On a real arm (a board.py: here the simulator stands for its controller), with the
        # robot.json a calibration saved: it moves the arm it finds there and leaves the file
        # as it was. With none, it saves its own.
        code = block(open("docs/arm.md").read(), "## In a few lines", "```python")
        limits = {"shoulder": [-90, 90], "elbow": [-30, 120], "gripper": [0, 60]}
        joints = {}
        for i, name in enumerate(("base", "shoulder", "elbow", "wrist", "gripper")):
            joints[name] = {"servo_id": i + 1, "kind": "BUS", "direction": 1, "trim": 0.0}
            joints[name].update({"limits": limits.get(name, [-120, 120]), "dps": None})
        links = {"base_height": 71.5, "upper_arm": 104, "forearm": 99, "hand": 148}
        saved = {"joints": joints, "links": links}
        for before in (saved, None):
            folder = scratch("arm")
            os.mkdir(folder)
            try:
                with open(folder + "/board.py", "w") as f:
                    f.write("from busservo_sim import SimController as uart\n")
                if before:
                    with open(folder + "/robot.json", "w") as f:
                        f.write(json.dumps(before))
                out = run("\n".join(code) + '\nprint("links", arm.links)\n', "links {", folder)
                with open(folder + "/robot.json") as f:
                    after = json.loads(f.read())
            finally:
                sh("rm -rf " + folder)
            self.assertTrue("Traceback" not in out, out)
            if before:
                self.assertEqual(after, before)  # nothing in the file changed
                self.assertIn("'hand': 148", out)
            else:
                self.assertEqual(after["links"], links_of(" ".join(code)))

    def test_the_pages_links_are_calibrate_mds(self):
        # One arm in both pages: the links the calibration asks for, saves and shows in code
        # are the ones docs/arm.md's example gives.
        arm = links_of(
            " ".join(block(open("docs/arm.md").read(), "## In a few lines", "```python"))
        )
        calibrate = open("docs/calibrate.md").read()
        asked = calibrate.split("links in mm, axis to axis (")[1]
        names = asked.split(")")[0].split()  # in the order the example asks for them
        typed = asked.split("or Enter to leave them out: ")[1].split("\n")[0].split()
        self.assertEqual(dict(zip(names, [float(x) for x in typed])), arm)
        shown = calibrate[calibrate.index('"links": {') + len('"links": ') :]
        self.assertEqual(links_of(shown), arm)
        self.assertEqual(links_of(calibrate[calibrate.index("links={") + len("links=") :]), arm)

    def test_the_picture_is_well_formed_svg_and_shows_the_conventions(self):
        svg = "docs/arm.svg"
        check = (
            "import sys, xml.etree.ElementTree as E; r = E.parse(sys.argv[1]).getroot(); "
            "print(r.tag, r.get('width'), r.get('height'))"
        )
        ok, out = sh('%s -c "%s" %s' % (PYTHON, check, svg))
        self.assertTrue(ok, out)
        self.assertEqual(out.split(), ["{http://www.w3.org/2000/svg}svg", "800", "500"])
        text = open(svg).read()
        for words in LINKS:
            self.assertIn(words, text)
        for words in ("shoulder +", "elbow +", "wrist +", "base +", "pitch", "x", "y", "z"):
            self.assertIn(words, text)
        self.assertIn("](arm.svg)", open("docs/arm.md").read())
        png = scratch("arm") + ".png"
        try:
            ok, out = sh("%s tests/render_svg.py %s %s" % (PYTHON, svg, png))
        finally:
            sh("rm -f " + png)
        if out.startswith("no renderer"):
            print("\n*** SKIPPED: %s: %s (tests/run.sh installs it) ***" % (svg, out.strip()))
            raise unittest.SkipTest(out.strip())
        self.assertTrue(ok, out)
        size, colours, ink = out.split()
        self.assertEqual(size, "800x500")
        self.assertTrue(10 < float(ink[len("ink=") :]) < 80, out)


if __name__ == "__main__":
    unittest.main()
