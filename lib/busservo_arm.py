# busservo_arm: a desktop arm in millimetres, on busservo_motion.Robot.
#
#   import busservo_arm
#   arm = busservo_arm.Arm(robot, {"base_height": 70, "upper_arm": 105, "forearm": 98,
#                                  "hand": 150})
#   arm.move_to(150, 0, 40, ms=1000)     # the tool point to x, y, z mm, the hand down
#   arm.where()                          # (x, y, z, pitch), read now
#   line = arm.line_to(120, 80, 30, mm_s=50)   # line.step() from a loop, or await line
#
# The geometry (docs/arm.md has the picture): a base that turns, then a shoulder, an elbow and
# a wrist that tilt in one vertical plane. x is forward when the base is at 0, y to the left,
# z up, the origin on the base's axis at the table. base positive turns counter-clockwise seen
# from above. shoulder 0 holds the upper arm vertical; shoulder, elbow and wrist positive all
# tilt forward and down; elbow 0 and wrist 0 are straight in line with the link before. pitch
# is the hand's angle from the horizontal: 0 straight out, -90 straight down. The joints'
# degrees are busservo_motion's: calibrate each joint's direction and trim to these.
#
# Floats are heap objects on most ports: a solve allocates. A line solves its points when it is
# made (one every 2 mm); its step() goes straight in the joints between them, only when the wire
# can take a frame, and streams through one dict made in Arm().
import math
import time
from array import array

import busservo_motion

try:
    import micropython  # noqa: F401 (on a board; CPython has none)

    _awaitable = None
except ImportError:  # CPython, on a computer: busservo_cpython gives what it lacks
    from busservo_cpython import awaitable as _awaitable
    from busservo_cpython import time

JOINTS = ("base", "shoulder", "elbow", "wrist")
LINKS = ("base_height", "upper_arm", "forearm", "hand")

_RAD = math.pi / 180
_DEG = 180 / math.pi
_MS_MAX = 65535  # a move's time on the wire: 16 bits
_SCAN = 2  # degrees between the pitches tried when none is given
_HALVE = 6  # then halved this often: to 1/32 degree
_HAIR = 0.001  # degrees inside the reach's edge
_EDGE_MM = 0.01  # reach() puts the wrist this far inside the reach's edge
_CHECK_MM = 2  # a line is checked every this many mm (and degrees of pitch)
_CHECKS_MAX = 500
_DPS = 0.9  # a line plans a joint's speed at most this share of its dps
_LATE_MS = 100  # a line's time moves on at most this much an update: a late loop slows it

_number = busservo_motion.number  # a finite number in a range, or raise naming it
_SOLVE = object()  # move_to(..., ms=_SOLVE): pose()'s solve alone, nothing sent
# One lookup rather than two (math, then its function): the solve calls them often.
_atan2 = math.atan2
_sqrt = math.sqrt
_acos = math.acos
_cos = math.cos
_sin = math.sin
_INF = float("inf")
_NINF = float("-inf")
_type = type
_int = int
_float = float
_next = next


def check_links(links):
    """{name: mm} of the four LINKS, each a number in 0..10000 mm, upper_arm and forearm more
    than 0 (the one check of an arm's links: busservo_calibrate and the panel use it), or
    TypeError or ValueError naming what is wrong."""
    if _type(links) is not dict:
        raise TypeError("links must be a dict {name: mm}, got %r" % (links,))
    for name in links:
        if name not in LINKS:
            raise ValueError("links: no link %r: the links are %s" % (name, ", ".join(LINKS)))
    for name in LINKS:
        if name not in links:
            raise ValueError("links: %r is missing (the links are %s)" % (name, ", ".join(LINKS)))
        _number("links[%r]" % name, links[name], 0, 10000)
    for name in ("upper_arm", "forearm"):
        if not links[name]:
            raise ValueError("links[%r] must be more than 0 mm, got 0" % name)
    return {name: links[name] for name in LINKS}


def _wrap(degrees):
    # The same angle in -180..180.
    while degrees > 180:
        degrees -= 360
    while degrees <= -180:
        degrees += 360
    return degrees


class Arm:
    def __init__(self, robot, links, elbow_up=True):
        if not isinstance(robot, busservo_motion.Robot):
            raise TypeError("robot must be a busservo_motion.Robot, got %r" % (robot,))
        missing = [name for name in JOINTS if name not in robot.joints]
        if missing:
            raise ValueError(
                "an arm needs joints %s: no %s among %s"
                % (", ".join(JOINTS), ", ".join(missing), ", ".join(robot.names))
            )
        links = self.links = check_links(links)
        self.robot = robot
        self.elbow_up = bool(elbow_up)
        self._b = float(links["base_height"])
        self._u = u = float(links["upper_arm"])
        self._f = f = float(links["forearm"])
        self._h = float(links["hand"])
        # Worked out once, for the solve: the law of cosines' terms.
        self._uf2 = u * u + f * f
        self._2uf = 2 * u * f
        self._joints = [robot.joints[name] for name in JOINTS]
        self._at = None  # [base, shoulder, elbow, wrist]: degrees last sent or read
        self._pose = {name: 0.0 for name in JOINTS}  # what a line streams, made once
        # A solve's result: the plane's angles, or why not (a joint's index, or -1 for the
        # reach, the value, how far beyond, and the limits it is beyond).
        self._a = self._s = self._e = self._w = 0.0
        self._hand_pitch = None  # the pitch the hand's reach in the plane is worked out for
        self._hand_r = self._hand_z = 0.0
        self._target = {name: 0.0 for name in JOINTS}  # what move_to() moves to, made once
        self._why = None
        self._worst = None  # the least bad failure of a scan of pitches, and its pitch
        self._why_pitch = 0
        # move_to()'s arguments, and what it raised, for _moves.
        self._in_x = self._in_y = self._in_z = self._in_pitch = self._in_ms = None
        self._in_mm_s = self._err = None
        self._moves = self._mover()

    # Calibration.

    @staticmethod
    def load(bus_or_robot, path=None, elbow_up=True):
        """The Arm whose links save() wrote to path, on a Robot of the joints saved there (on
        bus), or on the robot given."""
        path = path or busservo_motion.CALIBRATION
        robot = bus_or_robot
        if not isinstance(robot, busservo_motion.Robot):
            robot = busservo_motion.Robot.load(bus_or_robot, path)
        links = busservo_motion.load_json(path, "links", "Arm.save()")
        if _type(links) is not dict:
            raise ValueError("%s: links must be {name: mm}, got %r" % (path, links))
        try:
            return Arm(robot, links, elbow_up)
        except (TypeError, ValueError) as e:
            raise ValueError("%s: %s" % (path, e))

    def save(self, path=None):
        """Write the joints' calibration and the links to path (default
        busservo_motion.CALIBRATION) as JSON, keeping what else the file holds (Robot.load()
        and Arm.load() read it)."""
        self.robot.save(path or busservo_motion.CALIBRATION, links=dict(self.links))

    # The geometry.

    def point(self, pose):
        """(x, y, z, pitch) of the tool point at pose {name: degrees} (the four joints'):
        the forward kinematics."""
        for name in JOINTS:
            if name not in pose:
                raise ValueError("pose has no %r: it needs %s" % (name, ", ".join(JOINTS)))
            _number("pose[%r]" % name, pose[name])
        return self._point(pose["base"], pose["shoulder"], pose["elbow"], pose["wrist"])

    def _point(self, base, shoulder, elbow, wrist):
        a = shoulder * _RAD
        b = a + elbow * _RAD
        c = b + wrist * _RAD
        r = self._u * _sin(a) + self._f * _sin(b) + self._h * _sin(c)
        z = self._b + self._u * _cos(a) + self._f * _cos(b) + self._h * _cos(c)
        base *= _RAD
        return r * _cos(base), r * _sin(base), z, _wrap(90 - c * _DEG)

    def pose(self, x, y, z, pitch=None):
        """{name: degrees} of the four joints that put the tool point at x, y, z mm with the
        hand at pitch degrees (None: the reachable pitch nearest -90): the inverse
        kinematics. Raises ValueError naming the point, the reach and the limiting joint."""
        self.move_to(x, y, z, pitch, _SOLVE)
        return {"base": self._a, "shoulder": self._s, "elbow": self._e, "wrist": self._w}

    def reach(self, x, y, z, pitch):
        """The tool point nearest x, y, z mm (with the hand at pitch degrees) that the wrist
        can reach: x, y, z itself if it can, else the one whose wrist is at the reach's edge
        (a hair inside), on the line from the shoulder's axis. (x, y, z)."""
        base = _atan2(y, x) if x or y else (self._at[0] if self._at else 0.0) * _RAD
        p = pitch * _RAD
        hr = self._h * _cos(p)  # the hand, in the arm's plane
        hz = self._h * _sin(p)
        wr = _sqrt(x * x + y * y) - hr  # the wrist, from the shoulder's axis
        wz = z - self._b - hz
        d = _sqrt(wr * wr + wz * wz)
        far = self._u + self._f - _EDGE_MM
        near = abs(self._u - self._f) + _EDGE_MM
        k = far / d if d > far else near / d if 0 < d < near else 1.0
        r = wr * k + hr
        return r * _cos(base), r * _sin(base), wz * k + hz + self._b

    def _plane(self, r, zz, pitch):
        # Solve in the arm's plane for the tool point r mm out from the base's axis, zz mm
        # above the shoulder's, at pitch: self._s, _e, _w, and True; or False (past the reach
        # or a joint's limits), and why in self._why.
        # Floats are heap objects: each float operation here allocates, so the terms that do
        # not change are worked out once (Arm()), and no tuple is built unless it fails.
        if pitch != self._hand_pitch:  # the hand, in the plane: the same for the same pitch
            p = pitch * _RAD
            self._hand_r = self._h * _cos(p)
            self._hand_z = self._h * _sin(p)
            self._hand_pitch = pitch
        wr = r - self._hand_r
        wz = zz - self._hand_z
        f = self._f
        d2 = wr * wr + wz * wz
        c = (d2 - self._uf2) / self._2uf
        if c > 1 or c < -1:
            u = self._u
            d = _sqrt(d2)
            if c > 1:
                self._why = (-1, d, d - u - f, u + f)
            else:
                self._why = (-1, d, abs(u - f) - d, abs(u - f))
            return False
        # The elbow's angle e has cos(e) = c, elbow up 0..180 degrees.
        e = _acos(c)
        if not self.elbow_up:
            e = -e
        s = (_atan2(wr, wz) - _atan2(f * _sin(e), self._u + f * c)) * _DEG
        if s > 180:  # the difference of two angles in -180..180: one turn at most
            s -= 360
        elif s <= -180:
            s += 360
        self._s = s
        self._e = e = e * _DEG
        w = 90 - pitch - s - e
        if w > 180 or w <= -180:
            w = _wrap(w)
        self._w = w
        joints = self._joints
        joint = joints[1]
        if s < joint.lo or s > joint.hi:
            return self._beyond(1, s)
        joint = joints[2]
        if e < joint.lo or e > joint.hi:
            return self._beyond(2, e)
        joint = joints[3]
        if w < joint.lo or w > joint.hi:
            return self._beyond(3, w)
        return True

    def _beyond(self, i, value):
        # False, and why in self._why: joint i would be at value, beyond its limits.
        joint = self._joints[i]
        beyond = joint.lo - value if value < joint.lo else value - joint.hi
        self._why = (i, value, beyond, joint)
        return False

    def _pitch(self, r, zz):
        # The pitch nearest -90 at which the plane's solve succeeds (self._s, _e, _w are its
        # angles), or None, with the least bad failure in self._why and its pitch in
        # self._why_pitch.
        self._worst = None
        if self._tried(r, zz, -90):
            return -90
        # The wrist is the hand's length back from the tool point: how far it is from the
        # shoulder's axis depends on the pitch's angle from phi, the tool point's direction
        # from that axis. It is in reach where that angle is lo..hi degrees either way.
        h = self._h
        d = _sqrt(r * r + zz * zz)
        phi = -90.0
        lo = 0.0
        hi = 180.0
        if h * d > 1e-9:
            phi = _atan2(zz, r) * _DEG
            far = self._u + self._f
            near = abs(self._u - self._f)
            cos_hi = (d * d + h * h - far * far) / (2 * h * d)
            cos_lo = (d * d + h * h - near * near) / (2 * h * d)
            if cos_hi > 1 or cos_lo < -1:  # at no pitch: say so where it comes nearest
                self._tried(r, zz, phi if cos_hi > 1 else _wrap(phi + 180))
                self._why, self._why_pitch = self._worst
                return None
            if cos_hi > -1:
                hi = _acos(cos_hi) * _DEG
            if cos_lo < 1:
                lo = _acos(cos_lo) * _DEG
            # -90 failed: if it is out of reach, the edge of the reach nearest it (a hair
            # inside) is the answer, unless a joint's limit is in the way there too.
            off = _wrap(-90 - phi)
            edge = None
            if abs(off) > hi:
                edge = hi - _HAIR
            elif abs(off) < lo:
                edge = lo + _HAIR
            if edge is not None:
                pitch = phi + edge if off > 0 else phi - edge
                if self._tried(r, zz, pitch):
                    return pitch
        # A joint's limit is in the way: try pitches further and further from -90, within
        # the reach, then halve the step back towards -90 to find the limit's edge.
        found = None
        k = _SCAN
        while k <= 180 and found is None:
            for pitch in (-90 - k, -90 + k):
                if not lo <= abs(_wrap(pitch - phi)) <= hi:
                    continue
                if self._tried(r, zz, pitch):
                    good = pitch
                    bad = pitch + _SCAN if pitch < -90 else pitch - _SCAN
                    for _ in range(_HALVE):
                        mid = (good + bad) / 2
                        if self._tried(r, zz, mid):
                            good = mid
                        else:
                            bad = mid
                    if found is None or abs(good + 90) < abs(found + 90):
                        found = good
            k += _SCAN
        if found is None:
            if self._worst is None:  # none tried: the reach is narrower than the steps
                self._tried(r, zz, phi)
            self._why, self._why_pitch = self._worst
            return None
        self._plane(r, zz, found)
        return found

    def _tried(self, r, zz, pitch):
        # _plane(), keeping the least bad failure seen.
        if self._plane(r, zz, pitch):
            return True
        if self._worst is None or self._why[2] < self._worst[0][2]:
            self._worst = (self._why, pitch)
        return False

    def _refusal(self, x, y, z, pitch):
        # The message of a point refused: the point, the reach, the limiting joint.
        where = "(x, y, z) = (%.1f, %.1f, %.1f) mm" % (x, y, z)
        if pitch is None:
            pitch = self._why_pitch
            where += ": no pitch reaches it within the limits; the nearest, pitch %.1f" % pitch
        else:
            where += ", pitch %.1f" % pitch
        i, value, beyond, limit = self._why
        if i < 0:
            if value > limit:
                return (
                    "%s: out of reach: the wrist would be %.1f mm from the shoulder's axis, and"
                    " the elbow straight reaches %.1f mm" % (where, value, limit)
                )
            return (
                "%s: out of reach: the wrist would be %.1f mm from the shoulder's axis, and"
                " the elbow folded reaches no closer than %.1f mm" % (where, value, limit)
            )
        return "%s: the %s would be at %.1f degrees, beyond its limits %.1f..%.1f" % (
            where,
            JOINTS[i],
            value,
            limit.lo,
            limit.hi,
        )

    # Moves.

    def move_to(self, x, y, z, pitch=None, ms=None, mm_s=None):
        """Move the tool point to x, y, z mm with the hand at pitch (None: the reachable
        pitch nearest -90), in one frame for the four joints: within ms, or at mm_s for the
        tool point and the wrist (from where the arm last went, read first if not known).
        Return the move's ms."""
        # On MicroPython a call of a function whose arguments, locals and stack take more
        # than 11 words takes a heap block for them, and gives it back at its end: the next
        # call takes the same block, behind all the floats allocated since, and the first
        # float after it makes the allocator look through them all (its first fit starts
        # again at a block given back). On a heap of 200 KB that cost a move more than its
        # solve. So move_to() only hands its arguments to _moves, a generator made once in
        # Arm(), whose locals are kept from call to call, and raises what it raised.
        self._in_x = x
        self._in_y = y
        self._in_z = z
        self._in_pitch = pitch
        self._in_ms = ms
        self._in_mm_s = mm_s
        took = _next(self._moves)
        e = self._err
        if e is not None:
            self._err = None
            raise e
        return took

    def _mover(self):
        # move_to()'s work, a call a turn: the move's ms (None for pose(), ms _SOLVE: the
        # solve alone, the angles in self._a, the base, _s, _e and _w, nothing sent), or
        # None and what it raised in self._err. The checks are inline (a call costs more
        # than the check): _number() only to say what is wrong. The module's names it uses
        # are its locals, looked up once (the generator keeps them).
        solve, typ, int_, float_, ninf, inf = _SOLVE, _type, _int, _float, _NINF, _INF
        ms_max, atan2, sqrt, deg = _MS_MAX, _atan2, _sqrt, _DEG
        while True:
            took = None
            try:
                x = self._in_x
                y = self._in_y
                z = self._in_z
                pitch = self._in_pitch
                ms = self._in_ms
                mm_s = self._in_mm_s
                if ms is not solve:
                    if (ms is None) == (mm_s is None):
                        raise ValueError(
                            "give move_to() ms or mm_s (not both), got ms=%r mm_s=%r" % (ms, mm_s)
                        )
                    if ms is not None:
                        if typ(ms) is not int_:
                            raise TypeError("ms must be an int in 0..%d ms, got %r" % (ms_max, ms))
                        if not 0 <= ms <= ms_max:
                            raise ValueError("ms must be in 0..%d ms, got %r" % (ms_max, ms))
                    else:
                        _number("mm_s", mm_s, 0)
                        if not mm_s:
                            raise ValueError("mm_s must be more than 0 mm/s, got %r" % (mm_s,))
                t = typ(x)
                if t is not int_ and (t is not float_ or not ninf < x < inf):
                    _number("x", x)
                t = typ(y)
                if t is not int_ and (t is not float_ or not ninf < y < inf):
                    _number("y", y)
                t = typ(z)
                if t is not int_ and (t is not float_ or not ninf < z < inf):
                    _number("z", z)
                t = typ(pitch)
                if (
                    pitch is not None
                    and t is not int_
                    and (t is not float_ or not ninf < pitch < inf)
                ):
                    _number("pitch", pitch)
                # The base's angle towards x, y (checked), or where it is if x, y is on its
                # axis.
                if x or y:
                    base = atan2(y, x) * deg
                else:
                    base = self._at[0] if self._at else 0.0
                joint = self._joints[0]
                if base < joint.lo or base > joint.hi:
                    raise ValueError(
                        "(x, y, z) = (%.1f, %.1f, %.1f) mm: the base would be at %.1f degrees,"
                        " beyond its limits %.1f..%.1f" % (x, y, z, base, joint.lo, joint.hi)
                    )
                r = sqrt(x * x + y * y)
                zz = z - self._b
                if pitch is None:
                    pitch = self._pitch(r, zz)
                    if pitch is None:
                        raise ValueError(self._refusal(x, y, z, None))
                elif not self._plane(r, zz, pitch):
                    raise ValueError(self._refusal(x, y, z, pitch))
                self._a = base
                if ms is not solve:
                    pose = self._target
                    pose["base"] = base
                    pose["shoulder"] = s = self._s
                    pose["elbow"] = e = self._e
                    pose["wrist"] = w = self._w
                    if mm_s is not None:
                        ms = math.ceil(self._distance(pose) * 1000 / mm_s - 1e-6)  # (float error)
                        if ms > ms_max:
                            raise ValueError(
                                "the move would take %d ms, more than %d: move in steps, or"
                                " faster" % (ms, ms_max)
                            )
                    robot = self.robot
                    if robot.player:
                        robot.player.stop()
                    took = robot.move(pose, ms)
                    at = self._at
                    if at is None:
                        self._at = at = [0.0] * 4
                    at[0] = base
                    at[1] = s
                    at[2] = e
                    at[3] = w
            except BaseException as err:  # (Ctrl-C too: move_to() raises it)
                self._err = err
                if _awaitable:  # CPython: whoever catches it may clear its frames (as
                    self._moves = self._mover()  # unittest does), and so end this one
            yield took

    def _known(self):
        # The joints' degrees last sent or read; read now if none.
        if self._at is None:
            self.where()
        return self._at

    def _distance(self, pose):
        # How far the tool point and the wrist go, from where the arm is to pose: the more,
        # and a degree of the pitch counts as a mm, so that with a short hand (or none) the
        # pitch alone does not turn at once.
        at = self._known()
        x0, y0, z0, p0 = self._point(at[0], at[1], at[2], at[3])
        x1, y1, z1, p1 = self._point(pose["base"], pose["shoulder"], pose["elbow"], pose["wrist"])
        h = self._h
        tool = _sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2 + (z1 - z0) ** 2)
        # The wrist is the hand's length back from the tool point, along the hand.
        b0 = at[0] * _RAD
        b1 = pose["base"] * _RAD
        q0 = _cos(p0 * _RAD)
        q1 = _cos(p1 * _RAD)
        dx = (x1 - h * q1 * _cos(b1)) - (x0 - h * q0 * _cos(b0))
        dy = (y1 - h * q1 * _sin(b1)) - (y0 - h * q0 * _sin(b0))
        dz = (z1 - h * _sin(p1 * _RAD)) - (z0 - h * _sin(p0 * _RAD))
        return max(tool, _sqrt(dx * dx + dy * dy + dz * dz), abs(_wrap(p1 - p0)))

    def where(self, positions=None):
        """(x, y, z, pitch) of the tool point, from the joints' positions read now (a
        blocking query), or from positions {servo_id: position} read before (not
        blocking: Robot.where()), to 0.1 mm and 0.1 degree."""
        got = self.robot.where(JOINTS, positions)
        self._at = [got[name] for name in JOINTS]
        x, y, z, pitch = self._point(*self._at)
        return round(x, 1), round(y, 1), round(z, 1), round(pitch, 1)

    def line_to(self, x, y, z, pitch=None, mm_s=50):
        """A Line: the tool point along a straight line from where the arm last went (read
        first if not known) to x, y, z mm, at mm_s, the pitch turning evenly to pitch (None:
        the reachable pitch nearest -90 at the end). The whole line is checked first, and
        solved every 2 mm (8 bytes a point: 4 KB at most): a point on it the arm cannot reach
        raises ValueError naming it, and nothing is sent. Call the Line's step() from a
        loop, or await it."""
        return Line(self, x, y, z, pitch, mm_s)


class Line:
    def __init__(self, arm, x, y, z, pitch=None, mm_s=50):
        _number("mm_s", mm_s, 0)
        if not mm_s:
            raise ValueError("mm_s must be more than 0 mm/s, got %r" % (mm_s,))
        end = arm.pose(x, y, z, pitch)  # checks x, y, z and pitch
        at = arm._known()
        x0, y0, z0, p0 = arm._point(at[0], at[1], at[2], at[3])
        p1 = pitch
        if p1 is None:
            p1 = _wrap(90 - end["shoulder"] - end["elbow"] - end["wrist"])
        self.arm = arm
        self.robot = arm.robot
        self.start = (x0, y0, z0, p0)
        self.end = (x, y, z, p1)
        self.mm_s = mm_s
        # Check the line every _CHECK_MM of the wrist's way at most (the tool point's, and
        # the hand's length turning with the pitch: 2.6 mm a degree for a hand of 150 mm;
        # and degrees of pitch), and time it: mm_s for the tool point and the wrist, and no
        # joint faster than _DPS of its dps.
        dx, dy, dz, dp = x - x0, y - y0, z - z0, _wrap(p1 - p0)  # the short way round
        length = _sqrt(dx * dx + dy * dy + dz * dz)
        n = math.ceil(max(length + arm._h * abs(dp) * _RAD, abs(dp), 1) / _CHECK_MM)
        n = min(n, _CHECKS_MAX)
        self.ms = arm._distance(end) * 1000 / mm_s
        joints = arm._joints
        # The joints' degrees at each point checked, in hundredths (0.06 mm at the arm's full
        # reach), within their limits: a step goes straight in the joints between the two
        # points around it rather than solving (8 bytes a point, and 4 KB at most).
        points = array("h")
        # Point 0: where the arm is, each joint's angle within a turn (a servo may report a
        # position far out) and within its limits (as the robot would clamp it).
        before = [min(max(_wrap(at[i]), joints[i].lo), joints[i].hi) for i in range(4)]
        for k in range(n + 1):
            if k:
                u = k / n
                px, py, pz, pp = x0 + dx * u, y0 + dy * u, z0 + dz * u, p0 + dp * u
                try:
                    pose = arm.pose(px, py, pz, pp)
                except ValueError as e:
                    raise ValueError(
                        "the line from (%.1f, %.1f, %.1f) to (%.1f, %.1f, %.1f) mm leaves the"
                        " reach at %s" % (x0, y0, z0, x, y, z, e)
                    )
                now = [pose[name] for name in JOINTS]
            else:
                now = before
            for i in range(4):
                joint = joints[i]
                c = round(now[i] * 100)  # back within the limits if rounding took it past
                if c / 100 < joint.lo:
                    c += 1
                elif c / 100 > joint.hi:
                    c -= 1
                points.append(c)
                dps = joint.dps
                if dps:  # with a margin: the robot's stream rounds to whole positions
                    self.ms = max(self.ms, n * abs(now[i] - before[i]) * 1000 / (_DPS * dps))
            before = now
        self.ms = math.ceil(self.ms - 1e-6)
        self._points = points
        self._n = n
        self._last = end  # the last frame's degrees, exactly
        self.updates = 0  # frames of this line sent
        self.done = False
        self._t = -1  # the line's time at the last target streamed, in ms (-1: none yet)
        self._sent = 0  # ticks_ms then
        self._stepped = time.ticks_ms()
        robot = self.robot
        # The robot's stream(), looked up once, here (the bus is looked up each step: a
        # program may open its port again, and robot.step() uses it).
        self._steps = self._stepper(robot.stream)
        self._err = None  # what step() raised, for it to raise again
        if robot.player:
            robot.player.stop()
        robot.player = self  # robot.estop() stops it

    def step(self):
        """From the control loop: if the wire can take a frame, stream the point the line
        has reached (the joints straight between the two points around it, solved when the
        line was made) and send it with robot.step(). Never waits; works out nothing while
        the wire is busy. True if it sent."""
        if self.done:
            return False
        # The work is in _steps, a generator made once (Line()), as Arm.move_to()'s is.
        sent = _next(self._steps)
        e = self._err
        if e is not None:
            self._err = None
            raise e
        return sent

    def _stepper(self, stream):
        # step()'s work, a call a turn: True if it sent, or False (and what it raised in
        # self._err). What does not change along the line, and the module's names it uses,
        # are its locals, looked up once; the robot's stream() comes bound, from Line() (so
        # that nothing here raises outside the try below: that would end the generator, and
        # each later step() raise StopIteration).
        robot = self.robot
        arm = self.arm
        pose = arm._pose
        points = self._points
        n = self._n
        last = self._last
        late_ms = _LATE_MS
        while True:
            sent = False
            try:
                now = time.ticks_ms()
                since = time.ticks_diff(now, self._stepped)
                self._stepped = now
                frame = robot.frame_ms or 20  # a 4-servo frame at 9600 baud, until measured
                if robot.bus.wire_ms() <= (since if since < frame else frame):
                    # The line's time: a frame ahead at first, then as the clock goes, but at
                    # most _LATE_MS an update (a late loop slows the line, rather than
                    # cutting across).
                    t = self._t
                    if t < 0:
                        t = frame
                    else:
                        dt = time.ticks_diff(now, self._sent)
                        t += dt if dt < late_ms else late_ms
                    ms = self.ms
                    if t < ms:
                        # Between points k and k + 1, r / ms of the way, rounded to whole
                        # hundredths of a degree: ints, so that only the four degrees
                        # streamed are floats.
                        q = t * n
                        k = q // ms
                        r = 2 * (q - k * ms)
                        k *= 4
                        ms2 = 2 * ms
                        a = points[k]
                        pose["base"] = b = (a + ((points[k + 4] - a) * r + ms) // ms2) / 100
                        a = points[k + 1]
                        pose["shoulder"] = s = (a + ((points[k + 5] - a) * r + ms) // ms2) / 100
                        a = points[k + 2]
                        pose["elbow"] = e = (a + ((points[k + 6] - a) * r + ms) // ms2) / 100
                        a = points[k + 3]
                        pose["wrist"] = w = (a + ((points[k + 7] - a) * r + ms) // ms2) / 100
                    else:  # the end, exactly
                        pose["base"] = b = last["base"]
                        pose["shoulder"] = s = last["shoulder"]
                        pose["elbow"] = e = last["elbow"]
                        pose["wrist"] = w = last["wrist"]
                    stream(pose)
                    if robot.step():
                        self._t = t
                        self._sent = now
                        self.updates += 1
                        at = arm._at
                        at[0] = b
                        at[1] = s
                        at[2] = e
                        at[3] = w
                        if t >= ms:
                            self._end()
                        sent = True
            except BaseException as err:  # (Ctrl-C too: step() raises it)
                self._err = err
                if _awaitable:  # CPython: as in Arm._mover()
                    self._steps = self._stepper(stream)
            yield sent

    def stop(self):
        """End the line: the tool point stops at the last point sent. Nothing is sent, and
        targets streamed but not yet sent are dropped (robot.hold())."""
        if not self.done:
            self._end()
            self.robot.hold()

    def _end(self):
        self.done = True
        if self.robot.player is self:
            self.robot.player = None

    async def run(self, poll_ms=5):
        """Step to the end of the line, sleeping between frames: other tasks run meanwhile."""
        asyncio = busservo_motion.aio()
        while not self.done:
            self.step()
            if not self.done:
                wait = self.robot.bus.wire_ms()
                await asyncio.sleep_ms(min(poll_ms, wait) if wait else 1)

    def __await__(self):
        return self.run()

    __iter__ = __await__


if _awaitable:  # CPython: await wants an iterator, not the coroutine MicroPython takes
    _awaitable(Line)
