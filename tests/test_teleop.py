# busservo_teleop: a limp leader arm drives a follower, on the wire-faithful world of
# tests/wire.py (a stepped clock, the rp2 and esp32 UART models, the simulated controller):
# two controllers on two UARTs (two worlds on one clock), or both arms on one controller's
# bus. The driver, the motion layer and the teleop all run on the world's clock.
import math
import time
import unittest

import busservo
import busservo_motion as bm
import busservo_teleop as bt
import wire
from busservo import CMD_MULT_SERVO_POS_READ as READ
from busservo import CMD_MULT_SERVO_UNLOAD as UNLOAD
from busservo import CMD_SERVO_MOVE as MOVE

NAMES = ("base", "shoulder", "elbow", "wrist", "roll", "gripper")
BYTE_MS = 10 / 9.6  # 10 bits at 9600 baud
# Cycles a second, 6 servos: two UARTs, a request and its reply; one bus, a request and a move.
LIMITS = {"two": 1000 / ((11 + 23) * BYTE_MS), "one": 1000 / ((11 + 25) * BYTE_MS)}


def clocked(clock):
    busservo.time = bm.time = bt.time = clock


def arm(bus, first=1, **per_joint):
    """Six bus servos, ids first.., named as NAMES; per_joint: {name: Joint's keywords}."""
    return bm.Robot(
        bus, {n: bm.Joint(first + i, **per_joint.get(n, {})) for i, n in enumerate(NAMES)}
    )


def two_uarts(port="rp2", leader=None, follower=None):
    """(leader's world, follower's world, Teleop): two controllers on two UARTs, one clock."""
    clock = wire.Clock()
    wl = wire.World(port, clock=clock)
    wf = wire.World(port, clock=clock)
    clocked(clock)
    lead = arm(busservo.BusServo(wl.uart), **(leader or {}))
    follow = arm(busservo.BusServo(wf.uart), **(follower or {}))
    return wl, wf, lead, follow


def one_bus(port="rp2"):
    """(world, leader, follower): both arms on one controller, leader ids 1..6, follower 7..12."""
    w = wire.World(port)
    clocked(w.clock)
    bus = busservo.BusServo(w.uart)
    return w, arm(bus), arm(bus, first=7)


def moves(w, ids=None):
    """Each CMD_SERVO_MOVE the controller received: (time_ms, {id: position})."""
    out = []
    for f in w.frames():
        if f[3] == MOVE:
            pose = {f[i]: f[i + 1] | f[i + 2] << 8 for i in range(7, len(f), 3)}
            if ids is None or set(pose) <= set(ids):
                out.append((f[5] | f[6] << 8, pose))
    return out


def run(t, worlds, ms, hand=None, every=5, step_us=500):
    """Step t every step_us for ms of simulated time (a loop that does little else); hand(ms)
    -> {id: position} turns the leader's servos by hand (every `every` ms) in worlds[0]."""
    clock = worlds[0].clock
    start = clock.now_us
    end = start + ms * 1000
    turned = -every
    while clock.now_us < end:
        i = (clock.now_us - start) // 1000
        if hand is not None and i - turned >= every:
            turned = i
            sim = worlds[0].sim
            for servo_id, position in hand(i).items():
                sim.turn(servo_id, position)
        t.step()
        clock.advance_us(step_us)


def wave(i):
    """A hand moving the leader's six joints, slowly: 100 positions (24 degrees) each way."""
    return {s: 500 + int(100 * math.sin(i / 700 + s)) for s in range(1, 7)}


def raises(call, error, *words):
    """The error call() raises (of that class): its message, which must hold words."""
    try:
        call()
    except error as e:
        text = str(e)
        for word in words:
            assert word in text, "%r not in %r" % (word, text)
        return text
    raise AssertionError("no error")


class Tidy(unittest.TestCase):
    def tearDown(self):
        busservo.time = bm.time = bt.time = time
        bm._asyncio = None


class Following(Tidy):
    def test_two_uarts_the_follower_follows_the_leader_at_the_wires_pace(self):
        for port in wire.PORTS:
            wl, wf, lead, follow = two_uarts(port)
            t = bt.Teleop(lead, follow, dps=60)
            run(t, (wl, wf), 300)  # still: it reads the follower, then engages
            self.assertTrue(t.engaged)
            self.assertEqual(t.timeouts, 0)
            before = t.reads
            run(t, (wl, wf), 6000, wave)
            # The leader's joints went limp first; then only its positions were asked for.
            self.assertEqual(wl.frames()[0][3], UNLOAD)
            self.assertEqual({f[3] for f in wl.frames()[1:]}, {READ})
            # 35.4 ms a cycle: 28.2 a second (at least 95 % of it), each reply a move.
            self.assertTrue(0.95 * LIMITS["two"] * 6 <= t.reads - before <= 28.3 * 6, t.reads)
            self.assertTrue(abs(t.moves - t.reads) <= 2, (t.moves, t.reads))
            # Where the leader's servos are, the follower's go (a cycle behind).
            run(t, (wl, wf), 200)
            for s in range(1, 7):
                self.assertEqual(wf.sim.position(s), wl.sim.position(s))

    def test_one_bus_the_request_and_the_move_share_tx(self):
        for port in wire.PORTS:
            w, lead, follow = one_bus(port)
            t = bt.Teleop(lead, follow, dps=60)
            run(t, (w,), 300)
            self.assertTrue(t.engaged)
            before = t.reads
            run(t, (w,), 6000, wave)
            # 37.5 ms a cycle: 26.7 a second (at least 95 % of it).
            self.assertTrue(0.95 * LIMITS["one"] * 6 <= t.reads - before <= 26.7 * 6, t.reads)
            run(t, (w,), 200)
            for s in range(1, 7):
                self.assertEqual(w.sim.position(s + 6), w.sim.position(s))
            # Each move goes right behind a request, while the reply comes.
            frames = [f[3] for f in w.frames()[-40:]]
            for i in range(1, len(frames)):
                if frames[i] == MOVE:
                    self.assertEqual(frames[i - 1], READ)
            self.assertTrue(all(set(p) == set(range(7, 13)) for _, p in moves(w)))

    def test_the_same_degrees_through_each_arms_calibration(self):
        # The follower's shoulder is mounted the other way round and trimmed; its claw is a
        # PWM servo. The leader's elbow is trimmed. Each joint goes to the leader's degrees.
        wl, wf, lead, follow = two_uarts(
            leader={"elbow": {"trim": 7.2}},
            follower={
                "shoulder": {"direction": -1, "trim": -4.8},
                "gripper": {"kind": bm.PWM_180, "limits": (-30, 60)},
            },
        )
        wf.sim.pwm.add(6)
        t = bt.Teleop(lead, follow, dps=90, rest=False)
        hand = {1: 600, 2: 560, 3: 530, 4: 440, 5: 500, 6: 620}
        run(t, (wl, wf), 3000, lambda i: hand)
        self.assertTrue(t.engaged)
        for name in NAMES:
            want = lead.joints[name].degrees(wl.sim.position(lead.joints[name].servo_id))
            got = follow.joints[name].degrees(wf.sim.position(follow.joints[name].servo_id))
            self.assertTrue(abs(want - got) < 0.3, (name, want, got))

    def test_the_follower_stops_at_its_limits(self):
        wl, wf, lead, follow = two_uarts(follower={"base": {"limits": (-10, 10)}})
        t = bt.Teleop(lead, follow, dps=90, rest=False)
        run(t, (wl, wf), 2000, lambda i: {1: 800})  # 72 degrees: past 10
        self.assertEqual(wf.sim.position(1), follow.joints["base"].position(10))
        self.assertTrue(t.clamped > 0)
        self.assertTrue(t.engaged)

    def test_joints_are_matched_by_name(self):
        # The follower lacks the roll; its gripper is servo 9. Only the shared names move.
        clock = wire.Clock()
        wl = wire.World("rp2", clock=clock)
        wf = wire.World("rp2", clock=clock)
        clocked(clock)
        lead = arm(busservo.BusServo(wl.uart))
        follow = bm.Robot(
            busservo.BusServo(wf.uart),
            {"gripper": bm.Joint(9), "base": bm.Joint(1), "elbow": bm.Joint(3)},
        )
        t = bt.Teleop(lead, follow, rest=False)
        self.assertEqual(t.names, ["base", "elbow", "gripper"])
        run(t, (wl, wf), 2000, lambda i: {1: 520, 3: 480, 6: 510})
        self.assertEqual(moves(wf)[-1][1], {1: 520, 3: 480, 9: 510})
        self.assertEqual(wl.frames()[0], bytes((0x55, 0x55, 6, UNLOAD, 3, 1, 3, 6)))

    def test_bad_arguments_are_refused_by_name_and_nothing_is_sent(self):
        wl, wf, lead, follow = two_uarts()
        for args, kw, error, words in (
            ((lead, "arm"), {}, TypeError, "busservo_motion Robots"),
            ((lead, lead), {}, ValueError, "the same one twice"),
            ((lead, follow), {"dps": 0}, ValueError, "dps"),
            ((lead, follow), {"dps": "fast"}, TypeError, "dps"),
        ):
            raises(lambda a=args, k=kw: bt.Teleop(*a, **k), error, words)
        other = bm.Robot(follow.bus, {"hand": bm.Joint(1)})
        raises(lambda: bt.Teleop(lead, other), ValueError, "share no joint name", "hand")
        same = arm(lead.bus)  # one bus, the same ids
        raises(lambda: bt.Teleop(lead, same), ValueError, "'base'", "servo 1")
        self.assertEqual((wl.frames(), wf.frames()), ([], []))


if __name__ == "__main__":
    unittest.main()
