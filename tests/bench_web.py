# The web panel's figures: its page's size, the RAM it adds, the latency from a slider
# event to its frame leaving the wire, and how long the loop ever stands still. The panel
# serves the robot of tests/web_world.py (the simulated controller behind an rp2's UART and
# a 9600-baud line, on real time), and a client in the same process plays the page: it polls
# /api/state 5 times a second, as an open page does, and sends slider targets.
#
#   sh boards/unix.sh tests/bench_web.py          # prints a Markdown table
#   sh boards/unix.sh tests/bench_web.py quick    # fewer samples (tests/test_bench_web.py)
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
#   the figure too.
import asyncio
import gc
import os
import sys
import time

import busservo
import busservo_motion as bm

web_world = None  # imported after ram() has measured busservo_web's import

PORT = 18301
PASSWORD = "bench-pw-1"


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
    figures = []

    async def main():
        gc.collect()
        start = gc.mem_alloc()
        server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, PORT))
        await asyncio.sleep_ms(100)
        reader, writer = await asyncio.open_connection("127.0.0.1", PORT)
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
    found = []

    async def page(token, stop):
        while not stop:
            await web_world.http(PORT + joints, "GET", "/api/state", token=token)
            await asyncio.sleep_ms(200)

    async def main():
        server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, PORT + joints))
        await asyncio.sleep_ms(100)
        port = PORT + joints
        token = await web_world.login(port, PASSWORD)
        http = web_world.http
        await http(port, "POST", "/api/arm", {"on": True}, token)
        stop = []
        asyncio.create_task(page(token, stop))
        for k in range(samples):
            degrees = 10 + 3 * k % 50  # a new target each time
            seen = len(world.arrivals())
            start = world.clock.now_us
            await http(
                port, "POST", "/api/target", {"targets": {n: degrees for n in names}}, token
            )
            want = {robot.joints[n].servo_id: robot.joints[n].position(degrees) for n in names}
            while True:
                frames = world.arrivals()[seen:]
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


def stall(seconds):
    """(the event loop's longest stall, the panel loop's longest gap between two ticks, how
    many poses were captured), in ms, while one page captures poses and adds them to the
    sequence, and another, armed, streams a slider and polls the state as an open page
    does. A blocking query stalls both for its round trip."""
    import busservo_web

    world = web_world.live()
    robot = web_world.robot(world)
    port = PORT + 10
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

    async def main():
        server = asyncio.create_task(busservo_web.serve(robot, PASSWORD, port))
        await asyncio.sleep_ms(100)
        first = await web_world.login(port, PASSWORD)
        second = await web_world.login(port, PASSWORD)
        stop = []
        tasks = [streamer(second, stop), capturer(first, stop)]
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
    try:
        asyncio.run(main())
    finally:
        busservo_web.Panel._tick = tick
        busservo.time = bm.time = time
    return worst[0] / 1000, worst[1] / 1000, worst[2]


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
    loop, ticks, captured = stall(1 if quick else 5)
    print(
        "| longest stall, a page capturing poses (%d), another streaming a slider |"
        " the event loop %.1f ms, the panel's ticks %.1f ms apart |"
        " a frame's decode (the ticks: %d ms apart) |" % (captured, loop, ticks, 10)
    )


main("quick" in sys.argv[1:])
