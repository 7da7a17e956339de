# A 100 Hz control loop that sets new targets for every servo every tick, three ways, side
# by side in one run, on the wire-faithful test world (tests/wire.py: the rp2 and esp32
# UART models, a 9600-baud line, the simulated controller, a simulated clock):
#
#   1. move:       one bus.move() per servo per tick (the naive way);
#   2. move_many:  one bus.move_many() per tick;
#   3. stream:     arm.stream(targets) and arm.step() every tick (busservo_motion).
#
#   sh boards/unix.sh tests/bench_motion.py      # prints Markdown tables
#
# Simulated time only: the same figures every run, on any machine. What is measured:
#
# - The loop. Tick k starts at s(k); the loop computes tick k's targets (no simulated time),
#   calls the driver, and tick k+1 starts at s(k) + 10 ms, or at once if the driver calls
#   took longer than that (the loop is late, and its ticks are re-anchored there).
# - blocked per tick: the simulated time that passed inside the driver calls of one tick
#   (the clock before and after them). The world's clock moves while a UART call waits (rp2's
#   write() for room in its ring, esp32's until all is in its ring) and a little for every
#   UART call and ticks read, as a board's does.
# - Targets say which tick set them: servo s's position at tick k is 150 + (3k + 50s) % 700,
#   so each servo's target changes every tick. Way 3 streams it in degrees,
#   (position - 500) * 0.24, and a frame's position may differ from it by 1 (rounding).
# - A pose update reaches the controller when every servo's target of one tick has arrived
#   in whole move frames (w.arrivals(): each whole frame with the time its last byte was in):
#   one move_many frame, or for the naive way N move frames. updates/s: the poses of the run
#   that were complete within its simulated time, over that time. A frame whose targets are no
#   tick's is counted wrong. The physical limit is one move_many frame a pose, 3N + 7 bytes of
#   10 bits at 9600 baud: 960 / (3N + 7) a second; the naive way's own is 960 / (10N).
# - target age: for each pose that reached the controller, from the start of the tick that
#   set it to when its last byte was in (the last frame's, for the naive way).
# - lost/cut bytes: after the run, the wire is left to empty; then bytes the controller
#   received in no whole frame (cut or garbled, w.garbled and a frame's unfinished start) and
#   bytes still not sent. Also counted, and shown beside them if any: the controller's beeps,
#   OSErrors the driver raised, received bytes the UART lost, frames of no tick's targets.
import busservo
import busservo_motion as bm
import wire

TICK_US = 10000  # 100 Hz
TIME_MS = 20  # the moves' time, ways 1 and 2
SECONDS = 10  # simulated, per case
WAYS = ("move", "move_many", "stream")
SERVOS = (6, 18)
WINDOW = 100  # ticks a frame's targets are looked for in, from the last frame's tick on


def target(tick, servo):
    """Servo servo's position at tick tick: it changes every tick."""
    return 150 + (3 * tick + 50 * servo) % 700


def degrees(position):
    return (position - 500) * 0.24  # -120..120 degrees over 0..1000, 500 = 0


def limit(n):
    """Pose updates a second that one move_many frame a pose lets through 9600 baud."""
    return 960 / (3 * n + 7)


def frame_ms(n):
    """A move_many frame's time on the wire, in ms."""
    return (3 * n + 7) * 10 / 9.6


def loop(w, bus, n, way, seconds):
    """Run the 100 Hz loop for seconds of simulated time; (starts of the ticks in us, us
    blocked in the driver a tick, OSErrors raised)."""
    clock = w.clock
    ids = list(range(1, n + 1))
    if way == "stream":
        arm = bm.Robot(bus, {"j%d" % s: bm.Joint(s) for s in ids})
    starts = []
    blocked = []
    errors = 0
    start = clock.now_us
    end = start + seconds * 1000000
    tick = 0
    while start < end:
        starts.append(start)
        if way == "stream":
            degs = {"j%d" % s: degrees(target(tick, s)) for s in ids}
        else:
            pairs = [(s, target(tick, s)) for s in ids]
        before = clock.now_us
        try:
            if way == "move":
                for s, p in pairs:
                    bus.move(s, p, TIME_MS)
            elif way == "move_many":
                bus.move_many(pairs, TIME_MS)
            else:
                arm.stream(degs)
                arm.step()
        except OSError:
            errors += 1
        now = clock.now_us
        blocked.append(now - before)
        tick += 1
        start = max(start + TICK_US, now)
        clock.advance_us(start - now)
    return starts, blocked, errors


def match(pairs, starts, first, tol):
    """The first tick from first on whose targets the (id, position) pairs carry, or None."""
    for k in range(first, min(first + WINDOW, len(starts))):
        for s, p in pairs:
            if abs(p - target(k, s)) > tol:
                break
        else:
            return k
    return None


def measure(port, n, way, seconds=SECONDS):
    """One case: a dict of its figures (see the top of this file)."""
    w = wire.World(port, keep=seconds * 100 + 100)  # every frame: 96 a second at most
    # The driver's clock is the world's; the motion module's too, if it has one of its own.
    saved = busservo.time, getattr(bm, "time", None)
    busservo.time = w.clock
    if saved[1] is not None:
        bm.time = w.clock
    try:
        bus = busservo.BusServo(w.uart)
        t0 = w.clock.now_us
        starts, blocked, errors = loop(w, bus, n, way, seconds)
    finally:
        busservo.time = saved[0]
        if saved[1] is not None:
            bm.time = saved[1]
    end = t0 + seconds * 1000000
    backlog = w.tx_backlog_us()  # let the wire empty: what was written and can go, goes
    if backlog:
        w.run_ms(backlog // 1000 + 2)
    tol = 1 if way == "stream" else 0
    poses = {}  # tick: [ids arrived, when the one that made them all was in]
    wrong = 0
    whole = 0  # frames of one servo (the naive way's) or of n servos
    cursor = 0
    for at, frame in w.arrivals():
        if frame[3] != busservo.CMD_SERVO_MOVE:
            wrong += 1
            continue
        pairs = [
            (frame[i], frame[i + 1] | frame[i + 2] << 8) for i in range(7, 7 + 3 * frame[4], 3)
        ]
        k = None
        if all(1 <= s <= n for s, _ in pairs):
            k = match(pairs, starts, cursor, tol)
        if k is None:
            wrong += 1
            continue
        whole += len(pairs) in (1, n)
        cursor = k
        pose = poses.setdefault(k, [set(), 0])
        if len(pose[0]) < n:  # a pose reaches the controller once: a repeat is no update
            pose[0].update(s for s, _ in pairs)
            pose[1] = at
    ages = []
    for k, (got, at) in poses.items():
        if len(got) == n and at <= end:
            ages.append(at - starts[k])
    return {
        "port": port,
        "n": n,
        "way": way,
        "seconds": seconds,
        "ticks": len(starts),
        "frames": len(w.arrivals()),
        "whole": whole,
        "poses": len(ages),
        "rate": len(ages) / seconds,
        "percent": 100 * len(ages) / seconds / limit(n),
        "age_mean_ms": sum(ages) / len(ages) / 1000 if ages else None,
        "age_max_ms": max(ages) / 1000 if ages else None,
        "age_min_ms": min(ages) / 1000 if ages else None,
        "blocked_mean_ms": sum(blocked) / len(blocked) / 1000,
        "blocked_max_ms": max(blocked) / 1000,
        "lost": w.garbled + len(w.rest()) + w.tx_pending(),
        "beeps": w.sim.beeps,
        "errors": errors,
        "overrun": w.overrun,
        "wrong": wrong,
    }


def goals(r):
    """stream()'s goals, each (what, figure, goal, met)."""
    n = r["n"]
    age_goal = frame_ms(n) + TICK_US / 1000
    nothing = not (r["lost"] or r["beeps"] or r["errors"] or r["overrun"] or r["wrong"])
    return [
        ("of the limit", "%.1f %%" % r["percent"], ">= 95 %", r["percent"] >= 95),
        ("blocked max", "%.3f ms" % r["blocked_max_ms"], "<= 1 ms", r["blocked_max_ms"] <= 1),
        (
            "age max",
            "%.1f ms" % (r["age_max_ms"] or 0),
            "<= %.1f ms" % age_goal,
            r["age_max_ms"] is not None and r["age_max_ms"] <= age_goal,
        ),
        ("lost", "0" if nothing else "some", "nothing", nothing),
    ]


def lost_cell(r):
    cell = str(r["lost"])
    for key in ("beeps", "errors", "overrun", "wrong"):
        if r[key]:
            cell += ", %d %s" % (r[key], "OSError" if key == "errors" else key)
    return cell


def ms(x):
    return "-" if x is None else "%.1f" % x


def main(seconds=SECONDS, ports=wire.PORTS, servos=SERVOS, out=print):
    """Measure every case, print the tables with out(), return the cases' figures."""
    out(
        "A 100 Hz loop, new targets for every servo every tick, %d s of simulated time a case."
        % seconds
    )
    out("")
    out(
        "| port | N | way | updates/s | % of physical limit | target age mean / max, ms "
        "| blocked per tick mean / max, ms | lost/cut bytes |"
    )
    out("| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: |")
    results = []
    for port in ports:
        for n in servos:
            for way in WAYS:
                r = measure(port, n, way, seconds)
                results.append(r)
                out(
                    "| %s | %d | %s | %.1f | %.1f %% | %s / %s | %.3f / %.3f | %s |"
                    % (
                        port,
                        n,
                        "stream + step" if way == "stream" else way,
                        r["rate"],
                        r["percent"],
                        ms(r["age_mean_ms"]),
                        ms(r["age_max_ms"]),
                        r["blocked_mean_ms"],
                        r["blocked_max_ms"],
                        lost_cell(r),
                    )
                )
    out("")
    out(
        "Physical limit: one move_many frame a pose, 960 / (3N + 7) a second: "
        + ", ".join("%.1f for %d servos" % (limit(n), n) for n in servos)
        + ". The naive way sends N 10-byte frames a pose: its own limit is 960 / (10N), "
        + ", ".join("%.1f" % (96 / n) for n in servos)
        + "."
    )
    out("")
    out("stream()'s goals:")
    out("")
    for r in results:
        if r["way"] == "stream":
            said = [
                "%s %s (%s): %s" % (what, got, goal, "met" if ok else "NOT met")
                for what, got, goal, ok in goals(r)
            ]
            out("- %s, %d servos: %s" % (r["port"], r["n"], "; ".join(said)))
    return results


if __name__ == "__main__":
    main()
