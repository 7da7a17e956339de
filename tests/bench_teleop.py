# A leader arm, moved by a hand, drives a follower (busservo_teleop) on the wire-faithful test
# world (tests/wire.py: the rp2 and esp32 UART models, 9600-baud lines, the simulated
# controller, a simulated clock), in each configuration, for 10 simulated minutes a case:
#
#   two:  two controllers on two UARTs (two worlds on one clock);
#   one:  one controller, both arms on its bus (leader ids 1..6, follower 7..12).
#
#   sh boards/unix.sh tests/bench_teleop.py          # prints a Markdown table (minutes)
#   sh boards/unix.sh tests/bench_teleop.py 60       # 60 s a case
#   sh boards/unix.sh tests/bench_teleop.py --budget # a step's time against move_many()'s
#
# Simulated time only: the same figures every run, on any machine. What is measured:
#
# - The loop calls t.step() every 0.5 ms (a loop that does little else; each UART call and
#   ticks read moves the clock on a little more, as a board's do). The hand turns the leader's
#   six servos every 5 ms, each along its own slow wave, so that every reply differs.
# - cycles/s: the follower's moves that reached its controller carrying a leader's reply
#   (both arms calibrated alike: the move's positions are the reply's), over the time; % of
#   the limit: of docs/teleop.md's (two: 1000 / 35.4, one: 1000 / 37.5 a second).
# - latency: from a reply's last byte at the board's pin to the last byte of the move that
#   carries it at the follower's controller: the median and the 99th percentile.
# - faults: with them, every 5 s the leader's line gets one of: a reply 300 ms late (a read
#   timeout), 3 bytes of a reply dropped, a false frame start (noise), a reply cut short.
#   aborts: exceptions out of step() (none may come: a case stops at the first).
import busservo
import busservo_motion as bm
import busservo_teleop as bt
import wire

STEP_US = 500
HAND_MS = 5
SECONDS = 600
BYTE_MS = 10 / 9.6
LIMITS = {"two": 1000 / (34 * BYTE_MS), "one": 1000 / (36 * BYTE_MS)}
NAMES = ("base", "shoulder", "elbow", "wrist", "roll", "gripper")
FAULT_MS = 5000
# A slow wave a servo, in positions: 100 * sin, as a table (no float on the hot path).
_WAVE = [int(100 * __import__("math").sin(6.2832 * k / 1000)) for k in range(1000)]


def hand(ms, servo):
    """Where the hand holds the leader's servo (1..6) at ms: each its own period, 3..5.5 s."""
    period = 3000 + 500 * servo
    return 500 + _WAVE[(ms % period) * 1000 // period]


class Replies:
    """The leader's replies as they reached the board's pin: {positions: us of the last byte},
    read from w.arrived as it grows (its last KEEP_LOG bytes)."""

    def __init__(self, w, ids):
        self.w = w
        self.ids = ids
        self.seen = 0
        self.buf = []
        self.at = {}

    def collect(self):
        w = self.w
        total = w.arrived_total
        new = total - self.seen
        if not new:
            return
        got = w.arrived[-new:]
        self.seen = total
        buf = self.buf
        for us, b in got:
            buf.append(b)
            # A reply to the leader's request: 55 55 Length 21 6 (id lo hi) x 6.
            if len(buf) >= 4 and (buf[0] != 0x55 or buf[1] != 0x55 or buf[3] != 21):
                del buf[0]
                while buf and buf[0] != 0x55:
                    del buf[0]
                continue
            if len(buf) >= 4 and len(buf) == buf[2] + 2:
                ids = tuple(buf[i] for i in range(5, len(buf), 3))
                if ids == self.ids:
                    pose = tuple(buf[i + 1] | buf[i + 2] << 8 for i in range(5, len(buf), 3))
                    self.at[pose] = us
                buf.clear()


def percentile(bins, p):
    """The p-th percentile, in ms, of the latencies counted in 0.1 ms bins (None if none)."""
    n = sum(bins)
    if not n:
        return None
    want = (n * p + 99) // 100  # the rank of the p-th percentile, 1-based
    seen = 0
    for i, count in enumerate(bins):
        seen += count
        if seen >= want:
            return (i + 1) / 10  # the bin's top: within 0.1 ms
    return None


def measure(port, config, seconds=SECONDS, faults=False):
    """One case: a dict of its figures."""
    clock = wire.Clock()
    wl = wire.World(port, clock=clock)
    saved = busservo.time, bm.time, bt.time
    busservo.time = bm.time = bt.time = clock
    try:
        lbus = busservo.BusServo(wl.uart)
        if config == "two":
            wf = wire.World(port, clock=clock)
            fbus = busservo.BusServo(wf.uart)
            first = 1
        else:
            wf, fbus, first = wl, lbus, 7
        lead = bm.Robot(lbus, {n: bm.Joint(1 + i) for i, n in enumerate(NAMES)})
        follow = bm.Robot(fbus, {n: bm.Joint(first + i) for i, n in enumerate(NAMES)})
        t = bt.Teleop(lead, follow, dps=90, rest=False)
        t.warn = lambda text: None
        replies = Replies(wl, (1, 2, 3, 4, 5, 6))
        follower_ids = tuple(range(first, first + 6))
        latencies = [0] * 3000  # how many came in each 0.1 ms, up to 300 ms (made once)
        counted = [0, None]  # moves carrying a reply, once engaged; when the count began

        def arrived(us, frame):
            if frame[3] != busservo.CMD_SERVO_MOVE or frame[7] != first:
                return
            pose = tuple(frame[i + 1] | frame[i + 2] << 8 for i in range(7, len(frame), 3))
            replies.collect()
            came = replies.at.pop(pose, None)
            if came is not None and counted[1] is not None:
                counted[0] += 1
                latencies[min((us - came) // 100, 2999)] += 1

        wf.on_frame = arrived
        start = clock.now_us
        end = start + seconds * 1000000
        turned = fault = -1
        aborts = 0
        kinds = 0
        sim = wl.sim
        while clock.now_us < end:
            ms = (clock.now_us - start) // 1000
            if ms // HAND_MS != turned:
                turned = ms // HAND_MS
                sim = wl.sim
                for s in range(1, 7):
                    sim.turn(s, hand(ms, s))
            if counted[1] is None and t.engaged:
                counted[1] = clock.now_us
            if faults and ms // FAULT_MS != fault:
                fault = ms // FAULT_MS
                if fault:
                    kind = kinds % 4
                    kinds += 1
                    if kind == 0:
                        wl.late(300)
                    elif kind == 1:
                        wl.drop(3, skip=6)
                    elif kind == 2:
                        wl.noise(b"\x55\x55\x14\x15\x06\x01")
                    else:
                        wl.cut_reply(9)
            try:
                t.step()
            except Exception as e:  # an abort: the case ends
                aborts += 1
                print("abort:", repr(e))
                break
            if ms % 200 == 0:
                replies.collect()
                if len(replies.at) > 2000:  # those no move carried (a hold, a fault)
                    replies.at.clear()
            clock.advance_us(STEP_US)
        began = counted[1] or end
    finally:
        busservo.time, bm.time, bt.time = saved
    span = (end - began) / 1e6
    rate = counted[0] / span if span > 0 else 0
    return {
        "port": port,
        "config": config,
        "faults": faults,
        "seconds": seconds,
        "rate": rate,
        "percent": 100 * rate / LIMITS[config],
        "median_ms": percentile(latencies, 50),
        "p99_ms": percentile(latencies, 99),
        "reads": t.reads,
        "moves": t.moves,
        "timeouts": t.timeouts,
        "aborts": aborts,
        "noise": lbus.noise,
        "ids": follower_ids,
    }


def main(seconds=SECONDS, ports=wire.PORTS, out=print):
    out(
        "A hand moves the leader's six joints; step() every %.1f ms; %d s of simulated time a"
        " case." % (STEP_US / 1000, seconds)
    )
    out("")
    out(
        "| port | configuration | faults | cycles/s | % of the limit | latency median / 99th "
        "percentile, ms | timeouts | aborts |"
    )
    out("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: |")
    results = []
    for config in ("two", "one"):
        for port in ports:
            for faults in (False, True):
                r = measure(port, config, seconds, faults)
                results.append(r)
                out(
                    "| %s | %s | %s | %.1f | %.1f %% | %.1f / %.1f | %d | %d |"
                    % (
                        port,
                        "two UARTs" if config == "two" else "one bus",
                        "every 5 s" if faults else "none",
                        r["rate"],
                        r["percent"],
                        r["median_ms"] or 0,
                        r["p99_ms"] or 0,
                        r["timeouts"],
                        r["aborts"],
                    )
                )
    return results


def budget(n=2000, out=print):
    """A step's time against move_many()'s (six servos), on the fake UART of the allocation
    tests and the test clock (stepped 40 ms a cycle), timed by the unix port's own clock: a
    cycle's step (the reply decoded, the follower's move, the next request and its ask()),
    and a step that waits for a reply. A busy machine blurs it: run it on a quiet one."""
    import time as real

    from fakeuart import FakeUART

    clock = wire.Clock()
    saved = busservo.time, bm.time, bt.time
    busservo.time = bm.time = bt.time = clock
    try:
        lu, fu = FakeUART(), FakeUART()
        lbus, fbus = busservo.BusServo(lu), busservo.BusServo(fu)
        lead = bm.Robot(lbus, {name: bm.Joint(1 + i) for i, name in enumerate(NAMES)})
        follow = bm.Robot(fbus, {name: bm.Joint(1 + i) for i, name in enumerate(NAMES)})
        t = bt.Teleop(lead, follow, rest=False)
        t.warn = lambda text: None

        def reply(position):
            frame = bytearray((0x55, 0x55, 21, 21, 6))
            for servo_id in range(1, 7):
                frame += bytes((servo_id, position & 0xFF, position >> 8))
            return bytes(frame)

        t.step()
        clock.advance_ms(40)
        fu.feed(reply(500))
        t.step()
        replies = [reply(495 + k) for k in range(10)]
        cycle = wait = 0
        for k in range(n):
            clock.advance_ms(40)
            lu.clear()
            fu.clear()
            lu.feed(replies[k % 10])
            a = real.ticks_us()
            t.step()
            cycle += real.ticks_diff(real.ticks_us(), a)
            a = real.ticks_us()
            t.step()
            wait += real.ticks_diff(real.ticks_us(), a)
        pairs = [[servo_id, 500] for servo_id in range(1, 7)]
        many = 0
        for _ in range(n):
            fu.clear()
            a = real.ticks_us()
            fbus.move_many(pairs, 40)
            many += real.ticks_diff(real.ticks_us(), a)
    finally:
        busservo.time, bm.time, bt.time = saved
    out(
        "%d cycles (%d moves): a cycle's step %.1f us, a waiting step %.1f us, move_many() of "
        "six %.1f us: %.1fx and %.2fx move_many()"
        % (n, t.moves, cycle / n, wait / n, many / n, cycle / many, wait / many)
    )


if __name__ == "__main__":
    import sys

    if "--budget" in sys.argv:
        budget()
    else:
        main(int(sys.argv[1]) if len(sys.argv) > 1 else SECONDS)
