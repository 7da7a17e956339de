# busservo_calibrate: calibrate an arm by hand, once, on the motion layer. Every joint
# goes limp, and a person
# 1. holds the arm in its rest pose (every joint at its 0): each joint's trim;
# 2. moves each joint through the whole range it may safely use: its limits, MARGIN
#    degrees inside what was seen;
# 3. puts the arm back in its rest pose and nudges each joint a little in its positive
#    direction: its direction.
#
#   import busservo_calibrate as bc, busservo_motion as bm
#   cal = bc.Calibration(bus, {"base": 1, "shoulder": 2, "elbow": 3, "wrist": 4,
#                              "gripper": 5}, kinds={"gripper": bm.PWM_180})
#   cal.limp()
#   cal.rest()                  # step 1
#   cal.sample()                # step 2: again and again while the person sweeps
#   cal.nudge()                 # step 3: the last call counts
#   arm = cal.save("robot.json", links={"base_height": 70, "upper_arm": 105,
#                                       "forearm": 98, "hand": 60})
#
# Each step is one positions query (it blocks for a few tens of ms), or takes the
# positions a query made elsewhere brought ({servo_id: position} of cal.ids, as
# BusServo.read_positions() and AsyncBusServo.read_positions() give them), so a loop can
# drive it. robot() and save() refuse, naming each joint, what they cannot trust.
# Nothing here moves a servo: the example moves nothing until the person confirms a slow
# home() of the saved calibration.
#
# Positive directions (docs/calibrate.md): x forward when base is 0, y to the left, z
# up. base turns counter-clockwise seen from above; shoulder, elbow and wrist tilt
# forward and down (shoulder 0: the upper arm vertical; elbow 0 and wrist 0: in line with
# the link before); roll turns the hand clockwise seen from behind it; gripper opens.
import errno

import busservo_motion as bm

MARGIN = 3  # degrees kept inside the range seen, at each end
RANGE_MIN = 10  # degrees a joint's range must span
STILL = 2  # degrees seen under which a joint did not move (a hand's tremor, a read's noise)
NUDGE_MIN = 5  # degrees a nudge must go, from the rest pose, to tell the direction

_HALF = {bm.BUS: 120, bm.PWM_180: 90, bm.PWM_270: 135}  # each kind's degrees either side


class Calibration:
    def __init__(self, bus, ids, kinds=None):
        """ids: {joint name: servo_id}; kinds: {joint name: kind} for those that are not
        bus servos (bm.PWM_180, bm.PWM_270)."""
        if kinds is None:
            kinds = {}
        if type(ids) is not dict:
            raise TypeError("ids must be a dict {joint name: servo_id}, got %r" % (ids,))
        if type(kinds) is not dict:
            raise TypeError("kinds must be a dict {joint name: kind}, got %r" % (kinds,))
        for name in kinds:
            if name not in ids:
                raise ValueError("kinds names joint %r, which ids has not" % (name,))
        # A robot of the servos as they come, to let them go and to read them.
        joints = {}
        for name, servo_id in ids.items():
            joints[name] = bm.Joint(servo_id, kind=kinds.get(name, bm.BUS))
        self._robot = bm.Robot(bus, joints)
        self.bus = bus
        self.names = self._robot.names  # in servo id order
        self._joints = [joints[name] for name in self.names]
        self.ids = [joint.servo_id for joint in self._joints]
        n = len(self.names)
        # Each joint's degrees from its servo's centre, in the servo's own direction.
        self._rest = None  # at the rest pose
        self._lo = [None] * n  # the least and most seen in the sweep
        self._hi = [None] * n
        self._moved = None  # from the rest pose, at the last nudge()
        self.samples = 0  # sample() calls

    def limp(self):
        """Let every joint go limp, to be moved by hand (hold the arm: it falls)."""
        self._robot.limp()

    def _read(self, positions):
        # Each joint's degrees from its servo's centre, read now or from positions. A
        # servo that does not answer has none: OSError(ENODEV) naming its joint.
        if positions is None:
            got = self._robot.where()  # refuses a silent servo as the motion layer does
            return [got[name] for name in self.names]
        out = []
        for name, joint in zip(self.names, self._joints):
            if joint.servo_id not in positions:
                raise ValueError(
                    "positions has no servo %d (joint %r): read all of cal.ids"
                    % (joint.servo_id, name)
                )
            position = positions[joint.servo_id]
            if position is None:
                raise OSError(
                    errno.ENODEV,
                    "joint %r: servo %d does not answer (unpowered, its cable, or its id?)"
                    % (name, joint.servo_id),
                )
            out.append(round(joint.degrees(position), 1))
        return out

    def rest(self, positions=None):
        """Step 1: read the rest pose, each joint's 0. {name: degrees from its servo's
        centre}."""
        self._rest = self._read(positions)
        return dict(zip(self.names, self._rest))

    def sample(self, positions=None):
        """Step 2, again and again while the person sweeps each joint: widen each joint's
        range seen. {name: (least, most) degrees seen}."""
        now = self._read(positions)
        lo = self._lo
        hi = self._hi
        for i, d in enumerate(now):
            if lo[i] is None or d < lo[i]:
                lo[i] = d
            if hi[i] is None or d > hi[i]:
                hi[i] = d
        self.samples += 1
        return {name: (lo[i], hi[i]) for i, name in enumerate(self.names)}

    def nudge(self, positions=None):
        """Step 3, after rest(): read how far each joint has been nudged from its rest pose
        (the last call counts). {name: degrees, positive in its servo's own direction}."""
        if self._rest is None:
            raise ValueError("no rest pose read: rest() first")
        now = self._read(positions)
        self._moved = [round(now[i] - self._rest[i], 1) for i in range(len(now))]
        return dict(zip(self.names, self._moved))

    def problems(self):
        """{name: why} of each joint the steps so far cannot calibrate (none: {})."""
        return self._by_joint(self._problem)

    def unswept(self):
        """{name: why} of each joint whose range seen in step 2 is too small to calibrate
        (none: {}): the sweep is not done."""
        return self._by_joint(self._sweep_problem)

    def _by_joint(self, problem):
        # {name: why} of each joint i for which problem(i) says why.
        out = {}
        for i, name in enumerate(self.names):
            why = problem(i)
            if why:
                out[name] = why
        return out

    def _sweep_problem(self, i):
        # Why joint i's range seen cannot be calibrated, or None.
        joint = self._joints[i]
        lo = self._lo[i]
        hi = self._hi[i]
        if lo is None:
            return "no range seen: sample() while it is moved"
        span = hi - lo
        if span < STILL:
            why = "did not move (%.1f degrees seen): is it limp, and is servo %d its servo?"
            why %= (span, joint.servo_id)
            if joint.kind != bm.BUS:  # its three wires carry no angle back
                why += " (a PWM servo cannot tell the controller where a hand turned it)"
            return why
        if span < RANGE_MIN:
            why = "moved through %.1f degrees (%.1f..%.1f), under %d: move it through all its"
            return why % (span, lo, hi, RANGE_MIN) + " safe range"
        return None

    def _problem(self, i):
        # Why joint i cannot be calibrated, or None. Degrees here are from its servo's
        # centre, in the servo's own direction: what the person's hand did.
        why = self._sweep_problem(i)
        if why:
            return why
        joint = self._joints[i]
        lo = self._lo[i]
        hi = self._hi[i]
        if self._rest is None:
            return "no rest pose read: rest() first"
        rest = self._rest[i]
        if not lo - MARGIN <= rest <= hi + MARGIN:
            why = "its rest pose (%.1f degrees) is outside the range seen (%.1f..%.1f): hold"
            return why % (rest, lo, hi) + " the rest pose the picture shows, and sweep through it"
        if abs(rest) > _HALF[joint.kind]:
            why = "its rest pose is past its servo's end (%.1f degrees from the centre): turn"
            return why % rest + " its horn nearer the centre"
        if self._moved is None:
            return "no nudge read: nudge() once it is nudged"
        moved = self._moved[i]
        if abs(moved) < NUDGE_MIN:
            why = "nudged %.1f degrees from its rest pose: too little to tell its direction"
            return why % moved + " (%d or more)" % NUDGE_MIN
        return None

    def joints(self):
        """{name: bm.Joint} calibrated, or ValueError naming each joint that cannot be and
        why."""
        problems = self.problems()
        if problems:
            said = ["%s: %s" % (name, problems[name]) for name in self.names if name in problems]
            raise ValueError("cannot calibrate " + "; ".join(said))
        out = {}
        for i, name in enumerate(self.names):
            joint = self._joints[i]
            half = _HALF[joint.kind]
            trim = self._rest[i]
            direction = 1 if self._moved[i] > 0 else -1
            # The range seen in the joint's degrees, MARGIN inside at each end, within what
            # the servo reaches (a read just past its end, -3 of 0..1000, is beyond).
            a = direction * (self._lo[i] - trim)
            b = direction * (self._hi[i] - trim)
            low = max(round(min(a, b) + MARGIN, 1), -half - direction * trim)
            high = min(round(max(a, b) - MARGIN, 1), half - direction * trim)
            out[name] = bm.Joint(
                joint.servo_id, kind=joint.kind, direction=direction, trim=trim, limits=(low, high)
            )
        return out

    def robot(self, bus=None):
        """A bm.Robot of the calibrated joints, on bus (default: this calibration's), or
        ValueError naming each joint that cannot be calibrated and why."""
        return bm.Robot(self.bus if bus is None else bus, self.joints())

    def save(self, path=None, links=None, dps=None):
        """Write the calibration to path (default busservo_motion.CALIBRATION, robot.json)
        as Robot.load() reads it, with links {name: mm} if given (measured with a ruler, for
        busservo_arm, which checks them), keeping what else the file holds: links saved
        before, and a joint's dps a person set in it. Refuses as robot() does, before the
        file is touched. Returns the Robot, each joint at most dps degrees a second if given
        (a program's cap, as Robot.load() keeps it: not saved)."""
        joints = self.joints()
        more = {}
        if links is not None:
            from busservo_arm import check_links  # only with links: the arm is their owner

            more["links"] = check_links(links)
        if path is None:
            path = bm.CALIBRATION
        try:
            before = bm.Robot.load(None, path).joints
        except (OSError, ValueError, TypeError):
            before = {}  # no file yet, or not one of ours
        for name, joint in joints.items():
            kept = before.get(name)
            if kept and kept.dps:  # a calibration brings limits, never a faster joint
                settings = joint.config()
                settings["dps"] = kept.dps
                joints[name] = bm.Joint(**settings)
        bm.Robot(self.bus, joints).save(path, **more)  # the file's links kept
        return bm.Robot.load(self.bus, path, dps)
