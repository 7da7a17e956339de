# busservo_motion: joints in degrees, poses taught by hand, and motion at the
# wire's limit, on top of busservo.BusServo.
#
#   import busservo, busservo_motion as bm
#   arm = bm.Robot(busservo.BusServo(uart), {
#       "base": bm.Joint(1),                                  # a bus servo
#       "shoulder": bm.Joint(2, direction=-1, trim=3.5, limits=(-90, 90)),
#       "claw": bm.Joint(6, kind=bm.PWM_180, limits=(0, 60)), # a PWM servo
#   })
#   arm.move({"base": 30, "shoulder": -45}, ms=500)
#   arm.stream({"base": x}); arm.step()                  # from a control loop
#
# Degrees are the joint's, 0 at the servo's centre (position 500 for a bus
# servo, 1500 us for a PWM servo), positive in the servo's own direction times
# `direction`. A joint's servo turns to direction * degrees + trim.
#
# The stream path (stream() and step()) allocates nothing: its buffers are made
# once, in Robot(). Floats are heap objects on most ports, so it does not
# multiply them: it reads a float's bits (struct.pack_into) and scales them with
# small ints (Joint.position()).
#
# RAM: loops where a comprehension would do. On MicroPython each comprehension is a function
# of its own, kept with the module and made again at each call: loops took 0.6 KB off what
# this module keeps on a 32-bit port.
import errno
import json
import math
import time
from array import array
from struct import pack_into

try:
    from micropython import const

    _awaitable = None
except ImportError:  # CPython, on a computer: busservo_cpython gives what it lacks
    from busservo_cpython import awaitable as _awaitable
    from busservo_cpython import const, time

BUS = "BUS"  # a bus servo: positions 0..1000 over 240 degrees
PWM_180 = "PWM_180"  # a PWM servo on an LSC board: 500..2500 us over 180 degrees
PWM_270 = "PWM_270"  # the same over 270 degrees

# kind: (centre position, num, den, half): num / den positions per degree, half
# the degrees each side of the centre.
_KINDS = {BUS: (500, 25, 6, 120), PWM_180: (1500, 100, 9, 90), PWM_270: (1500, 200, 27, 135)}

_Q = const(10)  # positions are computed in 1/1024ths, then rounded
_MS_MAX = const(65535)  # a move's time on the wire: 16 bits
_SERVOS_MAX = const(83)  # servos one CMD_SERVO_MOVE can carry
_GAP_MS = const(1000)  # stream() calls further apart than this are no stream
_LATE_MS = const(50)  # a player's step this late starts its timing afresh
_INF = float("inf")
_NINF = float("-inf")

CALIBRATION = "robot.json"  # where a calibration is saved: the joints (and an arm's links)

_CHECK = object()  # move(targets, _CHECK): check targets, send nothing (a Player, home())
_asyncio = None  # imported by the first aio(): many robots never need it
# A float's bits, as two 16-bit halves (little-endian: every MicroPython board, and the
# computers CPython runs the modules on), for Joint.position().
_bits = array("H", (0, 0))
_type = type
_int = int
_float = float


def aio():
    """The asyncio module, imported when first asked for (many robots never need it)."""
    global _asyncio
    if _asyncio is None:
        import asyncio as _asyncio

        if not hasattr(_asyncio, "sleep_ms"):  # CPython: busservo_cpython's has it
            from busservo_cpython import asyncio as _asyncio
    return _asyncio


def load_json(path, key, saver):
    """config[key] of the JSON file at path (saver wrote it), or ValueError naming the file
    and what is wrong with it."""
    with open(path) as f:
        try:
            config = json.load(f)
        except ValueError as e:
            raise ValueError("%s: not valid JSON (%s)" % (path, e))
    if _type(config) is not dict or key not in config:
        raise ValueError("%s: no %r in it, as %s writes" % (path, key, saver))
    return config[key]


def number(name, value, low=_NINF, high=_INF):
    """value, a finite int or float in low..high; else TypeError or ValueError naming it
    (name), the range and what came."""
    t = _type(value)
    if t is not _int and t is not _float:
        raise TypeError("%s must be a number, got %r" % (name, value))
    if not low <= value <= high or not _NINF < value < _INF:
        if low == _NINF and high == _INF:
            raise ValueError("%s must be a finite number, got %r" % (name, value))
        raise ValueError("%s must be in %s..%s, got %r" % (name, low, high, value))
    return value


def least_dps(joints):
    """The least dps of joints {name: Joint}, or None when none has one: the speed cap a
    program's joints ask for, which Robot.load(bus, path, dps) keeps over a file's."""
    least = None
    for joint in joints.values():
        if joint.dps and (least is None or joint.dps < least):
            least = joint.dps
    return least


def _dps(dps):
    number("dps", dps, 0)
    if not dps:
        raise ValueError("dps must be more than 0 degrees/s, got %r" % (dps,))
    return dps


def _ms(name, value):
    if _type(value) is not _int:
        raise TypeError("%s must be an int in 0..%d ms, got %r" % (name, _MS_MAX, value))
    if not 0 <= value <= _MS_MAX:
        raise ValueError("%s must be in 0..%d ms, got %r" % (name, _MS_MAX, value))
    return value


class Joint:
    def __init__(self, servo_id, kind=BUS, direction=1, trim=0.0, limits=None, dps=None):
        if _type(servo_id) is not _int:
            raise TypeError("servo_id must be an int in 0..255, got %r" % (servo_id,))
        if not 0 <= servo_id <= 255:
            raise ValueError("servo_id must be in 0..255, got %r" % (servo_id,))
        if kind not in _KINDS:
            raise ValueError("kind must be BUS, PWM_180 or PWM_270, got %r" % (kind,))
        if _type(direction) is not _int:
            raise TypeError("direction must be 1 or -1, got %r" % (direction,))
        if direction != 1 and direction != -1:
            raise ValueError("direction must be 1 or -1, got %r" % (direction,))
        centre, num, den, half = _KINDS[kind]
        number("trim", trim, -half, half)
        # The degrees the servo can reach, with this direction and trim.
        low = -half - trim if direction > 0 else trim - half
        high = half - trim if direction > 0 else trim + half
        if limits is None:
            limits = (low, high)
        try:
            lo, hi = limits
        except (TypeError, ValueError):
            raise TypeError("limits must be (low, high) in degrees, got %r" % (limits,))
        number("limits", lo)
        number("limits", hi)
        if not low <= lo <= hi <= high:
            raise ValueError(
                "limits must be low <= high within %g..%g degrees (%s, trim %g), got %r"
                % (low, high, kind, trim, limits)
            )
        if dps is not None:
            _dps(dps)
        self.servo_id = servo_id
        self.kind = kind
        self.direction = direction
        self.trim = trim
        self.limits = (lo, hi)
        self.lo = lo
        self.hi = hi
        self.dps = dps
        self.per_degree = num / den  # positions per degree
        self.centre = centre
        # In 1/1024ths of a position: (_c + degrees * _num * 1024 / _den) / 1024, rounded
        # down (_c has the half that rounds it).
        self._num = direction * num
        self._den = den
        self._c = round((centre + trim * self.per_degree) * (1 << _Q)) + (1 << (_Q - 1))
        # The joint's dps in positions per second (0: none), for the stream.
        self._pps = 0 if dps is None else max(1, int(dps * self.per_degree))

    def position(self, degrees):
        """The position for degrees (an int or float), clamped to the limits.
        Allocates nothing."""
        if degrees < self.lo:
            degrees = self.lo
        elif degrees > self.hi:
            degrees = self.hi
        if _type(degrees) is _int:
            return (self._c + ((degrees * self._num << _Q) // self._den)) >> _Q
        return self._float(degrees)

    def _float(self, degrees):
        # position() of degrees, a float within the limits (Robot checks them, then calls
        # this), without a float: from the float's sign, its exponent e and the top 22 bits
        # of its significand m (1 <= m / 2**21 < 2), degrees = m * 2**(e - 148), read as
        # two 16-bit halves (the high one: sign, e, the top 7 bits of m). |degrees| < 512,
        # so the shift is to the right, and m * num < 2**30 stays a small int on a 32-bit
        # port.
        h = _bits
        pack_into("<f", h, 0, degrees)
        hi = h[1]
        m = (
            ((hi & 0x7F | 0x80) << 14 | h[0] >> 2) * self._num >> 138 - (hi >> 7 & 0xFF)
        ) // self._den
        if hi & 0x8000:
            return (self._c - m) >> _Q
        return (self._c + m) >> _Q

    def degrees(self, position):
        """The joint's angle in degrees at position (not clamped)."""
        return self.direction * ((position - self.centre) / self.per_degree - self.trim)

    def config(self):
        """The joint's settings: Joint(**joint.config()) makes it again."""
        return {
            "servo_id": self.servo_id,
            "kind": self.kind,
            "direction": self.direction,
            "trim": self.trim,
            "limits": list(self.limits),
            "dps": self.dps,
        }


class Robot:
    def __init__(self, bus, joints):
        if _type(joints) is not dict:
            raise TypeError("joints must be a dict {name: Joint}, got %r" % (joints,))
        if not 1 <= len(joints) <= _SERVOS_MAX:
            raise ValueError("joints must hold 1..%d joints, got %d" % (_SERVOS_MAX, len(joints)))
        seen = {}
        for name, joint in joints.items():
            if _type(name) is not str or not isinstance(joint, Joint):
                raise TypeError("joints must be {name: Joint}, got %r: %r" % (name, joint))
            other = seen.get(joint.servo_id)
            if other is not None:
                raise ValueError(
                    "joints %r and %r share servo_id %d" % (other, name, joint.servo_id)
                )
            seen[joint.servo_id] = name
        self.bus = bus
        self.joints = joints
        self.names = []  # in the order of their servo_ids
        self._joints = []
        self._index = {}  # {name: its index in names}
        self._ids = []
        self._pairs = []  # [id, position]: what step() sends of each joint
        for servo_id in sorted(seen):
            name = seen[servo_id]
            self._index[name] = len(self.names)
            self.names.append(name)
            self._joints.append(joints[name])
            self._ids.append(servo_id)
            self._pairs.append([servo_id, 0])
        n = len(self.names)
        self._at = [None] * n  # each joint's position as last read or commanded
        self.clamped = 0  # targets clamped to a joint's limits
        self.slowed = 0  # moves and stream frames slowed to a joint's dps
        self.player = None  # the Player playing on this robot, if any
        # The stream: each joint's latest target, the [id, position] pairs that
        # step() sends (those of the joints streamed to), and the pace.
        self._goal = [0] * n
        self._tmp = [0] * n
        self._live = []  # pairs of the joints in the stream, in the order they came
        self._live_i = []  # their joints' indices
        self._sends = {}  # {k: a list of k pairs}: a move's frame, made once for each k
        self._sel = [0] * n  # a move's joints' indices (Robot.move(), stream())
        self._in = bytearray(n)  # 1: the joint is in the stream
        self._fresh = False  # targets not yet sent
        now = time.ticks_ms()
        self._given = self._given_before = self._stepped = self._sent = now
        self._ms = 0  # the move time of the last frame step() sent
        self._slowing = False  # that frame slowed a joint to its dps (or glides longer than asked)
        self._owed = [0] * n  # a slowed joint's way not yet taken, in 1/1000 positions
        self._way = [0] * n  # the way a slowed joint's servo had to go for the last frame (1/1000)
        self.frame_ms = 0  # a stream frame's time on the wire, in ms (0: none sent yet)
        self._frame_n = 0  # the joints in the frame it was measured on
        self.updates = 0  # stream frames sent

    # Calibration.

    @staticmethod
    def load(bus, path, dps=None):
        """A Robot on bus with the joints that save() wrote to path. dps: a cap in degrees a
        second that holds whatever the file says: each joint turns at most the least of its
        own dps (the file's) and dps."""
        joints = {}
        saved = load_json(path, "joints", "Robot.save()")
        if _type(saved) is not dict:
            raise ValueError("%s: joints must be {name: settings}, got %r" % (path, saved))
        for name, settings in saved.items():
            try:
                joint = Joint(**settings)
            except TypeError as e:
                raise TypeError("%s: joint %r: %s" % (path, name, e))
            if dps is not None and (joint.dps is None or _dps(dps) < joint.dps):
                settings = joint.config()
                settings["dps"] = dps
                joint = Joint(**settings)
            joints[name] = joint
        return Robot(bus, joints)

    def save(self, path, **more):
        """Write the joints' calibration to path as JSON (Robot.load() reads it), and the
        keys in more (busservo_arm's links=...), keeping what else the file holds."""
        config = {}
        try:
            with open(path) as f:
                config = json.load(f)
        except (OSError, ValueError):
            pass  # no file yet, or not one of ours: written afresh
        if _type(config) is not dict:
            config = {}
        config.update(more)
        config["joints"] = saved = {}
        for name in self.names:
            saved[name] = self.joints[name].config()
        with open(path, "w") as f:
            json.dump(config, f)

    def _i(self, name):
        i = self._index.get(name) if _type(name) is str else None
        if i is None:
            raise ValueError("no joint %r: the joints are %s" % (name, ", ".join(self.names)))
        return i

    def _indices(self, names):
        # The indices of these joints (None: all), each name checked.
        if names is None:
            return list(range(len(self.names)))
        indices = []
        for name in names:
            indices.append(self._i(name))
        return indices

    def _ids_of(self, indices):
        # The servo ids of the joints at these indices.
        ids = []
        for i in indices:
            ids.append(self._ids[i])
        return ids

    def _read(self, indices, got=None):
        # Read positions of these joints into _at (or take them from got). A servo that
        # does not answer (its position None, or none read) has no angle: refuse it by
        # name, before anything is changed.
        if got is None:
            got = self.bus.read_positions(self._ids_of(indices))
        for i in indices:
            if got.get(self._ids[i]) is None:
                raise OSError(
                    errno.ENODEV,
                    "joint %r: servo %d does not answer (unpowered, its cable, or its id?)"
                    % (self.names[i], self._ids[i]),
                )
        for i in indices:
            self._at[i] = got[self._ids[i]]

    # Moves.

    def move(self, targets, ms=None, dps=None):
        """Move joints {name: degrees} together in one frame, within ms, or at dps
        (degrees per second) for the joint that goes furthest. Return the move's
        time in ms (longer than asked if a joint's own dps needed it)."""
        # One function (on MicroPython a call of one with many locals takes a heap block):
        # check targets (the one place a move's are checked: a Player and home() too, with
        # ms _CHECK), then time the move and send it. No comprehensions, items(), dicts or
        # tuples: each is a heap object. Each joint's position goes in its [id, position]
        # pair (the stream's: step() writes it again before it sends), the pairs in a list of
        # k made once for each k, their indices in _sel[:k].
        if ms is not _CHECK:
            if (ms is None) == (dps is None):
                raise ValueError("give move() ms or dps (not both), got ms=%r dps=%r" % (ms, dps))
            if ms is not None:
                if _type(ms) is not _int or not 0 <= ms <= _MS_MAX:
                    _ms("ms", ms)  # raises, naming it
            else:
                _dps(dps)
        if _type(targets) is not dict or not targets:
            raise TypeError("targets must be a dict {joint name: degrees}, got %r" % (targets,))
        clamped = 0
        index = self._index
        joints = self._joints
        pairs = self._pairs
        sel = self._sel
        k = len(targets)
        sends = self._sends.get(k)
        made = sends is None
        if made:  # kept once the targets are known good
            sends = [None] * k
        k = 0
        capped = dps  # a speed to keep: the call's, or a joint's own
        name = None
        try:
            for name in targets:
                i = index[name]
                degrees = targets[name]
                joint = joints[i]
                pair = pairs[i]
                t = _type(degrees)
                # A float within the limits is finite: its position at once; else, if a
                # number, a position clamped to the limits.
                if t is _float and joint.lo <= degrees <= joint.hi:
                    pair[1] = joint._float(degrees)
                else:
                    if t is not _int and (t is not _float or not _NINF < degrees < _INF):
                        number("targets[%r]" % name, degrees)  # raises, naming it
                    if not joint.lo <= degrees <= joint.hi:
                        clamped += 1
                    pair[1] = joint.position(degrees)
                sends[k] = pair
                sel[k] = i
                k += 1
                if joint.dps:
                    capped = True
        except KeyError:
            self._i(name)  # raises, naming the joints
        if ms is _CHECK:
            return 0
        if made:
            self._sends[k] = sends
        at = self._at
        took = ms or 0
        if capped:
            slowed = 0
            unknown = None
            for j in range(k):
                i = sel[j]
                if at[i] is None and (dps or joints[i].dps):
                    if unknown is None:
                        unknown = []
                    unknown.append(i)
            if unknown:
                self._read(unknown)  # a speed needs a distance: where are they?
            if dps:
                for j in range(k):
                    i = sel[j]
                    need = _time(abs(sends[j][1] - at[i]) / joints[i].per_degree, dps)
                    if need > took:
                        took = need
            for j in range(k):
                i = sel[j]
                joint = joints[i]
                if joint.dps:
                    need = _time(abs(sends[j][1] - at[i]) / joint.per_degree, joint.dps)
                    if need > took:
                        took = need
                        slowed = 1
            if took > _MS_MAX:
                raise ValueError(
                    "the move would take %d ms, more than %d: move in steps, or faster"
                    % (took, _MS_MAX)
                )
            self.slowed += slowed
        if self._live or self._fresh:
            self.hold()  # (the pairs are the stream's: it ends)
        self.bus.move_many(sends, took)
        for j in range(k):
            at[sel[j]] = sends[j][1]
        if clamped:
            self.clamped += clamped
        return took

    def where(self, names=None, positions=None):
        """{name: degrees} of these joints (all by default), read from the
        controller now (a blocking query), to 0.1 degree; or, not blocking, from
        positions {servo_id: position} read before (the driver's ask() leaves them
        in bus.positions)."""
        indices = self._indices(names)
        self._read(indices, positions)
        pose = {}
        for i in indices:
            pose[self.names[i]] = round(self._joints[i].degrees(self._at[i]), 1)
        return pose

    def capture(self):
        """The pose the robot is in now, {name: degrees} of every joint: for a
        Sequence. Pose the robot by hand after limp(), then capture()."""
        return self.where()

    def limp(self, names=None):
        """Let these joints (all by default) go limp, to be posed by hand; the
        next move gives them their torque back. Ends the stream."""
        indices = self._indices(names)
        self.hold()
        self.bus.unload(self._ids_of(indices))
        for i in indices:
            self._at[i] = None  # they will be moved by hand

    def home(self, pose=None, dps=30):
        """A soft start: read where the joints are, then go to pose (default:
        every joint at 0 degrees, within its limits) at dps. Return the ms."""
        _dps(dps)
        if pose is None:
            pose = {}
            for name, j in self.joints.items():
                pose[name] = min(max(0, j.lo), j.hi)
        self.move(pose, _CHECK)  # check it before anything is sent
        self._read(self._indices(None))
        return self.move(pose, dps=dps)

    def estop(self):
        """Stop: the player and the stream end, the action group stops, and every
        joint goes limp."""
        if self.player:
            self.player.stop()
        self.hold()
        for i in range(len(self._at)):
            self._at[i] = None
        try:
            self.bus.stop_group()
        finally:
            self.bus.unload(self._ids)

    # The stream.

    def stream(self, targets):
        """Store targets {name: degrees} for step() to send: the latest win, and
        nothing is sent here. Allocates nothing once each joint has been streamed
        to. Returns how many targets were clamped to their limits."""
        if _type(targets) is not dict:
            raise TypeError("targets must be a dict {joint name: degrees}, got %r" % (targets,))
        index = self._index
        joints = self._joints
        tmp = self._tmp
        sel = self._sel
        at = self._at
        clamped = 0
        k = 0
        for name in targets:  # check all first: a bad one stores nothing
            i = index.get(name)
            if i is None:
                self._i(name)
            degrees = targets[name]
            joint = joints[i]
            if joint._pps and at[i] is None:
                raise ValueError(
                    "joint %r has a dps limit and no known position: home() or where() first"
                    % name
                )
            t = _type(degrees)
            if t is _float and joint.lo <= degrees <= joint.hi:  # as move()
                # joint._float(degrees), inline: a call costs more than its work (a test
                # checks that the two agree)
                pack_into("<f", _bits, 0, degrees)
                hi = _bits[1]
                m = (
                    ((hi & 0x7F | 0x80) << 14 | _bits[0] >> 2) * joint._num
                    >> 138 - (hi >> 7 & 0xFF)
                ) // joint._den
                tmp[k] = (joint._c - m if hi & 0x8000 else joint._c + m) >> _Q
            else:
                if t is not _int and (t is not _float or not _NINF < degrees < _INF):
                    number("targets[%r]" % name, degrees)
                if not joint.lo <= degrees <= joint.hi:
                    clamped += 1
                tmp[k] = joint.position(degrees)
            sel[k] = i
            k += 1
        goal = self._goal
        streamed = self._in
        for j in range(k):
            i = sel[j]
            goal[i] = tmp[j]
            if not streamed[i]:
                streamed[i] = 1
                self._live.append(self._pairs[i])
                self._live_i.append(i)
        now = time.ticks_ms()
        self._given_before = self._given
        self._given = now
        self._fresh = True
        self.clamped += clamped
        return clamped

    def step(self):
        """From the control loop: send the latest stream targets in one frame if
        there are new ones and the wire is free, or will be before the next
        step(). Never waits for the UART; allocates nothing. True if it sent."""
        now = time.ticks_ms()
        since = time.ticks_diff(now, self._stepped)  # the loop's period
        self._stepped = now
        if not self._fresh:
            return False
        if self._slowing and time.ticks_diff(now, self._sent) < self._ms:
            return False  # a slowed joint is on its way: its next step once it is there
        live = self._live
        n = len(live)
        frame = self.frame_ms or 3 * n + 8  # ms: at 9600 baud, until measured
        bus = self.bus
        ahead = bus.wire_ms()
        if ahead > (since if since < frame else frame):
            return False
        # Interpolate over the time to the next update: the pace of stream(),
        # or the frame's wire time if that is longer.
        ms = time.ticks_diff(self._given, self._given_before)
        if ms < frame or ms > _GAP_MS:
            ms = frame
        at = self._at
        goal = self._goal
        joints = self._joints
        owed = self._owed
        # A slowed joint goes as far as its dps allows in the time since the last frame (no
        # more than that frame's glide and the loop's period, or this one's ms: after a
        # pause it starts afresh), the part of a position a frame cannot take carried to the
        # next; the frame takes as long as its longest step needs at that dps (glide), and no
        # frame goes before the servo is there (above). So a joint never turns faster than
        # its dps, however fast step() runs and however fast the targets come. A glide grows
        # by the loop's lateness, up to 10 loop periods: a new target is heard within them,
        # and the joint goes at 10/11 of its dps at the least. (Worked out at the first such
        # joint: elapsed is -1 until then.)
        elapsed = -1
        glide = ms
        fresh = False
        live_i = self._live_i
        way = self._way
        for k in range(n):
            i = live_i[k]
            pps = joints[i]._pps
            if pps:  # no faster than the joint's dps: step towards the goal
                if elapsed < 0:
                    elapsed = sent = time.ticks_diff(now, self._sent)
                    cap = self._ms + since
                    if cap > 10 * since:
                        cap = 10 * since
                    if cap < ms:
                        cap = ms
                    if elapsed > cap:
                        elapsed = cap
                need = toward(live[k], goal[i], i, at, owed, way, pps, elapsed, self._ms, sent)
                if need > glide:
                    glide = need
                fresh = fresh or live[k][1] != goal[i]
            else:
                live[k][1] = goal[i]
        bus.move_many(live, glide)
        self._sent = now
        self._ms = glide
        self._slowing = fresh or glide > ms  # still on its way: the next frame waits
        for k in range(n):
            at[live_i[k]] = live[k][1]
        if fresh:
            self.slowed += 1
        self._fresh = fresh
        self.updates += 1
        # The frame's time on the wire, as wire_ms() grew (whole ms: the most seen).
        sent = bus.wire_ms() - ahead
        if n != self._frame_n:
            self._frame_n = n
            self.frame_ms = 0
        if sent > self.frame_ms:
            self.frame_ms = sent
        return True

    def hold(self):
        """End the stream: targets not yet sent are dropped, and each joint stops
        at the last target sent. Nothing is sent. A later stream() starts afresh."""
        self._fresh = False
        if self._live:
            for i in self._live_i:
                self._in[i] = 0
            self._live.clear()
            self._live_i.clear()


def toward(pair, goal, i, at, owed, way, pps, elapsed, last_ms, since):
    """One step of joint i of a stream towards goal, at pps positions a second at most
    (Robot.step(), busservo_teleop): pair[1] = the position to send, from at[i] (the last
    sent) as far as elapsed ms allow (owed[i] carries a position's part, in 1/1000ths).
    Returns the ms the move needs at pps from where the servo is: short of at[i] still if
    the last move (way[i]/1000 positions, over last_ms, sent `since` ms ago) is on its way. So a
    servo that goes straight from where it is to each target, over each move's time, never
    turns faster than pps, however soon a move comes after a long one. way[i] becomes this
    move's (the caller sets at[i] once it is sent). Allocates nothing."""
    position = goal
    a = at[i]
    owed[i] += pps * elapsed
    most = owed[i] // 1000
    if position > a + most:
        position = a + most
    elif position < a - most:
        position = a - most
    else:
        most = owed[i] = 0  # there: nothing owed
    owed[i] -= most * 1000
    pair[1] = position
    far = abs(position - a) * 1000  # in 1/1000 positions
    if since < last_ms:  # the servo is short of at[i] by the last move's way still to go
        far += way[i] * (last_ms - since) // last_ms
    way[i] = far
    return (far + pps - 1) // pps


def _time(degrees, dps):
    # ms to go degrees at dps, rounded up.
    return math.ceil(degrees * 1000 / dps)


class Sequence:
    def __init__(self, steps=()):
        """steps: (pose, ms) pairs: each pose {name: degrees}, and the ms to reach it."""
        self.steps = []
        for step in steps:
            try:
                pose, ms = step
            except (TypeError, ValueError):
                raise TypeError("steps must be (pose, ms) pairs, got %r" % (step,))
            self.append(pose, ms)

    def append(self, pose, ms):
        """Add a pose {name: degrees}, reached ms after the one before."""
        if _type(pose) is not dict or not pose:
            raise TypeError("pose must be a dict {joint name: degrees}, got %r" % (pose,))
        for name, degrees in pose.items():
            if _type(name) is not str:
                raise TypeError("pose's names must be str, got %r" % (name,))
            number("pose[%r]" % name, degrees)
        self.steps.append((dict(pose), _ms("ms", ms)))

    def __len__(self):
        return len(self.steps)

    def save(self, path):
        """Write the sequence to path as JSON (Sequence.load() reads it)."""
        with open(path, "w") as f:
            steps = []
            for pose, ms in self.steps:
                steps.append({"ms": ms, "pose": pose})
            json.dump({"steps": steps}, f)

    @staticmethod
    def load(path):
        """The sequence that save() wrote to path."""
        steps = load_json(path, "steps", "Sequence.save()")
        pairs = []
        try:
            for step in steps:
                pairs.append((step["pose"], step["ms"]))
        except (KeyError, TypeError) as e:
            raise ValueError('%s: steps must be [{"pose": ..., "ms": ...}]: %r' % (path, e))
        return Sequence(pairs)

    def play(self, robot, speed=1.0, loop=False):
        """A Player of this sequence on robot: call its step() from a loop, or
        await it. speed 2.0 plays twice as fast."""
        return Player(robot, self, speed, loop)


class Player:
    def __init__(self, robot, sequence, speed=1.0, loop=False):
        number("speed", speed, 0)
        if not speed:
            raise ValueError("speed must be more than 0, got %r" % (speed,))
        if not sequence.steps:
            raise ValueError("the sequence has no poses")
        self.robot = robot
        self.loop = bool(loop)
        self.speed = speed
        self._poses = []
        for pose, ms in sequence.steps:
            robot.move(pose, _CHECK)  # every name and number checked before anything moves
            self._poses.append((pose, _ms("ms / speed", round(ms / speed))))
        self.index = -1  # the pose last sent
        self.loops = 0  # times the sequence has come round again
        self.done = False
        self._due = None  # ticks_ms when the pose last sent will have been reached
        if robot.player:
            robot.player.stop()
        robot.player = self

    def step(self):
        """Send the next pose if its time has come; never waits. True if it sent."""
        if self.done:
            return False
        now = time.ticks_ms()
        due = self._due
        if due is not None and time.ticks_diff(now, due) < 0:
            return False
        if self.index + 1 == len(self._poses):
            if not self.loop:
                self.stop()
                return False
            self.index = -1
            self.loops += 1
        self.index += 1
        pose, ms = self._poses[self.index]
        took = self.robot.move(pose, ms=ms)
        # Time from when this pose was due, so that a late step() does not delay
        # the ones after it; from now, if it came very late.
        if due is None or time.ticks_diff(now, due) > _LATE_MS:
            due = now
        self._due = time.ticks_add(due, took)
        return True

    def stop(self):
        """Stop playing; nothing is sent (the pose on its way is reached)."""
        self.done = True
        if self.robot.player is self:
            self.robot.player = None

    async def run(self, poll_ms=10):
        """Play to the end (for ever with loop, until stop()), sleeping between poses."""
        asyncio = aio()
        while not self.done:
            self.step()
            if not self.done:
                wait = poll_ms
                if self._due is not None:
                    wait = min(wait, max(0, time.ticks_diff(self._due, time.ticks_ms())))
                await asyncio.sleep_ms(wait)

    def __await__(self):
        return self.run()

    __iter__ = __await__


if _awaitable:  # CPython: await wants an iterator, not the coroutine MicroPython takes
    _awaitable(Player)
