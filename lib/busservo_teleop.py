# busservo_teleop: a leader arm, limp, moved by hand, drives a follower arm live, at
# the wire's pace, on top of busservo_motion.Robot.
#
#   import busservo_teleop
#   t = busservo_teleop.Teleop(leader, follower, dps=30)   # two Robots, joints by name
#   while True:
#       t.step()                     # from the loop: never waits for the wire
#   # or, in asyncio: await t
#
# Each arm is a Robot with its own calibration, so the same degrees are the same pose
# even where the two arms' servos are mounted differently. The arms may be on two UARTs
# (two BusServo), on one controller's bus (one BusServo, the two Robots' servo ids
# apart), or on two serial ports of a computer.
#
# A cycle: the leader's positions are asked for (BusServo.ask(), step by step), and
# when they come the follower is sent them, mapped joint by joint through both
# calibrations, in one CMD_SERVO_MOVE whose time is the cycle's, so the servos glide
# from one sample to the next. On one bus the next request goes first and the move
# behind it, while the reply comes on RX. The step works in the servos' integer
# positions: the two calibrations are folded, per joint, into one line in 1/1024ths of
# a position (made once, here), and the leader's query is made once and asks again
# after each answer: a cycle allocates nothing.
#
# Safety: the follower first goes to the leader's pose at `dps`, and follows freely
# only once its every joint is within ENGAGE degrees of the leader's; a leader joint
# that does not answer holds the follower (naming the joint), and after that, or a
# pause in the reads, it engages again the same way. The follower's limits and its
# joints' own dps always hold. The teleop is the follower's player: estop() stops it.
import time

from busservo_motion import Robot, aio, number, toward

try:
    from micropython import const

    _awaitable = None
except ImportError:  # CPython, on a computer: busservo_cpython gives what it lacks
    from busservo_cpython import awaitable as _awaitable
    from busservo_cpython import const, time

ENGAGE = 3  # degrees: the follower follows once every joint is this near the leader's
REST = 2  # degrees: at the start, two calibrations that differ more at rest are warned of
_Q = const(10)  # the calibrations' line, in 1/1024ths of a position
_GAP_MS = const(250)  # no leader reply for longer: engage again, at dps
_GLIDE_MIN = const(10)  # a move's time: the cycle's, within these
_GLIDE_MAX = const(200)
_ROOM_MS = const(5)  # a move goes when its wire is free within this (and a request, on one bus)


class Teleop:
    def __init__(self, leader, follower, dps=30, rest=True, timeout_ms=None, recorder=None):
        """leader drives follower, two busservo_motion Robots, their joints matched by name.
        dps: how fast the follower goes to the leader's pose before it follows (degrees/s).
        rest: both arms start in their rest pose, so their readings there are compared and a
        joint whose two calibrations disagree by more than REST degrees is warned of.
        timeout_ms: each read's, as BusServo.ask() takes it (None: its default).
        recorder: a busservo_record.Recorder of the leader, given each read of it (its
        take()): the leader is recorded with no read of its own."""
        if not isinstance(leader, Robot) or not isinstance(follower, Robot):
            raise TypeError(
                "leader and follower must be busservo_motion Robots, got %r and %r"
                % (leader, follower)
            )
        if leader is follower:
            raise ValueError("leader and follower must be two Robots, got the same one twice")
        number("dps", dps, 0)
        if not dps:
            raise ValueError("dps must be more than 0 degrees/s, got %r" % (dps,))
        names = [name for name in leader.names if name in follower.joints]
        if not names:
            raise ValueError(
                "leader and follower share no joint name: the leader's are %s, the follower's %s"
                % (", ".join(leader.names), ", ".join(follower.names))
            )
        self.shared = leader.bus is follower.bus  # one controller's bus for both
        if self.shared:
            mine = {leader.joints[name].servo_id: name for name in leader.names}
            for name in follower.names:
                other = mine.get(follower.joints[name].servo_id)
                if other is not None:
                    raise ValueError(
                        "on one bus the arms need their own servo ids: the leader's %r and the "
                        "follower's %r are both servo %d"
                        % (other, name, follower.joints[name].servo_id)
                    )
        if recorder is not None:
            _recording(recorder, leader, names)
        self.leader = leader
        self.follower = follower
        self.names = names
        self.recorder = recorder
        self.dps = dps
        self.rest = bool(rest)
        self.timeout_ms = timeout_ms
        n = len(names)
        self._lids = [leader.joints[name].servo_id for name in names]
        self._fids = [follower.joints[name].servo_id for name in names]
        # Per joint, the leader's position p to the follower's, unclamped, in 1/1024ths:
        # _a + (p - _c) * _s. The follower's servo turns to its direction * degrees + trim.
        self._c = []
        self._a = []
        self._s = []
        self._lo = []  # the follower's limits, in its positions
        self._hi = []
        self._tol = []  # ENGAGE degrees, in the follower's positions
        self._pps = []  # engaging: positions per second (dps, or the joint's own if less)
        self._jpps = []  # following: the joint's own dps in positions per second (0: none)
        for name in names:
            lj = leader.joints[name]
            fj = follower.joints[name]
            c = lj.centre
            f0 = fj.centre + fj.per_degree * (fj.trim + fj.direction * lj.degrees(c))
            f1 = fj.centre + fj.per_degree * (fj.trim + fj.direction * lj.degrees(c + 1))
            self._c.append(c)
            self._a.append(round(f0 * (1 << _Q)))
            self._s.append(round((f1 - f0) * (1 << _Q)))
            lo = fj.position(fj.lo)
            hi = fj.position(fj.hi)
            self._lo.append(min(lo, hi))
            self._hi.append(max(lo, hi))
            self._tol.append(int(ENGAGE * fj.per_degree))
            jpps = 0 if fj.dps is None else max(1, int(fj.dps * fj.per_degree))
            pps = max(1, int(dps * fj.per_degree))
            self._jpps.append(jpps)
            self._pps.append(min(pps, jpps) if jpps else pps)
        self._goal = [0] * n  # the follower's targets from the last leader reply
        self._at = [0] * n  # the follower's positions: read at the start, then as sent
        self._owed = [0] * n  # a slowed joint's way not yet taken, in 1/1000 positions
        self._way = [0] * n  # the way a slowed joint's servo had to go for the last move (1/1000)
        self._pairs = [[servo_id, 0] for servo_id in self._fids]  # the move, made once
        self._ask = None  # the query in flight (a BusServo.ask() generator, again=True)
        self._lead = None  # the leader's, made once
        self._got = None  # what the query's first step said (None: waiting)
        self._phase = 0  # 0: not begun, 1: reading the follower, 2: following the leader
        self._fresh = False  # targets not yet sent
        self._room = _ROOM_MS  # on one bus: and a request's time, as measured
        now = time.ticks_ms()
        self.read_at = now  # ticks_ms of the last good leader reply
        self._sent = now  # ticks_ms of the last move
        self._ms = 0  # its time
        self.period_ms = 0  # between the last two leader replies: the rate is 1000 / this
        self._cycle = 40  # ms: the last period that was no pause, each move's time
        self.engaged = False  # the follower follows (else it is on its way, at dps)
        self.held = None  # the leader's joint that does not answer, holding the follower
        self.done = False
        self.reads = 0  # leader replies
        self.moves = 0  # moves sent to the follower
        self.timeouts = 0  # reads that timed out, skipped
        self.clamped = 0  # targets clamped to the follower's limits
        self.slowed = 0  # moves slowed to dps (engaging) or a joint's own dps
        self.warnings = []  # what was warned of (each also given to warn)
        self.warn = None  # where warnings go as they come: warn(text), or print if None
        if follower.player:
            follower.player.stop()
        follower.player = self

    def step(self):
        """From the loop: take the leader's reply if it has come, ask again, and send the
        follower its targets once its wire is free. Never waits for the wire; allocates
        nothing once the leader's query is made. True if it sent the follower a move."""
        if self.done:
            return False
        if not self._phase:
            self._phase = 1
            self.leader.limp(self.names)  # for the hand
        try:
            if self._ask is None:
                self._start()
            got = self._got
            if got is None:
                got = next(self._ask)  # a step of the read: None while it waits
            self._got = None
            if got:  # the reply has come
                if self._phase == 1:
                    self._ask = None  # the follower is read once
                    self._follower_read()
                else:
                    self._leader_read()
                if not self.done:
                    self._start()  # at once: on one bus the request goes before the move
            elif got is not None:  # none came in time: skipped, and asked again
                self.timeouts += 1
                if self.recorder is not None and self._phase == 2:
                    self.recorder.take(time.ticks_ms(), None)  # a read skipped: counted
        except OSError:  # the UART failed: its query is over
            self._ask = self._lead = None
            raise
        return self._send()

    def _start(self):
        # Ask for the positions: the follower's, once, then the leader's, cycle after cycle,
        # with one query made once that asks again after each answer (no heap a read). Its
        # first step sends the request (and may find the answer there already, from a peer
        # faster than the wire: kept in _got for step()).
        if self._phase == 1:
            bus = self.follower.bus
            if self._ask is None:
                self._ask = bus.ask(self._fids, self.timeout_ms, again=True)
        else:
            bus = self.leader.bus
            if self._lead is None:
                self._lead = bus.ask(self._lids, self.timeout_ms, again=True)
            self._ask = self._lead
        before = bus.wire_ms()
        try:
            self._got = next(self._ask)
        finally:
            if self.shared and self._phase == 2:
                grew = bus.wire_ms() - before + _ROOM_MS
                if grew > self._room:
                    self._room = grew  # a move may go behind the request

    def _follower_read(self):
        positions = self.follower.bus.positions
        at = self._at
        for k in range(len(at)):
            p = positions.get(self._fids[k])
            if p is None:
                self._hold(k, "follower", self._fids[k])
                return
            at[k] = p
        self.held = None
        self._phase = 2

    def _leader_read(self):
        now = time.ticks_ms()
        positions = self.leader.bus.positions
        if self.recorder is not None:  # before the next request: its file may be written
            self.recorder.take(now, positions)
        goal = self._goal
        for k in range(len(goal)):
            p = positions.get(self._lids[k])
            if p is None:
                self._hold(k, "leader", self._lids[k])
                self._fresh = False
                return
            q = (self._a[k] + (p - self._c[k]) * self._s[k] + (1 << (_Q - 1))) >> _Q
            if q < self._lo[k]:
                q = self._lo[k]
                self.clamped += 1
            elif q > self._hi[k]:
                q = self._hi[k]
                self.clamped += 1
            goal[k] = q
        self.held = None  # (a hold disengaged it: it engages again, at dps)
        if self.reads:  # between two good replies: a pause, or the cycle
            self.period_ms = time.ticks_diff(now, self.read_at)
            if self.period_ms > _GAP_MS:
                self._disengage()
            else:
                self._cycle = self.period_ms
        if not self.reads and self.rest:
            self._check_rest(positions)
        self.reads += 1
        self.read_at = now
        self._fresh = True

    def _hold(self, k, arm, servo_id):
        # A servo that does not answer: nothing moves until it does; then engage again.
        name = self.names[k]
        if self.held != name:
            self.held = name
            self._warn(
                "joint %r: the %s's servo %d does not answer (unpowered, its cable, or its id?):"
                " the follower holds" % (name, arm, servo_id)
            )
        self._disengage()

    def _disengage(self):
        self.engaged = False
        owed = self._owed
        for k in range(len(owed)):
            owed[k] = 0

    def _check_rest(self, positions):
        # Both arms at rest: each joint should read the same degrees on both.
        for k, name in enumerate(self.names):
            lead = self.leader.joints[name].degrees(positions[self._lids[k]])
            follow = self.follower.joints[name].degrees(self._at[k])
            if abs(lead - follow) > REST:
                self._warn(
                    "joint %r: at rest the leader reads %.1f degrees and the follower %.1f: "
                    "their calibrations disagree by %.1f (more than %d); calibrate the one "
                    "that is off again" % (name, lead, follow, abs(lead - follow), REST)
                )

    def _warn(self, text):
        text = "busservo_teleop: " + text
        self.warnings.append(text)
        (self.warn or print)(text)

    def _send(self):
        # The follower's move, once its wire is free (on one bus, behind the request).
        if not self._fresh or self.follower.bus.wire_ms() > self._room:
            return False
        now = time.ticks_ms()
        elapsed = since = time.ticks_diff(now, self._sent)
        glide = self._cycle
        if glide < _GLIDE_MIN:
            glide = _GLIDE_MIN
        elif glide > _GLIDE_MAX:
            glide = _GLIDE_MAX
        if elapsed > glide:
            elapsed = glide  # after a pause, no leap: no more than a cycle's way at a time
        goal = self._goal
        at = self._at
        owed = self._owed
        way = self._way
        pairs = self._pairs
        if not self.engaged:  # within ENGAGE degrees already (after a short pause, say)?
            for k in range(len(goal)):
                if abs(goal[k] - at[k]) > self._tol[k]:
                    break
            else:
                self.engaged = True
        engaged = self.engaged
        near = True
        slowed = False
        ms = glide
        for k in range(len(goal)):
            pps = self._jpps[k] if engaged else self._pps[k]
            if pps:  # no faster than pps: step towards the goal
                need = toward(pairs[k], goal[k], k, at, owed, way, pps, elapsed, self._ms, since)
                if need > ms:
                    ms = need
                slowed = slowed or pairs[k][1] != goal[k]
            else:
                pairs[k][1] = goal[k]
                way[k] = abs(goal[k] - at[k]) * 1000  # (were it slowed next)
            if not engaged and abs(pairs[k][1] - goal[k]) > self._tol[k]:
                near = False
        self.follower.bus.move_many(pairs, ms)
        for k in range(len(at)):
            at[k] = pairs[k][1]
        self._sent = now
        self._ms = ms
        self._fresh = False
        self.moves += 1
        self.slowed += slowed
        if near:
            self.engaged = True
        return True

    def stop(self):
        """Stop: nothing more is sent (the move on its way is made); the leader stays limp.
        The follower's Robot knows where it was sent, for its next move."""
        self.done = True
        self._ask = self._lead = None
        if self.follower.player is self:
            self.follower.player = None
        if self.moves:
            at = {self._fids[k]: self._at[k] for k in range(len(self._at))}
            self.follower.where(self.names, at)

    async def run(self, poll_ms=1):
        """Follow until stop() (or the follower's estop()), a step every poll_ms."""
        asyncio = aio()
        while not self.done:
            self.step()
            await asyncio.sleep_ms(poll_ms)

    def __await__(self):
        return self.run()

    __iter__ = __await__


def _recording(recorder, leader, names):
    # A recorder must record the leader, and only joints the teleop reads.
    if not hasattr(recorder, "take") or not hasattr(recorder, "names"):
        raise TypeError(
            "recorder must be a busservo_record.Recorder (it has take()), got %r" % (recorder,)
        )
    if getattr(recorder, "robot", None) is not leader:
        raise ValueError("recorder must record the leader: busservo_record.Recorder(leader)")
    other = [name for name in recorder.names if name not in names]
    if other:
        raise ValueError(
            "the recorder records joints %s, which the teleop does not read (it reads those "
            "both arms have): Recorder(leader, names=%r)" % (", ".join(other), names)
        )


if _awaitable:  # CPython: await wants an iterator, not the coroutine MicroPython takes
    _awaitable(Teleop)
