# The arm's figures, side by side in one run (lib/busservo_arm.py, on the typical arm of
# tests/test_arm.py: base_height 70, upper_arm 105, forearm 98, hand 150 mm):
#
#   1. round trip: for a grid of targets over the space around the arm, the ones pose() takes
#      (in reach, within the joints' limits), the positions move_to() sends (each joint's
#      Joint.position() of the pose), back to millimetres: how far from the target.
#   2. line_to: on the wire-faithful world (tests/wire.py: rp2 and esp32 UART models, a
#      9600-baud line, the simulated controller, a simulated clock), a loop stepping the line
#      every ms, with the line's four joints alone in the frames, and with a roll and a gripper
#      streamed beside them (six servos a frame). Updates/s against the wire's limit, and the
#      tool point's largest distance from the line: at the positions the frames carried, and
#      along the way the simulated servos went (each straight from one position to the next
#      over its frame's time, as a bus servo does), sampled every ms.
#   3. the solve, on the unix port in real time: move_to() as a ratio to a move_many() of the
#      same four joints (both to the fake UART of tests/fakeuart.py, which costs next to
#      nothing), pose() alone, with a pitch and with none; and heap bytes per call (exact).
#
#   sh boards/unix.sh tests/bench_arm.py      # prints Markdown tables
#
# 1 and 2 are simulated: the same figures every run, on any machine. 3 is this machine's: its
# ratios say more than its microseconds.
import gc
import math
import time

import busservo
import busservo_arm as ba
import busservo_motion as bm
import wire
from fakeuart import FakeUART

LINKS = {"base_height": 70, "upper_arm": 105, "forearm": 98, "hand": 150}
START = (120, -100, 20)  # a line across the front of the arm, the hand pointing down
END = (120, 100, 20)
SPEEDS = (50, 100, 200)  # mm/s
GRID = (range(-100, 351, 25), range(-300, 301, 25), range(-50, 351, 25), (None, -45, 0))
CALLS = 500  # real-time calls a figure


def robot(bus, more=False):
    """The joints of tests/test_arm.py's arm: limits as a real arm's; with more, a roll and a
    gripper too."""
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


def limit(n):
    """Frames a second that 9600 baud lets through, n servos a frame."""
    return 960 / (3 * n + 7)


def frame_ms(n):
    """A frame of n servos' time on the wire, in ms."""
    return (3 * n + 7) * 10 / 9.6


def off_line(p, start, end):
    """The distance in mm of point p from the segment start..end."""
    d = [e - s for s, e in zip(start, end)]
    q = [a - s for s, a in zip(start, p)]
    dd = sum(c * c for c in d)
    u = max(0.0, min(1.0, sum(a * b for a, b in zip(q, d)) / dd)) if dd else 0.0
    return math.sqrt(sum((a - u * b) ** 2 for a, b in zip(q, d)))


def point(arm, positions):
    """(x, y, z, pitch) at {servo id: position}."""
    joints = arm.robot.joints
    return arm.point({n: joints[n].degrees(positions[joints[n].servo_id]) for n in ba.JOINTS})


def round_trip(grid=GRID):
    """Targets tried, reached, and the round trip's mean and largest error (mm), and the
    largest in pitch (degrees) where a pitch was asked for."""
    arm = ba.Arm(robot(None), LINKS)
    joints = arm.robot.joints
    tried = reached = 0
    total = worst = worst_pitch = 0.0
    xs, ys, zs, pitches = grid
    for x in xs:
        for y in ys:
            for z in zs:
                for pitch in pitches:
                    tried += 1
                    try:
                        pose = arm.pose(x, y, z, pitch)
                    except ValueError:
                        continue
                    reached += 1
                    sent = {n: joints[n].position(pose[n]) for n in ba.JOINTS}
                    got = point(arm, {joints[n].servo_id: p for n, p in sent.items()})
                    off = math.sqrt((got[0] - x) ** 2 + (got[1] - y) ** 2 + (got[2] - z) ** 2)
                    total += off
                    worst = max(worst, off)
                    if pitch is not None:
                        worst_pitch = max(worst_pitch, abs(ba._wrap(got[3] - pitch)))
    return {
        "tried": tried,
        "reached": reached,
        "mean_mm": total / reached,
        "max_mm": worst,
        "max_pitch": worst_pitch,
    }


def line(port, n, mm_s, start=START, end=END):
    """One line on the wire-faithful world: a dict of its figures."""
    w = wire.World(port)
    saved = busservo.time, bm.time, ba.time
    busservo.time = bm.time = ba.time = w.clock
    try:
        bus = busservo.BusServo(w.uart)
        r = robot(bus, n == 6)
        arm = ba.Arm(r, LINKS)
        arm.move_to(*start, pitch=-90, ms=0)
        w.run_ms(100)
        first = w.frames_total
        ln = arm.line_to(*end, pitch=-90, mm_s=mm_s)
        joints = [r.joints[name] for name in ba.JOINTS]
        ids = [j.servo_id for j in joints]
        path = 0.0  # the servos' way: the largest distance from the line
        blocked = 0
        tick = 0
        done = None  # when the line sent its last frame, in us
        while done is None or w.clock.now_us - done < 300000:  # the servos get there
            extra = n == 6 and not ln.done
            if extra:
                r.stream({"roll": tick % 90, "gripper": 30})
            before = w.clock.now_us
            ln.step()
            if extra:
                r.step()  # the roll's and the gripper's, between the line's
            blocked = max(blocked, w.clock.now_us - before)
            if ln.done and done is None:
                done = w.clock.now_us
            while bus.poll() is not None:
                pass
            w.clock.advance_ms(1)
            tick += 1
            sim = w.sim
            p = point(arm, {i: sim.position(i) for i in ids})
            path = max(path, off_line(p[:3], start, end))
        # The line's frames: those that carry its joints, until its last was in.
        times = []
        sent = []
        for at, f in w.arrivals(first):
            if at > done + frame_ms(n) * 1000 + 2000:
                break
            positions = {f[i]: f[i + 1] | f[i + 2] << 8 for i in range(7, len(f), 3)}
            if f[3] == busservo.CMD_SERVO_MOVE and ids[0] in positions:
                times.append(at)
                sent.append([positions[i] for i in ids])
        worst = chord = 0.0
        for k, positions in enumerate(sent):
            worst = max(worst, off_line(point(arm, dict(zip(ids, positions)))[:3], start, end))
            if k:  # each joint straight from the frame before's position to this one's
                for f in range(1, 8):
                    mid = [a + (b - a) * f / 8 for a, b in zip(sent[k - 1], positions)]
                    pose = {name: j.degrees(q) for name, j, q in zip(ba.JOINTS, joints, mid)}
                    chord = max(chord, off_line(arm.point(pose)[:3], start, end))
        last = point(arm, {i: w.sim.position(i) for i in ids})
    finally:
        busservo.time, bm.time, ba.time = saved
    rate = (len(times) - 1) * 1000000 / (times[-1] - times[0])
    return {
        "port": port,
        "n": n,
        "mm_s": mm_s,
        "ms": ln.ms,
        "updates": ln.updates,
        "frames": len(times),
        "rate": rate,
        "percent": 100 * rate / limit(n),
        "at_frames_mm": worst,
        "between_mm": chord,
        "on_the_way_mm": path,
        "end_mm": math.sqrt(sum((a - b) ** 2 for a, b in zip(last[:3], end))),
        "blocked_us": blocked,
        "lost": w.garbled + w.sim.beeps,
    }


def real_us(call, calls=CALLS):
    """Mean real microseconds a call, in batches (the fake UART emptied between them)."""
    total = 0
    done = 0
    while done < calls:
        UART.clear()
        start = time.ticks_us()
        for _ in range(50):
            call()
        total += time.ticks_diff(time.ticks_us(), start)
        done += 50
    return total / done


def heap(call, before=None, calls=20):
    """Heap bytes a call (gc.mem_alloc() with the collector off), after one to warm up."""
    if before:
        before()
    call()
    gc.collect()
    gc.disable()
    total = 0
    try:
        for _ in range(calls):
            if before:
                before()
            start = gc.mem_alloc()
            call()
            total += gc.mem_alloc() - start
    finally:
        gc.enable()
    return total // calls


UART = FakeUART()


def solve(calls=CALLS):
    """The solve's figures: real us a call, and heap bytes a call."""
    bus = busservo.BusServo(UART)
    arm = ba.Arm(robot(bus), LINKS)
    joints = arm.robot.joints
    pose = arm.pose(150, 0, 40, -90)
    pairs = [(joints[n].servo_id, joints[n].position(pose[n])) for n in ba.JOINTS]
    far = (300, 0, 70)  # the hand cannot point down there: no pitch means a search
    cases = (
        ("move_many() of the 4 joints", lambda: bus.move_many(pairs, 500)),
        ("move_to(x, y, z, pitch, ms=)", lambda: arm.move_to(150, 0, 40, -90, ms=500)),
        ("move_to(x, y, z, ms=): pitch -90 reached", lambda: arm.move_to(150, 0, 40, ms=500)),
        ("move_to(x, y, z, ms=): pitch searched", lambda: arm.move_to(*far, ms=500)),
        ("pose(x, y, z, pitch)", lambda: arm.pose(150, 0, 40, -90)),
        ("pose(x, y, z): pitch searched", lambda: arm.pose(*far)),
        ("point(pose)", lambda: arm.point(pose)),
    )
    out = []
    for name, call in cases:
        UART.clear()
        out.append({"what": name, "us": real_us(call, calls), "heap": heap(call, UART.clear)})
    # A line's step() that sends, and one that finds the wire busy: on a stepped clock.
    clock = wire.Clock()
    saved = busservo.time, bm.time, ba.time
    busservo.time = bm.time = ba.time = clock
    try:
        arm = ba.Arm(robot(busservo.BusServo(UART)), LINKS)
        arm.move_to(*START, pitch=-90, ms=0)
        clock.advance_ms(40)
        ln = arm.line_to(*END, pitch=-90, mm_s=10)

        def free():
            clock.advance_ms(25)
            UART.clear()

        sends = heap(ln.step, free)
        busy = heap(ln.step)
    finally:
        busservo.time, bm.time, ba.time = saved
    out.append({"what": "a line's step() that sends", "us": None, "heap": sends})
    out.append({"what": "a line's step(), the wire busy", "us": None, "heap": busy})
    base = out[0]["us"]
    for r in out:
        r["ratio"] = r["us"] / base if r["us"] is not None else None
    return out


def main(ports=wire.PORTS, speeds=SPEEDS, grid=GRID, calls=CALLS, out=print):
    """Measure all, print the tables with out(), return (round trip, lines, solve)."""
    rt = round_trip(grid)
    out("Round trip: %d targets of a grid in reach, of %d tried." % (rt["reached"], rt["tried"]))
    out("")
    out("| arm | targets | mean, mm | max, mm | max pitch error, degrees |")
    out("| --- | ---: | ---: | ---: | ---: |")
    out(
        "| 70 / 105 / 98 / 150 mm | %d | %.2f | %.2f | %.2f |"
        % (rt["reached"], rt["mean_mm"], rt["max_mm"], rt["max_pitch"])
    )
    out("")
    out(
        "A bus servo's position is 0.24 degree (1000 over 240): rounding to one moves a joint"
        " 0.12 degree at most, 0.74 mm at the arm's full reach of 353 mm."
    )
    out("")
    out(
        "line_to(): (%d, %d, %d) to (%d, %d, %d) mm, the hand down, stepped every ms."
        % (START + END)
    )
    out("")
    out(
        "| port | N | mm/s | ms | updates/s | % of the wire's limit | from the line: at the "
        "frames | between them | on the servos' way | end | step() max, us | lost |"
    )
    out("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    lines = []
    for port in ports:
        for n in (4, 6):
            for mm_s in speeds:
                r = line(port, n, mm_s)
                lines.append(r)
                out(
                    "| %s | %d | %d | %d | %.1f | %.1f %% | %.2f | %.2f | %.2f | %.2f | %d | %d |"
                    % (
                        port,
                        n,
                        mm_s,
                        r["ms"],
                        r["rate"],
                        r["percent"],
                        r["at_frames_mm"],
                        r["between_mm"],
                        r["on_the_way_mm"],
                        r["end_mm"],
                        r["blocked_us"],
                        r["lost"],
                    )
                )
    out("")
    out(
        "Distances in mm. The wire's limit: one frame of N servos, 3N + 7 bytes at 9600 baud: "
        + ", ".join("%.1f a second for %d" % (limit(n), n) for n in (4, 6))
        + ". Between the frames: each joint straight from one frame's position to the next"
        " (as a bus servo goes), exactly; on the servos' way: the simulated servos, which are"
        " at whole positions, every ms; end: where they stopped, 300 ms after the last frame."
    )
    out("")
    figures = solve(calls)
    out("The solve on the unix port, real time, %d calls a figure:" % calls)
    out("")
    out("| call | us a call | × move_many() | heap bytes a call |")
    out("| --- | ---: | ---: | ---: |")
    for r in figures:
        us = "-" if r["us"] is None else "%.1f" % r["us"]
        ratio = "-" if r["ratio"] is None else "%.1f" % r["ratio"]
        out("| %s | %s | %s | %d |" % (r["what"], us, ratio, r["heap"]))
    return rt, lines, figures


if __name__ == "__main__":
    main()
