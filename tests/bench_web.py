# The web panel's figures: its page's size, the RAM it adds, the latency from a slider
# event to its frame leaving the wire, and how long the loop ever stands still. The panel
# serves the robot of tests/web_world.py (the simulated controller behind an rp2's UART and
# a 9600-baud line, on real time), and a client in the same process plays the page: it polls
# /api/state 5 times a second, as an open page does, and sends slider targets.
#
#   sh boards/unix.sh tests/bench_web.py          # prints a Markdown table
#   sh boards/unix.sh tests/bench_web.py quick    # fewer samples (tests/test_bench_web.py)
#   sh boards/unix.sh tests/bench_web.py --32bit PATH   # and the heap it needs on a board
#   sh boards/unix.sh tests/bench_web.py --help         # this text (also -h); runs nothing
#
# - page: lib/busservo_web.html.gz as served (goal: 12 KB at most).
# - RAM, measured on the unix port with gc.mem_alloc() after gc.collect(): what importing
#   busservo_web adds to a process that has busservo and busservo_motion, and
#   what serving adds on top while one client is connected (its request half sent). The unix
#   port is 64-bit: a 32-bit board's objects take about 40 % less.
# - latency: from the moment the page's target request starts (before it connects) to when
#   the controller had the last byte of the frame that carries it (the world's arrivals),
#   for a drag of one joint and of all four. Goal: one frame's wire time plus 50 ms.
# - stall: while one page captures poses and adds them (each a positions query) and another,
#   armed, streams a slider, the longest the event loop stood still (a task that sleeps 1 ms
#   and notes the gap beyond it), and the longest gap between two of the panel's ticks (due
#   every 10 ms). A query that blocked would stall both for its round trip (30 ms and more);
#   the goal is a frame's decode. The client runs in the same process: its own work is in
#   the figure too; so is the machine's (the same with no page at all is given beside it).
#   Each is the median of 3 runs of 5 s (quick: one run of 1 s).
# - with --32bit PATH, PATH being MicroPython's unix port built for 32 bits (a board's object
#   sizes; the 64-bit port's figures run about 1.4x higher): the smallest heap the panel
#   serves at, installed as lib/busservo_web.json has mip install it (.mpy) and from source,
#   each in a folder of its own, run by tests/bench_web_board.py with -X heapsize=N. It
#   serves if, in every one of RUNS runs, one page loads it, logs in, arms, drives a slider,
#   captures, adds, plays, halts, removes and stops while a second page polls, each answer
#   200 and whole, and the panel says no error; and with an arm (.mpy), if a page jogs,
#   starts a calibration, cancels it and jogs again. Heaps are tried from the top down, to
#   the first that fails a run. Then the RAM each module keeps after its import (asyncio is
#   frozen in that port, as on a board), and the most the panel holds while serving them.
import asyncio
import gc
import json
import os
import sys
import time

import busservo
import busservo_motion as bm
from shell import free_port, scratch, sh, start, stop, wait_for


def arguments(args):
    """The command line, checked: --help prints this file's header and runs nothing; an
    argument it does not know gets a usage line (exit status 2), never a traceback."""
    if "--help" in args or "-h" in args:
        with open(sys.argv[0]) as f:
            for line in f:
                if not line.startswith("#"):
                    break
                print(line[2:].rstrip())
        sys.exit(0)
    i = 0
    while i < len(args):
        if args[i] == "--32bit" and i + 1 < len(args):
            i += 1  # its PATH
        elif args[i] != "quick":
            said = "unknown argument %r" % args[i]
            if args[i] == "--32bit":
                said = "--32bit wants a PATH"
            print("bench_web.py: %s (sh boards/unix.sh tests/bench_web.py --help)" % said)
            sys.exit(2)
        i += 1


arguments(sys.argv[1:])
web_world = None  # imported after ram() has measured busservo_web's import

PASSWORD = "bench-pw-1"
MICROPYTHON32 = sys.argv[sys.argv.index("--32bit") + 1] if "--32bit" in sys.argv else None
RUNS = 5
PAGES_MS = 60000  # a run's pages must be done within this (they take about 3 s)
HEAPS = {  # KB, the first tried first
    "mpy": (64, 62, 60, 59, 58, 57, 56, 54, 52),
    "py": (160, 144, 128, 120, 112, 104, 96),
    "arm": (96, 88, 84, 80, 78, 76, 74, 72),  # .mpy, with an arm: jogging and calibrating
}


# The arm of the heap's arm case: its joints, and its links (mm).
ARM = {
    "base": bm.Joint(1),
    "shoulder": bm.Joint(2, limits=(-90, 90)),
    "elbow": bm.Joint(3, limits=(-120, 120)),
    "wrist": bm.Joint(4, limits=(-120, 120)),
}
LINKS = {"base_height": 70, "upper_arm": 105, "forearm": 98, "hand": 150}


class Unplugged:
    """A UART with nothing on it: the arm's Robot, to save() its joints."""

    def any(self):
        return 0

    def readinto(self, buf, n=None):
        return None

    def write(self, buf, off=0, n=None):
        return 0


def frame_ms(n):
    """A CMD_SERVO_MOVE of n servos on the wire at 9600 baud: 3n + 7 bytes of 10 bits."""
    return (3 * n + 7) * 10 / 9.6


def page_size():
    with open("lib/busservo_web.html.gz", "rb") as f:
        gz = len(f.read())
    return gz, os.stat("lib/busservo_web.html")[6]


def ram():
    """(bytes importing busservo_web adds, bytes serving adds with a client connected)."""
    global web_world
    gc.collect()
    before = gc.mem_alloc()
    import busservo_web

    gc.collect()
    imported = gc.mem_alloc() - before
    import web_world

    world = web_world.live()
    robot = web_world.robot(world)
    port = free_port()
    figures = []

    async def main():
        gc.collect()
        start = gc.mem_alloc()
        server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, port))
        await asyncio.sleep_ms(100)
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        await writer.awrite(b"GET /api/state HTTP/1.0\r\nHost: x\r\n")  # half a request
        await asyncio.sleep_ms(100)
        gc.collect()
        figures.append(gc.mem_alloc() - start)
        await writer.awrite(b"\r\n")
        await reader.read(1024)
        await writer.aclose()
        server.cancel()
        await asyncio.sleep_ms(20)

    asyncio.run(main())
    busservo.time = bm.time = time
    return imported, figures[0]


def latency(joints, samples):
    """Each sample's ms from a target request's start to its frame off the wire."""
    import busservo_web  # noqa: F401 (imported by ram() first, for its figure)

    world = web_world.live()
    robot = web_world.robot(world)
    names = robot.names[:joints]
    port = free_port()
    found = []

    async def page(token, stop):
        while not stop:
            await web_world.http(port, "GET", "/api/state", token=token)
            await asyncio.sleep_ms(200)

    async def main():
        server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, port))
        await asyncio.sleep_ms(100)
        token = await web_world.login(port, PASSWORD)
        http = web_world.http
        await http(port, "POST", "/api/arm", {"on": True}, token)
        stop = []
        asyncio.create_task(page(token, stop))
        for k in range(samples):
            degrees = 10 + 3 * k % 50  # a new target each time
            seen = world.frames_total
            start = world.clock.now_us
            await http(
                port, "POST", "/api/target", {"targets": {n: degrees for n in names}}, token
            )
            want = {robot.joints[n].servo_id: robot.joints[n].position(degrees) for n in names}
            while True:
                frames = world.arrivals(seen)
                hit = [
                    us for us, f in frames if f[3] == busservo.CMD_SERVO_MOVE and carries(f, want)
                ]
                if hit:
                    found.append((hit[0] - start) / 1000)
                    break
                if world.clock.now_us - start > 2000000:
                    found.append(None)
                    break
                await asyncio.sleep_ms(1)
            await asyncio.sleep_ms(150)  # a drag's next event comes later
        stop.append(1)
        await asyncio.sleep_ms(250)
        server.cancel()
        await asyncio.sleep_ms(20)

    asyncio.run(main())
    busservo.time = bm.time = time
    return found


def stall(seconds, pages=True, use=None):
    """(the event loop's longest stall, the panel loop's longest gap between two ticks, how
    many poses were captured), in ms, while one page captures poses and adds them to the
    sequence, and another, armed, streams a slider and polls the state as an open page
    does (without pages: the panel and its world alone, the floor of the figure on this
    machine). A blocking query stalls both for its round trip. use "jog": an arm instead,
    the armed page jogging it back and forth; "calibrate": the armed page calibrating it
    while hands sweep its limp joints (the third figure: jogs, or positions reads)."""
    import busservo_web

    world = web_world.live()
    robot = web_world.robot(world)
    arm = None
    if use:
        import busservo_arm

        robot = bm.Robot(robot.bus, ARM)  # bent at the servos' 500: a tool point to jog
        arm = busservo_arm.Arm(robot, LINKS)
    port = free_port()
    worst = [0, 0, 0]  # us: the event loop's, the panel's ticks'; captures
    tick = busservo_web.Panel._tick
    last_tick = [None]

    def timed_tick(panel):
        now = time.ticks_us()
        if last_tick[0] is not None:
            worst[1] = max(worst[1], time.ticks_diff(now, last_tick[0]))
        last_tick[0] = now
        tick(panel)

    async def probe(stop):
        last = time.ticks_us()
        while not stop:
            await asyncio.sleep_ms(1)
            now = time.ticks_us()
            worst[0] = max(worst[0], time.ticks_diff(now, last) - 1000)
            last = now

    async def capturer(token, stop):
        http = web_world.http
        while not stop:
            status, reply = await http(port, "POST", "/api/capture", {}, token)
            status, reply = await http(port, "POST", "/api/add", {"ms": 500}, token)
            worst[2] += status == 200

    async def streamer(token, stop):
        http = web_world.http
        await http(port, "POST", "/api/arm", {"on": True}, token)
        k = 0
        while not stop:
            k += 1
            degrees = k % 60 - 30
            await http(port, "POST", "/api/target", {"targets": {"base": degrees}}, token)
            if k % 6 == 0:
                await http(port, "GET", "/api/state", token=token)
            await asyncio.sleep_ms(30)

    async def poller(token, stop):  # an open page
        while not stop:
            await web_world.http(port, "GET", "/api/state", token=token)
            await asyncio.sleep_ms(200)

    async def jogger(token, stop):
        http = web_world.http
        await http(port, "POST", "/api/arm", {"on": True}, token)
        k = 0
        while not stop:
            k += 1
            body = {"axis": "y", "by": 10 if k % 2 else -10}  # 250 ms at 40 mm/s
            status, reply = await http(port, "POST", "/api/jog", body, token)
            worst[2] += status == 200
            await http(port, "GET", "/api/state", token=token)
            await asyncio.sleep_ms(200)

    async def calibrator(token, stop):
        http = web_world.http
        await http(port, "POST", "/api/arm", {"on": True}, token)
        await http(port, "POST", "/api/calibrate", {"step": "start"}, token)
        await asyncio.sleep_ms(50)
        await http(port, "POST", "/api/calibrate", {"step": "rest"}, token)
        k = 0
        while not stop:  # the sweep: hands turn each joint, the page polls
            k += 1
            for i in (1, 2, 3, 4):
                world.sim.turn(i, 300 + (k * 37 + i * 101) % 400)
            await http(port, "GET", "/api/state", token=token)
            await asyncio.sleep_ms(150)
        worst[2] = panel[0].parts["busservo_web_calibrate"].cal.samples

    panel = []
    new = busservo_web.Panel.__init__

    def keep(self, *args):
        new(self, *args)
        panel.append(self)

    async def main():
        busservo_web.Panel.__init__ = keep
        server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, port, arm))
        await asyncio.sleep_ms(100)
        busservo_web.Panel.__init__ = new
        first = await web_world.login(port, PASSWORD)
        second = await web_world.login(port, PASSWORD)
        stop = []
        tasks = [streamer(second, stop), capturer(first, stop)] if pages else []
        if use:
            tasks = [jogger if use == "jog" else calibrator, poller]
            tasks = [tasks[0](first, stop), tasks[1](second, stop)]
        tasks = [asyncio.create_task(t) for t in tasks]
        await asyncio.sleep_ms(200)  # armed and streaming
        last_tick[0] = None
        worst[0] = worst[1] = worst[2] = 0
        watch = asyncio.create_task(probe(stop))
        await asyncio.sleep_ms(seconds * 1000)
        stop.append(1)
        for task in tasks + [watch]:
            await task
        server.cancel()
        await asyncio.sleep_ms(20)

    busservo_web.Panel._tick = timed_tick
    gc.collect()  # the worlds of the figures before: a big heap's collection is slow
    try:
        asyncio.run(main())
    finally:
        busservo_web.Panel._tick = tick
        busservo.time = bm.time = time
    return worst[0] / 1000, worst[1] / 1000, worst[2]


# The arm the stall figures jog and calibrate, as tests/browser.py's: bent where the servos
# are at 500.
ARM = {
    "base": bm.Joint(1),
    "shoulder": bm.Joint(2, trim=-30, limits=(-60, 90)),
    "elbow": bm.Joint(3, trim=-60, limits=(-30, 120)),
    "wrist": bm.Joint(4, trim=-60, limits=(-30, 120)),
}
LINKS = {"base_height": 70, "upper_arm": 105, "forearm": 98, "hand": 60}


def install(form):
    """A scratch folder with the panel as lib/busservo_web.json has mip install it (form
    "mpy"), or with the same modules' sources (form "py")."""
    folder = scratch("web-" + form)
    os.mkdir(folder)
    with open("lib/busservo_web.json") as f:
        package = json.load(f)
    for name, source in package["urls"]:
        if form == "py" and name.endswith(".mpy"):
            name = source = name[:-4] + ".py"
        sh("cp lib/%s %s/%s" % (source, folder, name))
    return folder


async def session(port, drive, bad):
    """A page on the panel at port: it loads, logs in and, with drive, arms, drags a slider,
    captures, adds, plays, halts, removes a step and stops; else it polls. What was not
    answered 200, or whole, goes in bad."""
    size = os.stat("lib/busservo_web.html.gz")[6]

    async def http(method, path, body=None, token=None):
        try:
            status, reply = await web_world.http(port, method, path, body, token)
        except OSError as e:  # the board is gone, or not listening
            status, reply = 0, {"error": repr(e)}
        if status != 200 or path == "/" and len(reply) != size:
            bad.append((method, path, status, str(reply)[:60]))
        return reply

    await http("GET", "/")
    reply = await http("POST", "/api/login", {"password": "bench-pw-32"})
    token = reply.get("token") if type(reply) is dict else None
    for path in ("/api/joints", "/api/sequences", "/api/state", "/api/steps"):
        await http("GET", path, token=token)
    if drive:
        await http("POST", "/api/arm", {"on": True}, token)
        for k in range(30):
            await http("POST", "/api/target", {"targets": {"base": k, "elbow": -k}}, token)
            if k % 5 == 0:
                await http("GET", "/api/state", token=token)
        pose = (await http("POST", "/api/capture", {}, token)).get("pose")
        await http("POST", "/api/add", {"pose": pose, "ms": 300}, token)
        await http("POST", "/api/add", {"ms": 5000}, token)
        await http("POST", "/api/play", {}, token)
        for _ in range(4):
            await http("GET", "/api/state", token=token)
            await asyncio.sleep_ms(100)
        await http("POST", "/api/stop", {}, token)
        await http("POST", "/api/remove", {"index": 0}, token)
        await http("GET", "/api/steps", token=token)
        await http("POST", "/api/estop", {}, token)
    else:
        for _ in range(40):
            await http("GET", "/api/state", token=token)
            await asyncio.sleep_ms(50)
    await asyncio.sleep_ms(100)
    state = await http("GET", "/api/state", token=token)
    if type(state) is not dict or state.get("error"):
        bad.append(("error", state))


async def arm_session(port, bad):
    """A page on the panel of an arm at port: it logs in, arms, drives the arm to a pose,
    jogs, starts a calibration and reads the rest pose, cancels, and jogs again, polling the
    state between. What was not answered 200 goes in bad."""

    async def http(method, path, body=None, token=None):
        try:
            status, reply = await web_world.http(port, method, path, body, token)
        except OSError as e:
            status, reply = 0, {"error": repr(e)}
        if status != 200:
            bad.append((method, path, status, str(reply)[:60]))
        return reply

    async def poll(n):
        for _ in range(n):
            await http("GET", "/api/state", token=token)
            await asyncio.sleep_ms(150)

    reply = await http("POST", "/api/login", {"password": "bench-pw-32"})
    token = reply.get("token") if type(reply) is dict else None
    await http("POST", "/api/arm", {"on": True}, token)
    pose = {"shoulder": 20, "elbow": 60, "wrist": 60}
    await http("POST", "/api/target", {"targets": pose}, token)
    await poll(8)
    await http("POST", "/api/jog", {"axis": "z", "by": -5}, token)
    await poll(5)
    for step in ("start", "rest"):
        await http("POST", "/api/calibrate", {"step": step}, token)
    await poll(5)
    await http("POST", "/api/calibrate", {"step": "cancel"}, token)
    await http("POST", "/api/jog", {"axis": "z", "by": 5}, token)
    await poll(5)


def board(folder, heap, port, watch=False, arm=False):
    """Run the panel in folder on the 32-bit port with heap KB and two pages on it (with arm:
    an arm's, and one page jogging and calibrating): (what went wrong, what the board
    printed)."""
    log = folder + ".log"
    if arm:  # the arm's joints, and its links, in the panel's calibration file
        robot = bm.Robot(busservo.BusServo(Unplugged()), ARM)
        robot.save(folder + "/robot.json", links=LINKS)
    pid = start(
        "MICROPYPATH=.frozen:%s %s -X heapsize=%dK tests/bench_web_board.py %d%s%s"
        % (
            folder,
            MICROPYTHON32,
            heap,
            port,
            " watch" if watch else "",
            " arm %s/robot.json" % folder if arm else "",
        ),
        log,
    )
    bad = []
    try:
        if wait_for(log, 10000, "serving"):

            async def pages():
                if arm:
                    await arm_session(port, bad)
                    return
                tasks = [asyncio.create_task(session(port, d, bad)) for d in (True, False)]
                for task in tasks:
                    await task

            try:  # a board that stops answering (its server ended) fails; the bench goes on
                asyncio.run(asyncio.wait_for_ms(pages(), PAGES_MS))
            except asyncio.TimeoutError:
                bad.append("it stopped answering")
        else:
            bad.append("it did not start")
    finally:
        stop(pid)
        time.sleep_ms(100)
        with open(log) as f:
            printed = f.read()
        os.remove(log)
    if "Error" in printed:
        bad.append(printed.strip().split("\n")[-1])
    return bad, printed


def heaps(form):
    """(the smallest heap in KB the panel in form ("mpy", "py", or "arm": .mpy with an arm)
    served at in every run, or None; the next heap tried, and how many runs it served)."""
    folder = install("py" if form == "py" else "mpy")
    smallest = None
    failed = None
    try:
        for heap in HEAPS[form]:
            served = 0
            for _ in range(RUNS):
                bad, _ = board(folder, heap, free_port(), arm=form == "arm")
                served += not bad
            if served < RUNS:
                failed = (heap, served)
                break
            smallest = heap
    finally:
        sh("rm -rf " + folder)
    return smallest, failed


def ram32():
    """([(module, bytes it keeps once imported)], the most the panel holds while serving
    two pages) on the 32-bit port, installed as mip installs it."""
    folder = install("mpy")
    measure = (
        "import gc;gc.collect();a=gc.mem_alloc()\n"
        'for m in ("asyncio", "busservo", "busservo_motion", "busservo_web",\n'
        '  "busservo_web_sliders", "busservo_web_teach"):\n'
        " __import__(m);gc.collect();b=gc.mem_alloc();print(m,b-a);a=b"
    )
    try:
        ok, out = sh("MICROPYPATH=.frozen:%s %s -c '%s'" % (folder, MICROPYTHON32, measure))
        kept = [(line.split()[0], int(line.split()[1])) for line in out.strip().split("\n")]
        bad, printed = board(folder, 256, free_port(), watch=True)
        held = [int(line.split()[1]) for line in printed.split("\n") if line[:5] == "held "]
    finally:
        sh("rm -rf " + folder)
    return kept, max(held) if held and not bad else None


def carries(frame, want):
    got = {frame[i]: frame[i + 1] | frame[i + 2] << 8 for i in range(7, len(frame), 3)}
    return all(got.get(k) == v for k, v in want.items())


def main(quick=False):
    samples = 5 if quick else 30
    gz, raw = page_size()
    imported, serving = ram()
    print("| figure | value | goal |")
    print("| --- | --- | --- |")
    print("| page, gzipped (raw) | %d bytes (%d) | 12288 bytes at most |" % (gz, raw))
    print("| RAM: import busservo_web | %d bytes | (unix port, 64-bit) |" % imported)
    print("| RAM: serving, one client connected | %d bytes more | (unix port, 64-bit) |" % serving)
    for joints in (1, 4):
        ms = latency(joints, samples)
        ok = sorted(x for x in ms if x is not None)
        goal = frame_ms(joints) + 50
        print(
            "| latency, slider to wire, %d joint%s | median %.1f ms, max %.1f ms, %d lost |"
            " %.1f ms (frame %.1f + 50) |"
            % (
                joints,
                "s" if joints > 1 else "",
                ok[len(ok) // 2],
                ok[-1],
                len(ms) - len(ok),
                goal,
                frame_ms(joints),
            )
        )
    # Each the median of 3 runs' longest: a shared machine's own pause hits one run.
    seconds, runs = (1, 1) if quick else (5, 3)
    busy = sorted(stall(seconds) for _ in range(runs))[runs // 2]
    idle = sorted(stall(seconds, pages=False) for _ in range(runs))[runs // 2]
    print(
        "| longest stall, a page capturing poses (%d), another streaming a slider |"
        " the event loop %.1f ms, the panel's ticks %.1f ms apart (no page: %.1f, %.1f) |"
        " a frame's decode (the ticks: %d ms apart) |"
        % (busy[2], busy[0], busy[1], idle[0], idle[1], 10)
    )
    for use, what, did in (
        ("jog", "the armed page jogging the arm, another polling", "jogs"),
        ("calibrate", "the armed page calibrating, hands sweeping", "sweep reads"),
    ):
        busy = sorted(stall(seconds, use=use) for _ in range(runs))[runs // 2]
        print(
            "| longest stall, %s | the event loop %.1f ms, the panel's ticks %.1f ms apart"
            " (%d %s) | a frame's decode |" % (what, busy[0], busy[1], busy[2], did)
        )
    if MICROPYTHON32:
        for form, how, goal in (
            ("mpy", "as mip installs it (.mpy)", "56 KB (the panel as one module's)"),
            ("py", "from source (.py)", ""),
            ("arm", ".mpy, an arm's page jogging, calibrating, jogging again", "80 KB"),
        ):
            smallest, failed = heaps(form)
            print(
                "| heap it serves at, 32-bit port, %s | %s in every run of %d%s | %s |"
                % (
                    how,
                    "%d KB" % smallest if smallest else "over %d KB" % HEAPS[form][0],
                    RUNS,
                    "; %d KB: %d of %d" % (failed[0], failed[1], RUNS) if failed else "",
                    goal,
                )
            )
        kept, held = ram32()
        print(
            "| RAM kept after import, 32-bit port: %s | %s = %d bytes | |"
            % (
                ", ".join(m for m, _ in kept),
                " + ".join(str(n) for _, n in kept),
                sum(n for _, n in kept),
            )
        )
        print("| RAM held while serving two pages, 32-bit port | %s bytes at most | |" % held)


main("quick" in sys.argv[1:])
