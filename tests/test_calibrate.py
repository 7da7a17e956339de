# busservo_calibrate: a person calibrates an arm by hand, on the wire-faithful world of
# tests/wire.py (a stepped clock, the rp2 UART model, the simulated controller), with the
# simulator's hands (SimController.turn()) scripted: the three steps, each refusal, the file
# that round-trips; then examples/calibrate.py on the unix port, with the keys typed at a
# terminal (tests/typist.py) and a board.py whose controller has a person's hands.
import errno
import json
import os
import unittest

import busservo
import busservo_arm
import busservo_calibrate as bc
import busservo_motion as bm
import wire
from busservo import CMD_MULT_SERVO_POS_READ, CMD_MULT_SERVO_UNLOAD
from busservo import CMD_SERVO_MOVE as MOVE
from busservo_sim import SimController
from shell import scratch, sh

# The arm of these tests, as the person holds it: each joint's servo, and its position at the
# rest pose, at the two ends of its safe range, and nudged a little in its positive
# direction. The shoulder and the wrist are mounted the other way round: their positive
# (forward and down) turns their servos back.
IDS = {"base": 1, "shoulder": 2, "elbow": 3, "wrist": 4, "gripper": 5}
REST = {1: 512, 2: 488, 3: 500, 4: 530, 5: 300}
ENDS = {1: (140, 880), 2: (200, 800), 3: (150, 860), 4: (180, 880), 5: (300, 700)}
NUDGED = {1: 560, 2: 440, 3: 545, 4: 480, 5: 350}
# What that makes of each joint: (direction, trim, limits) in degrees. base: 512 is
# 12 positions (2.9 degrees) past the centre; it swept 140..880, -86.4..91.2 degrees from
# the centre, -89.3..88.3 from its rest pose, and keeps 3 degrees inside each end.
JOINTS = {
    "base": (1, 2.9, (-86.3, 85.3)),
    "shoulder": (-1, -2.9, (-71.9, 66.1)),
    "elbow": (1, 0.0, (-81.0, 83.4)),
    "wrist": (-1, 7.2, (-81.0, 81.0)),
    "gripper": (1, -48.0, (3.0, 93.0)),  # closed at rest: one end of its range
}


def world():
    """(world, bus), the driver and the motion layer on the world's clock."""
    w = wire.World("rp2")
    busservo.time = bm.time = w.clock
    return w, busservo.BusServo(w.uart)


def turn(w, pose):
    """The person's hands: each servo of pose {servo_id: position} turned there. True if
    every one went (a servo under power holds)."""
    w.clock.advance_ms(50)  # a hand takes a moment; what was sent has crossed the wire
    went = [w.sim.turn(servo_id, position) for servo_id, position in pose.items()]
    return all(went)


def sweep(ends, k, steps):
    """The pose k steps of steps along each joint's sweep from one end to the other."""
    return {servo_id: a + (b - a) * k // steps for servo_id, (a, b) in ends.items()}


def calibrate(w, cal, rest=REST, ends=ENDS, nudged=NUDGED, steps=10, limp=True):
    """The person's minute: the joints limp, the rest pose held, every joint swept from one
    end of its range to the other (a sample at each step), the nudge."""
    if limp:
        cal.limp()
    turn(w, rest)
    cal.rest()
    for k in range(steps + 1):
        turn(w, sweep(ends, k, steps))
        cal.sample()
    turn(w, nudged)
    cal.nudge()


def raised(call, *args):
    """The exception call(*args) raised, or None."""
    try:
        call(*args)
    except Exception as e:
        return e
    return None


def but(pose, **changes):
    """pose with the changes {name: position} given by joint name."""
    out = dict(pose)
    for name, position in changes.items():
        out[IDS[name]] = position
    return out


class Steps(unittest.TestCase):
    def setUp(self):
        self.w, self.bus = world()
        self.cal = bc.Calibration(self.bus, IDS)

    def assertJoints(self, joints, expected):
        for name, (direction, trim, (lo, hi)) in expected.items():
            joint = joints[name]
            self.assertEqual(joint.direction, direction, name)
            for got, want in ((joint.trim, trim), (joint.lo, lo), (joint.hi, hi)):
                self.assertTrue(abs(got - want) < 0.01, (name, joint.config()))

    def test_a_person_calibrates_the_arm_in_three_steps(self):
        calibrate(self.w, self.cal)
        self.assertEqual(self.cal.problems(), {})
        robot = self.cal.robot()
        self.assertEqual(robot.names, ["base", "shoulder", "elbow", "wrist", "gripper"])
        self.assertJoints(robot.joints, JOINTS)
        for name, joint in robot.joints.items():
            servo_id = IDS[name]
            # 0 degrees is where the person held it; positive, the way they nudged it.
            self.assertEqual(round(joint.degrees(REST[servo_id]), 1), 0, name)
            went = NUDGED[servo_id] - REST[servo_id]
            self.assertEqual(joint.position(10) > joint.position(0), went > 0, name)
            # The limits: 3 degrees (12.5 positions) inside the ends the person swept to.
            ends = sorted((joint.position(joint.lo), joint.position(joint.hi)))
            a, b = ENDS[servo_id]
            self.assertTrue(a + 12 <= ends[0] <= a + 13, (name, ends))
            self.assertTrue(b - 13 <= ends[1] <= b - 12, (name, ends))

    def test_nothing_moves_under_power(self):
        # The controller hears one UNLOAD of every joint, then positions queries only.
        calibrate(self.w, self.cal)
        self.cal.robot()
        frames = self.w.frames()
        self.assertEqual(frames[0], bytes((0x55, 0x55, 0x08, 0x14, 5, 1, 2, 3, 4, 5)))
        self.assertEqual([f[3] for f in frames[1:]], [CMD_MULT_SERVO_POS_READ] * 13)
        self.assertEqual(self.w.sim.limp, {1, 2, 3, 4, 5})

    def test_the_calibrated_arm_homes_slowly_to_its_rest_pose(self):
        calibrate(self.w, self.cal)
        robot = self.cal.robot()
        first = self.w.frames_total
        ms = robot.home(dps=30)
        # The wrist goes furthest: 50 positions, 12 degrees, 400 ms at 30 degrees/s. The
        # gripper's 0 is 3 degrees outside its limits: it stops at 3.
        self.assertEqual(ms, 400)
        self.w.clock.advance_ms(ms + 50)
        moves = [f for f in self.w.frames(first) if f[3] == MOVE]
        self.assertEqual(len(moves), 1)
        self.assertEqual(moves[0][5] | moves[0][6] << 8, 400)
        where = robot.where()
        for name in ("base", "shoulder", "elbow", "wrist"):
            self.assertTrue(abs(where[name]) < 0.3, where)
        self.assertTrue(abs(where["gripper"] - 3) < 0.3, where)

    def test_the_steps_take_positions_a_loop_read_without_blocking(self):
        # The panel's way: request_positions(), poll() until the reply, then the step takes
        # bus.positions. The same calibration as the blocking reads make.
        bus = self.bus
        cal = self.cal

        def read():
            bus.request_positions(cal.ids)
            while bus.poll() != CMD_MULT_SERVO_POS_READ:
                self.w.clock.advance_ms(1)
            return bus.positions

        cal.limp()
        turn(self.w, REST)
        cal.rest(read())
        for k in range(11):
            turn(self.w, sweep(ENDS, k, 10))
            cal.sample(read())
        turn(self.w, NUDGED)
        self.assertEqual(cal.nudge(read())["base"], 11.5)  # 48 positions
        self.assertJoints(cal.joints(), JOINTS)
        self.assertEqual(cal.samples, 11)

    def test_the_sweep_may_start_anywhere_and_go_either_way(self):
        # From the rest pose up to one end, down to the other, and back to the rest pose: the
        # same calibration as one sweep from end to end.
        cal = self.cal
        top = {servo_id: b for servo_id, (a, b) in ENDS.items()}
        bottom = {servo_id: a for servo_id, (a, b) in ENDS.items()}
        cal.limp()
        turn(self.w, REST)
        cal.rest()
        for start, end in ((REST, top), (top, bottom), (bottom, REST)):
            for k in range(11):
                turn(self.w, {i: start[i] + (end[i] - start[i]) * k // 10 for i in start})
                cal.sample()
        turn(self.w, NUDGED)
        cal.nudge()
        self.assertJoints(cal.joints(), JOINTS)

    def test_a_pwm_joint_is_calibrated_in_its_own_units(self):
        # A PWM servo: 500..2500 us over 180 degrees, 1500 at its centre. (On the simulator
        # only: a real one cannot tell the controller where a hand turned it.)
        self.w.sim.pwm.add(5)
        cal = bc.Calibration(self.bus, IDS, kinds={"gripper": bm.PWM_180})
        calibrate(
            self.w,
            cal,
            rest=but(REST, gripper=1100),
            ends=but(ENDS, gripper=(1100, 2000)),
            nudged=but(NUDGED, gripper=1200),
        )
        gripper = cal.robot().joints["gripper"]
        self.assertEqual(gripper.kind, bm.PWM_180)
        self.assertEqual((gripper.direction, gripper.trim), (1, -36.0))  # 400 us: 36 degrees
        self.assertEqual(gripper.degrees(1100), 0)
        self.assertEqual((gripper.lo, gripper.hi), (3.0, 78.0))  # 1100..2000: 0..81


class Refusals(unittest.TestCase):
    # Each joint it cannot trust is named, with why; nothing is written.

    def setUp(self):
        self.w, self.bus = world()
        self.cal = bc.Calibration(self.bus, IDS)

    def refused(self, **person):
        """What the calibration says of the joints it cannot trust, after the person."""
        calibrate(self.w, self.cal, **person)
        error = raised(self.cal.robot)
        self.assertIsInstance(error, ValueError)
        return str(error)

    def test_a_joint_that_did_not_move(self):
        said = self.refused(
            rest=but(REST, elbow=500),
            ends=but(ENDS, elbow=(500, 500)),
            nudged=but(NUDGED, elbow=500),
        )
        self.assertEqual(
            said,
            "cannot calibrate elbow: did not move (0.0 degrees seen): is it limp, and is servo 3"
            " its servo?",
        )

    def test_a_range_under_10_degrees(self):
        # 500..540: 9.6 degrees.
        said = self.refused(ends=but(ENDS, wrist=(500, 540)), nudged=but(NUDGED, wrist=530))
        self.assertIn(
            "cannot calibrate wrist: moved through 9.6 degrees (0.0..9.6), under 10", said
        )
        self.assertFalse("base" in said or "elbow" in said, said)

    def test_a_rest_pose_outside_the_range_seen(self):
        # Held at 850 (81.6 degrees), swept 200..800 only.
        said = self.refused(rest=but(REST, shoulder=850), nudged=but(NUDGED, shoulder=800))
        self.assertIn(
            "cannot calibrate shoulder: its rest pose (84.0 degrees) is outside the range seen"
            " (-72.0..72.0)",
            said,
        )

    def test_a_direction_nudge_too_small_to_tell(self):
        # 512 to 520: 1.9 degrees.
        said = self.refused(nudged=but(NUDGED, base=520))
        self.assertIn(
            "cannot calibrate base: nudged 1.9 degrees from its rest pose: too little to tell"
            " its direction (5 or more)",
            said,
        )

    def test_every_joint_it_cannot_trust_is_named_at_once(self):
        said = self.refused(
            ends=but(ENDS, wrist=(500, 540)), nudged=but(NUDGED, base=520, wrist=530)
        )
        self.assertTrue(said.startswith("cannot calibrate base: nudged 1.9 degrees"), said)
        self.assertIn("; wrist: moved through 9.6 degrees", said)
        self.assertEqual(sorted(self.cal.problems()), ["base", "wrist"])

    def test_a_servo_under_power_holds_against_the_hands(self):
        # The person forgot limp(): the hands cannot turn a servo that holds.
        self.assertFalse(turn(self.w, REST))
        said = self.refused(limp=False)
        for name in IDS:
            self.assertIn("%s: did not move (0.0 degrees seen)" % name, said)

    def test_a_pwm_servo_that_did_not_move_is_told_why(self):
        self.w.sim.pwm.add(5)
        self.cal = bc.Calibration(self.bus, IDS, kinds={"gripper": bm.PWM_180})
        said = self.refused(
            rest=but(REST, gripper=1500),
            ends=but(ENDS, gripper=(1500, 1500)),
            nudged=but(NUDGED, gripper=1500),
        )
        self.assertIn(
            "gripper: did not move (0.0 degrees seen): is it limp, and is servo 5 its servo? (a"
            " PWM servo cannot tell the controller where a hand turned it)",
            said,
        )

    def test_a_servo_that_does_not_answer_is_named_at_once(self):
        self.cal.limp()
        self.w.sim.missing.add(3)  # unpowered, or off the bus: it reads 65535
        # Read now, or read elsewhere (the driver's None for it): refused by name.
        read_elsewhere = {1: 500, 2: 500, 3: None, 4: 500, 5: 500}
        for step, args in ((self.cal.rest, ()), (self.cal.sample, (read_elsewhere,))):
            error = raised(step, *args)
            self.assertIsInstance(error, OSError)
            self.assertEqual(error.args[0], errno.ENODEV)
            self.assertIn("joint 'elbow': servo 3 does not answer", error.args[1])
        error = raised(self.cal.sample, {1: 500, 2: 500, 4: 500, 5: 500})
        self.assertIsInstance(error, ValueError)
        self.assertIn("no servo 3 (joint 'elbow')", str(error))

    def test_a_rest_pose_past_the_servos_end(self):
        # A servo near its end may say -3; a horn mounted far off, -30: -127.2 degrees.
        cal = self.cal
        cal.rest(but(REST, base=-30))
        for position in (-30, 0, 300):
            cal.sample(but(REST, base=position))
        cal.nudge(but(REST, base=0))
        self.assertEqual(
            cal.problems(),
            {
                "base": "its rest pose is past its servo's end (-127.2 degrees from the centre):"
                " turn its horn nearer the centre",
                "shoulder": "did not move (0.0 degrees seen): is it limp, and is servo 2 its"
                " servo?",
                "elbow": "did not move (0.0 degrees seen): is it limp, and is servo 3 its servo?",
                "wrist": "did not move (0.0 degrees seen): is it limp, and is servo 4 its servo?",
                "gripper": "did not move (0.0 degrees seen): is it limp, and is servo 5 its"
                " servo?",
            },
        )

    def test_steps_left_out_are_named(self):
        self.assertEqual(self.cal.problems()["base"], "no range seen: sample() while it is moved")
        with self.assertRaises(ValueError):
            self.cal.nudge()  # no rest pose to nudge from
        self.cal.sample(but(REST, base=100))
        self.cal.sample(but(REST, base=900))
        self.assertEqual(self.cal.problems()["base"], "no rest pose read: rest() first")
        self.cal.rest(REST)
        self.assertEqual(self.cal.problems()["base"], "no nudge read: nudge() once it is nudged")

    def test_what_it_is_given_is_checked(self):
        for ids, kinds in (
            ([1, 2], None),  # not a dict
            ({"base": 1}, {"gripper": bm.PWM_180}),  # a kind for no joint
            ({"base": 1}, {"base": "SERVO"}),  # no such kind
            ({"base": 1, "elbow": 1}, None),  # one servo, two joints
            ({"base": 256}, None),
        ):
            error = raised(bc.Calibration, self.bus, ids, kinds)
            self.assertTrue(isinstance(error, (TypeError, ValueError)), (ids, kinds))
        self.assertEqual(self.w.frames_total, 0)  # nothing sent


class File(unittest.TestCase):
    # save() writes what Robot.load() reads, and busservo_arm's links; refusals first.

    def setUp(self):
        self.w, self.bus = world()
        self.cal = bc.Calibration(self.bus, IDS)
        self.dir = scratch("calibrate")
        os.mkdir(self.dir)
        self.path = self.dir + "/robot.json"

    def tearDown(self):
        sh("rm -rf " + self.dir)

    def read(self):
        with open(self.path) as f:
            return f.read()

    def test_the_file_round_trips(self):
        calibrate(self.w, self.cal)
        links = {"base_height": 70, "upper_arm": 105, "forearm": 98.5, "hand": 60}
        robot = self.cal.save(self.path, links)
        saved = json.loads(self.read())
        self.assertEqual(sorted(saved), ["joints", "links"])
        self.assertEqual(saved["links"], links)
        self.assertEqual(sorted(saved["joints"]), sorted(IDS))
        loaded = bm.Robot.load(self.bus, self.path)
        for name in IDS:
            self.assertEqual(loaded.joints[name].config(), robot.joints[name].config(), name)
            self.assertEqual(saved["joints"][name], robot.joints[name].config(), name)
        self.assertEqual(loaded.names, robot.names)

    def test_without_links_the_file_is_what_robot_save_writes(self):
        calibrate(self.w, self.cal)
        robot = self.cal.save(self.path)
        mine = json.loads(self.read())
        robot.save(self.path)
        self.assertEqual(mine, json.loads(self.read()))

    def test_calibrating_again_keeps_the_links_measured_before(self):
        # The arm's links were measured with a ruler and saved once; the joints calibrated
        # again (a servo replaced) leave them, and what else the file holds, as they were.
        calibrate(self.w, self.cal)
        links = {"base_height": 70, "upper_arm": 105, "forearm": 98.5, "hand": 60}
        self.cal.save(self.path, links)
        saved = json.loads(self.read())
        saved["note"] = "the blue arm"
        with open(self.path, "w") as f:
            json.dump(saved, f)
        cal = bc.Calibration(self.bus, IDS)
        calibrate(self.w, cal)
        cal.save(self.path)
        again = json.loads(self.read())
        self.assertEqual((again["links"], again["note"]), (links, "the blue arm"))
        self.assertEqual(sorted(again["joints"]), sorted(IDS))

    def test_calibrating_again_keeps_a_dps_a_person_set_and_a_programs_cap(self):
        # A person slowed the base in the file (its "dps": 20); the joints calibrated
        # again keep it (broken until issue 41: saved as null, the base as fast as asked).
        # A program's cap (the panel's 30 degrees/s) holds over the robot save() returns,
        # and is not written: the file is the arm's, the cap the program's.
        calibrate(self.w, self.cal)
        self.cal.save(self.path)
        saved = json.loads(self.read())
        self.assertEqual({saved["joints"][name]["dps"] for name in IDS}, {None})
        saved["joints"]["base"]["dps"] = 20
        with open(self.path, "w") as f:
            json.dump(saved, f)
        cal = bc.Calibration(self.bus, IDS)
        calibrate(self.w, cal)
        robot = cal.save(self.path, dps=30)
        again = json.loads(self.read())["joints"]
        for name in IDS:
            self.assertEqual(again[name]["dps"], 20 if name == "base" else None, name)
            self.assertEqual(robot.joints[name].dps, 20 if name == "base" else 30, name)
        self.assertEqual(cal.save(self.path).joints["shoulder"].dps, None)
        self.assertEqual(cal.save(self.path, dps=10).joints["base"].dps, 10)

    def test_the_default_path_is_the_calibration_every_example_loads(self):
        calibrate(self.w, self.cal)
        default = bm.CALIBRATION
        self.assertEqual(default, "robot.json")
        bm.CALIBRATION = self.path  # here, not in the folder the tests run from
        try:
            self.cal.save()
        finally:
            bm.CALIBRATION = default
        self.assertEqual(sorted(bm.Robot.load(self.bus, self.path).names), sorted(IDS))

    def test_what_it_cannot_trust_leaves_the_file_as_it_was(self):
        with open(self.path, "w") as f:
            f.write("the calibration before")
        calibrate(self.w, self.cal, nudged=but(NUDGED, base=520))
        with self.assertRaises(ValueError):
            self.cal.save(self.path)
        for links in (
            {"base_height": 70, "upper_arm": 105, "forearm": 98},  # no hand
            {"base_height": 70, "upper_arm": 105, "forearm": 98, "hand": -1},
            {"base_height": 70, "upper_arm": "105", "forearm": 98, "hand": 60},
            {"base_height": 70, "upper_arm": 105, "forearm": 98, "hand": 60, "claw": 20},
            [70, 105, 98, 60],
            # What Arm.load() would refuse is refused here: one check of the links.
            {"base_height": 70, "upper_arm": 0, "forearm": 98, "hand": 60},
            {"base_height": 70, "upper_arm": 105, "forearm": 0, "hand": 60},
        ):
            cal = bc.Calibration(self.bus, IDS)
            calibrate(self.w, cal)
            with self.assertRaises((TypeError, ValueError)):
                cal.save(self.path, links)
        self.assertEqual(self.read(), "the calibration before")


class Picture(unittest.TestCase):
    # docs/calibrate-rest-pose.svg, the rest pose the example asks for: well-formed, shown on
    # docs/calibrate.md, naming every joint and link, and it renders (CPython's XML parser,
    # and resvg, which tests/run.sh installs into .venv/; without resvg that part skips).
    SVG = "docs/calibrate-rest-pose.svg"

    def test_the_rest_pose_is_drawn_with_every_joint_and_link(self):
        check = (
            "import sys, xml.etree.ElementTree as E; r = E.parse(sys.argv[1]).getroot(); "
            "print(r.tag, r.get('width'), r.get('height'))"
        )
        ok, out = sh('.venv/bin/python -c "%s" %s' % (check, self.SVG))
        self.assertEqual(out.split(), ["{http://www.w3.org/2000/svg}svg", "800", "500"], out)
        with open(self.SVG) as f:
            text = f.read()
        for name in tuple(IDS) + ("roll",) + busservo_arm.LINKS:
            self.assertIn(">%s<" % name, text)
        with open("docs/calibrate.md") as f:
            self.assertIn("](calibrate-rest-pose.svg)", f.read())
        png = scratch("rest-pose") + ".png"
        try:
            ok, out = sh(".venv/bin/python tests/render_svg.py %s %s" % (self.SVG, png))
        finally:
            sh("rm -f " + png)
        if out.startswith("no renderer"):
            print("\n*** SKIPPED: %s: %s (tests/run.sh installs it) ***" % (self.SVG, out.strip()))
            raise unittest.SkipTest(out.strip())
        self.assertTrue(ok, out)
        self.assertTrue(out.startswith("800x500 colours="), out)


# A board.py for the example: the simulated controller, each command it takes logged as a
# line "CMD PARAMS..." (decimal bytes), and with PERSON, a person's hands at it. They hold the
# rest pose once the joints go limp; at each positions read after the first (the rest pose's)
# they sweep every joint a step, then nudge them. Their pose changes as the example reads it,
# so what it sees does not hang on how fast keys come.
BOARD = """import busservo_sim
from busservo import CMD_MULT_SERVO_POS_READ, CMD_MULT_SERVO_UNLOAD

PERSON = %r
REST = %r
ENDS = %r
NUDGED = %r


class Board(busservo_sim.SimController):
    reads = -1  # positions reads since the joints went limp
    presses = 0  # of the button (BUTTON, below)

    def _do(self, cmd, params):
        with open("log", "a") as f:
            f.write(" ".join(str(b) for b in bytes([cmd]) + params) + "\\n")
        super()._do(cmd, params)
        if not PERSON:
            return
        if cmd == CMD_MULT_SERVO_UNLOAD and self.reads < 0:
            self.reads = 0
            pose = REST
        elif cmd == CMD_MULT_SERVO_POS_READ and self.reads >= 0:
            self.reads += 1
            k = self.reads - 1  # the sweep's step, 0..10, then the nudge
            if k > 10:
                pose = NUDGED
            else:
                pose = {i: a + (b - a) * k // 10 for i, (a, b) in ENDS.items()}
        else:
            return
        for servo_id, position in pose.items():
            self.turn(servo_id, position)


board = Board()


def uart():
    return board
"""

# With BOARD, a board.py that offers button(), as boards/esp32.py and boards/rp2.py do. The
# person presses it (a short press: each value() call is one look) at each step once done:
# at once for the rest pose, once the example has read the whole sweep and the nudge for the
# range, at once for the nudge and the home.
BUTTON = """

class Button:
    down = False

    def value(self):
        if self.down:  # let go at the next look
            self.down = False
            board.presses += 1
        elif board.presses != 1 or board.reads >= 13:
            self.down = True
        return 0 if self.down else 1


pin = Button()


def button():
    return pin
"""


# As BUTTON, but the person holds the fourth press, the home's, for 1.5 s: no.
HELD_AT_HOME = """

class Button:
    held = 0  # looks it is held down for yet

    def value(self):
        if self.held:
            self.held -= 1
            if not self.held:  # let go
                board.presses += 1
        elif board.presses != 1 or board.reads >= 13:
            self.held = 150 if board.presses == 3 else 1  # a look each 10 ms
        return 0 if self.held else 1


pin = Button()


def button():
    return pin
"""


# What the example shows once the person has swept every joint, and nudged them.
SEEN = "base 177, shoulder 144, elbow 170, wrist 168, gripper 96"
NUDGE = "base +11, shoulder -11, elbow +10, wrist -12, gripper +12"


class Example(unittest.TestCase):
    # examples/calibrate.py on the unix port at a terminal: tests/typist.py types the keys,
    # once the example shows what the person waits for. In a folder of its own, where it
    # saves robot.json, with a board.py (so not the simulator: it asks) and the example
    # opted in, as a maker who checked the arm sets it.

    def setUp(self):
        self.dir = scratch("calibrate-example")
        os.mkdir(self.dir)
        with open("examples/calibrate.py") as f:
            text = f.read()
        opt_in = "I_HAVE_CHECKED_MY_ROBOT = False"
        self.assertIn("\n" + opt_in + "\n", text)
        self.write("calibrate.py", text.replace(opt_in, "I_HAVE_CHECKED_MY_ROBOT = True", 1))
        self.write("log", "")

    def tearDown(self):
        sh("rm -rf " + self.dir)

    def write(self, name, text):
        with open("%s/%s" % (self.dir, name), "w") as f:
            f.write(text)

    def run_typed(self, person, keys):
        """Run the example with a board.py (with a person's hands, or none) and keys
        [(text to wait for, keys to type)]: (ok, what it printed, the commands taken)."""
        self.write("board.py", BOARD % (person, REST, ENDS, NUDGED))
        typed = " ".join("'%s' '%s'" % pair for pair in keys)
        root = os.getcwd()
        ok, out = sh(
            "cd %s && %s/.venv/bin/python %s/tests/typist.py 30 %s -- sh %s/boards/unix.sh "
            "calibrate.py" % (self.dir, root, root, typed, root)
        )
        with open(self.dir + "/log") as f:
            taken = [[int(x) for x in line.split()] for line in f.read().split("\n") if line]
        return ok, out, taken

    def test_the_header_says_how_to_run_it_at_a_boards_repl(self):
        with open("examples/calibrate.py") as f:
            header = [line for line in f if line.startswith("#   mpremote ")]
        self.assertEqual(
            [line.split("  ")[1].strip() for line in header],
            [
                "mpremote mip install lib/busservo_calibrate.json",
                "mpremote cp examples/calibrate.py :calibrate.py",
                "mpremote repl",
            ],
        )
        self.assertIn("then type: import calibrate", header[2])

    def test_a_maker_calibrates_with_the_keys_and_homes_slowly(self):
        ok, out, taken = self.run_typed(
            True,
            (
                ("1. hold the arm in its rest pose", "\\r"),
                ("range seen, degrees: " + SEEN, "\\r"),
                ("nudged from the rest pose, degrees: " + NUDGE, "\\r"),
                ("or Enter to leave them out:", "70 105 98 150\\r"),
                ("Enter alone: no):", "y\\r"),
                ("home: ", ""),
            ),
        )
        self.assertTrue(ok, out)
        for line in (
            "saved robot.json:",
            "  base: servo 1, trim 2.9, direction +1, limits -86.3..85.3 degrees",
            "  shoulder: servo 2, trim -2.9, direction -1, limits -71.9..66.1 degrees",
            "  gripper: servo 5, trim -48.0, direction +1, limits 3.0..93.0 degrees",
            "home: base 0.0, shoulder 0.0, elbow 0.0, wrist 0.0, gripper 3.1 degrees",
        ):
            self.assertIn(line, out)
        with open(self.dir + "/robot.json") as f:
            saved = json.loads(f.read())
        self.assertEqual(
            saved["links"], {"base_height": 70, "upper_arm": 105, "forearm": 98, "hand": 150}
        )
        robot = bm.Robot.load(busservo.BusServo(SimController()), self.dir + "/robot.json")
        self.assertEqual(robot.names, ["base", "shoulder", "elbow", "wrist", "gripper"])
        # Under power only once the person said y: one move, home, no faster than 30
        # degrees/s (125 positions a second).
        cmds = [cmd[0] for cmd in taken]
        moves = [cmd for cmd in taken if cmd[0] == MOVE]
        self.assertEqual(len(moves), 1)
        self.assertEqual(cmds.index(MOVE), len(cmds) - 2)  # then where() reads "home: "
        self.assertEqual(cmds.index(CMD_MULT_SERVO_UNLOAD), 1)  # after "the servos are at"
        ms = moves[0][2] | moves[0][3] << 8
        for k in range(4, len(moves[0]), 3):
            servo_id, position = moves[0][k], moves[0][k + 1] | moves[0][k + 2] << 8
            self.assertTrue(abs(position - NUDGED[servo_id]) <= ms * 125 // 1000 + 1, moves)

    def test_what_it_cannot_trust_is_refused_by_name_and_nothing_moves(self):
        # No one turns the servos.
        ok, out, taken = self.run_typed(
            False,
            (
                ("1. hold the arm in its rest pose", "\\r"),
                ("range seen, degrees: base 0, ", "\\r"),
                ("nudged from the rest pose, degrees: base +0", "\\r"),
            ),
        )
        self.assertTrue(ok, out)
        for name, servo_id in IDS.items():
            self.assertIn(
                "refused: %s: did not move (0.0 degrees seen): is it limp, and is servo %d its"
                " servo?" % (name, servo_id),
                out,
            )
        self.assertIn("nothing saved; the joints stay limp: calibrate again", out)
        self.assertFalse("robot.json" in os.listdir(self.dir))
        self.assertEqual(
            sorted(set(cmd[0] for cmd in taken)), [CMD_MULT_SERVO_UNLOAD, CMD_MULT_SERVO_POS_READ]
        )

    def test_with_the_boards_button_no_keys_are_needed(self):
        # As `mpremote run` would: nothing comes from the console at all.
        self.write("board.py", BOARD % (True, REST, ENDS, NUDGED) + BUTTON)
        ok, out = sh(
            "cd %s && sh %s/boards/unix.sh calibrate.py </dev/null" % (self.dir, os.getcwd())
        )
        self.assertTrue(ok, out)
        for line in (
            "1. hold the arm in its rest pose (docs/calibrate.md), then press the button\n",
            "  range seen, degrees: " + SEEN,
            "saved robot.json:",
            "home now, at 30 degrees/s? a press: yes; held 1 s: no\n",
            "home: base 0.0, shoulder 0.0, elbow 0.0, wrist 0.0, gripper 3.1 degrees",
        ):
            self.assertIn(line, out)
        with open(self.dir + "/robot.json") as f:
            self.assertFalse("links" in json.loads(f.read()))  # no keys: no links

    def test_with_the_boards_button_held_1_s_there_is_no_home(self):
        self.write("board.py", BOARD % (True, REST, ENDS, NUDGED) + HELD_AT_HOME)
        ok, out = sh(
            "cd %s && sh %s/boards/unix.sh calibrate.py </dev/null" % (self.dir, os.getcwd())
        )
        self.assertTrue(ok, out)
        self.assertIn("saved robot.json:", out)
        self.assertIn("no home: the joints stay limp", out)
        with open(self.dir + "/log") as f:
            taken = [int(line.split()[0]) for line in f.read().split("\n") if line]
        self.assertFalse(MOVE in taken, taken)

    def test_no_home_unless_the_person_says_y(self):
        ok, out, taken = self.run_typed(
            True,
            (
                ("1. hold the arm in its rest pose", "\\r"),
                (SEEN, "\\r"),
                (NUDGE, "\\r"),
                ("or Enter to leave them out:", "\\r"),
                ("Enter alone: no):", "\\r"),
            ),
        )
        self.assertTrue(ok, out)
        self.assertIn("no home: the joints stay limp", out)
        with open(self.dir + "/robot.json") as f:
            self.assertFalse("links" in json.loads(f.read()))
        self.assertFalse(MOVE in [cmd[0] for cmd in taken])


if __name__ == "__main__":
    unittest.main()
