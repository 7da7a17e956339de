# busservo's speed and memory, side by side with the vendor's technique, on the
# MicroPython unix port, and on CPython (a computer: the same modules, the same calls, in a
# CPython process this run starts, and six positions read end to end over a pty through
# pyserial, with the simulated controller at the far end). Prints Markdown tables. Not a test:
# machines are noisy, so read the ratios (both sides measured in the same run), not the
# microseconds.
#
#   sh boards/unix.sh tests/bench.py                     # the unix port's 2 MB heap
#   sh boards/unix.sh -X heapsize=128K tests/bench.py    # a board's heap
#   sh boards/unix.sh tests/bench.py --32bit PATH        # RAM on a 32-bit unix port too
#   .venv/bin/python tests/bench.py --cpython            # the CPython figures alone
#
# Times are means over many calls with the collector left to run when it must,
# so what a call allocates is paid for, as it is on a board, in collections.
# RAM is measured in a fresh unix port, as on a board after boot.
import gc
import os
import sys
import time

try:
    import micropython  # noqa: F401 (the unix port)
except ImportError:  # CPython: lib/ on the path, and what it lacks (tests/cpython.py)
    import cpython  # noqa: F401

import busservo
from shell import MICROPYTHON, PYTHON, scratch, sh
from test_alloc import CALLS, heap_per_call
from test_frames import BATTERY_7500, COMPLETE_8_ONCE, POSITIONS_ALL_500, RUN_8_ONCE, STOP

N = 30000  # calls timed per figure; `bench.py quick` times 300, to check that it runs
if "quick" in sys.argv:
    N = 300
# A unix port built for 32 bits (a board's object sizes), to measure the RAM on it too.
MICROPYTHON32 = sys.argv[sys.argv.index("--32bit") + 1] if "--32bit" in sys.argv else None


class ReplayUART:
    """Hands out one frame again and again: the rest of it to readinto(), as
    much as it asks for, and a byte to each read(1) (which allocates, as
    UART.read() does). Its write() takes every byte, as a UART with room in its
    transmit buffer does. Its own readinto() and write() allocate nothing, and
    copy as a port's does (in C): pieces of the frame the size of the buffer
    asked to fill are made once, and copied in with one slice assignment."""

    def __init__(self, frame=b""):
        self.frame = frame
        self.size = len(frame)
        self.at = 0
        self.pieces = None  # [piece] of the frame, each as long as the reader's buffer
        self.piece_size = 0

    def any(self):
        return self.size - self.at

    def readinto(self, buf, nbytes=None):
        n = self.size - self.at
        if nbytes is not None and nbytes < n:
            n = nbytes
        if len(buf) < n:
            n = len(buf)
        if len(buf) != self.piece_size:  # the first read: cut the frame to the buffer
            self.cut(len(buf))
        at = self.at
        piece = self.pieces[at // self.piece_size]
        if at % self.piece_size == 0 and n == len(piece):
            buf[0:n] = piece  # the usual case: what any() said, a buffer at a time
        else:
            for i in range(n):
                buf[i] = self.frame[at + i]
        self.at = (at + n) % self.size
        return n

    def cut(self, size):
        # Not in readinto(): a comprehension there would make a cell of `size` on every call.
        self.piece_size = size
        self.pieces = [self.frame[i : i + size] for i in range(0, self.size, size)]

    def read(self, nbytes=1):
        at = self.at
        self.at = (at + 1) % self.size
        return self.frame[at : at + 1]

    def write(self, buf, nbytes=None):
        return len(buf) if nbytes is None else nbytes


class VendorStyle:
    """The baseline, written the way the vendor's Python sample works: a fresh
    bytearray grown with append/extend per command, and a parser that reads
    one byte at a time with read(1) through a header/length/body state machine."""

    def __init__(self, uart):
        self.uart = uart
        self.state = 0
        self.length = 0
        self.data = bytearray()
        self.running = False
        self.group = None
        self.times = 0
        self.battery = None
        self.positions = {}

    def move(self, servo_id, position, time_ms):
        buf = bytearray()
        buf.append(0x55)
        buf.append(0x55)
        buf.append(8)
        buf.append(busservo.CMD_SERVO_MOVE)
        buf.append(1)
        buf.extend([time_ms & 0xFF, time_ms >> 8])
        buf.append(servo_id)
        buf.extend([position & 0xFF, position >> 8])
        self.uart.write(buf)

    def request_positions(self, ids):
        buf = bytearray()
        buf.append(0x55)
        buf.append(0x55)
        buf.append(len(ids) + 3)
        buf.append(busservo.CMD_MULT_SERVO_POS_READ)
        buf.append(len(ids))
        buf.extend(ids)
        self.uart.write(buf)

    def poll(self):
        while self.uart.any():
            byte = self.uart.read(1)[0]
            if self.state == 0:
                self.state = 1 if byte == 0x55 else 0
            elif self.state == 1:
                self.state = 2 if byte == 0x55 else 0
            elif self.state == 2:
                self.length = byte
                self.data = bytearray()
                self.state = 3
            else:
                self.data.append(byte)
                if len(self.data) == self.length - 1:
                    self.state = 0
                    return self.apply(self.data)
        return None

    def apply(self, data):
        cmd = data[0]
        if cmd == busservo.CMD_ACTION_GROUP_RUN or cmd == busservo.CMD_ACTION_GROUP_COMPLETE:
            self.running = cmd == busservo.CMD_ACTION_GROUP_RUN
            self.group = data[1]
            self.times = data[2] | data[3] << 8
        elif cmd == busservo.CMD_ACTION_GROUP_STOP:
            self.running = False
        elif cmd == busservo.CMD_GET_BATTERY_VOLTAGE:
            self.battery = data[1] | data[2] << 8
        elif cmd == busservo.CMD_MULT_SERVO_POS_READ:
            for i in range(2, 2 + 3 * data[1], 3):
                self.positions[data[i]] = data[i + 1] | data[i + 2] << 8
        return cmd


def us_per_call(call):
    gc.collect()
    start = time.ticks_us()
    for _ in range(N):
        call()
    return time.ticks_diff(time.ticks_us(), start) / N


def heap(call):
    return heap_per_call(call) / CALLS


def wire_us(nbytes):
    return nbytes * 10 * 1000000 / 9600  # 8N1: 10 bits a byte


def import_ram(folder, micropython=MICROPYTHON):
    # In a fresh unix port, as on a board after boot: (import, one instance).
    measure = (
        'import gc;U=type("U",(),{"any":int,"readinto":print,"write":print});gc.collect();'
        "a=gc.mem_alloc();import busservo;gc.collect();b=gc.mem_alloc();"
        "x=busservo.BusServo(U());gc.collect();print(b-a,gc.mem_alloc()-b)"
    )
    ok, out = sh("MICROPYPATH=.frozen:%s %s -c '%s'" % (folder, micropython, measure))
    return [int(x) for x in out.split()]


def mpy_figures(micropython32):
    # The .mpy the project builds (mpy-cross's default: line numbers kept), its
    # size, and the RAM it takes on this port and, given one, on a 32-bit port.
    folder = scratch("mpy")
    os.mkdir(folder)
    mpy = folder + "/busservo.mpy"
    ok, out = sh(".venv/bin/mpy-cross -s busservo.py -o %s lib/busservo.py" % mpy)
    size = os.stat(mpy)[6] if ok else None
    ram = import_ram(folder)
    ram32 = import_ram(folder, micropython32) if micropython32 else None
    sh("rm -rf " + folder)
    return size, ram, ram32


class IdleUART:
    """machine.UART with nothing waiting, as a control loop mostly sees it: any()
    is a C builtin that returns 0."""

    any = int

    def write(self, buf, nbytes=None):
        return len(buf) if nbytes is None else nbytes

    def readinto(self, buf, nbytes=None):
        return None  # nothing ever comes


BEFORE = "49553ae"  # the last commit before the reliability work (issue 9)


def side_by_side():
    # The hot paths of this driver and of the one before the reliability work
    # (taken from the git history into a scratch folder), timed in one run.
    folder = scratch("before")
    os.mkdir(folder)
    ok, out = sh("git show %s:lib/busservo.py >%s/busservo_before.py" % (BEFORE, folder))
    if not ok:
        sh("rm -rf " + folder)
        return None
    sys.path.insert(0, folder)
    import busservo_before

    sys.path.pop(0)
    sh("rm -rf " + folder)
    rows = []
    idle = IdleUART()
    now = busservo.BusServo(idle)
    then = busservo_before.BusServo(idle)
    # Five rounds, the three taken in turn, and the fastest of each: a busy
    # machine slows some rounds, never speeds one up.
    calls = (
        ("move", lambda: now.move(1, 500, 1000), lambda: then.move(1, 500, 1000)),
        ("poll(), idle", now.poll, then.poll),
    )
    best = {}
    for _ in range(5):
        best["any"] = min(best.get("any", 1e9), us_per_call(idle.any))
        for name, new, old in calls:
            best[name] = min(best.get(name, 1e9), us_per_call(new))
            best[name + " before"] = min(best.get(name + " before", 1e9), us_per_call(old))
    bare = best["any"]
    for name, _, _ in calls:
        new_us = best[name]
        old_us = best[name + " before"]
        rows.append((name, new_us, old_us, new_us / bare, old_us / bare))
    return bare, rows


# The calls timed on CPython too, by the names of main()'s rows.
ON_CPYTHON = (
    "move",
    "request_positions, 6 servos",
    "decode RUN",
    "decode STOP",
    "decode COMPLETE",
    "decode battery",
    "request and decode 6 positions",
)
PTY_READS = 200  # six positions read over the pty, for the median (quick: 10)


def cpython_main():
    # `python tests/bench.py --cpython`: a line per figure, "cpython|NAME|us|vendor us",
    # then "pty|median ms|fastest ms|reads".
    uart = ReplayUART()
    bus = busservo.BusServo(uart)
    vendor = VendorStyle(uart)
    ids = (1, 2, 3, 4, 5, 6)

    def best(call):  # the fastest of three rounds: a busy machine slows some
        return min(us_per_call(call) for _ in range(3))

    def row(name, call, base):
        print("cpython|%s|%.3f|%.3f" % (name, best(call), best(base)))

    row("move", lambda: bus.move(1, 500, 1000), lambda: vendor.move(1, 500, 1000))
    row(
        "request_positions, 6 servos",
        lambda: bus.request_positions(ids),
        lambda: vendor.request_positions(ids),
    )
    for name, frame in (
        ("decode RUN", RUN_8_ONCE),
        ("decode STOP", STOP),
        ("decode COMPLETE", COMPLETE_8_ONCE),
        ("decode battery", BATTERY_7500),
    ):
        uart.__init__(frame)
        assert bus.poll() == vendor.poll() == frame[3]
        row(name, bus.poll, vendor.poll)
    uart.__init__(POSITIONS_ALL_500)

    def ours():
        bus.request_positions(ids)
        return bus.poll()

    def theirs():
        vendor.request_positions(ids)
        return vendor.poll()

    assert ours() == theirs() == busservo.CMD_MULT_SERVO_POS_READ
    row("request and decode 6 positions", ours, theirs)
    print("pty|%.2f|%.2f|%d" % pty_reads(10 if N < 30000 else PTY_READS))


def pty_reads(reads):
    # Six positions read end to end: busservo_host's port (pyserial) on a pty, the simulated
    # controller (the unix port, boards/simpty.py) at the far end. (median ms, fastest ms).
    import subprocess

    import busservo_host

    folder = scratch("pty")
    os.mkdir(folder)
    link = folder + "/controller"
    sim = subprocess.Popen(
        ["sh", "boards/unix.sh", "--sim-pty", "--link", link],
        stdout=subprocess.DEVNULL,
        start_new_session=True,
    )
    try:
        while not os.path.exists(link):
            time.sleep(0.02)
        port = busservo_host.serial_port(link)
        bus = busservo.BusServo(port)
        for _ in range(20):  # the link comes as the simulator starts: wait for its answer
            try:
                bus.read_positions([1, 2, 3, 4, 5, 6], 1000)
                break
            except OSError:
                pass
        took = []
        for _ in range(reads):
            start = time.perf_counter()
            bus.read_positions([1, 2, 3, 4, 5, 6], 1000)
            took.append((time.perf_counter() - start) * 1000)
        port.close()
    finally:
        os.killpg(sim.pid, 15)
        sim.wait()
        sh("rm -rf " + folder)
    took.sort()
    return took[len(took) // 2], took[0], reads


def cpython_figures():
    # The CPython figures, from a CPython process: ({name: (us, vendor us)}, pty figures), or
    # None if it failed (then why is printed).
    ok, out = sh(PYTHON + " tests/bench.py --cpython" + (" quick" if N < 30000 else ""))
    rows = {}
    pty = None
    for line in out.split("\n"):
        cells = line.split("|")
        if cells[0] == "cpython" and len(cells) == 4:
            rows[cells[1]] = (float(cells[2]), float(cells[3]))
        elif cells[0] == "pty" and len(cells) == 4:
            pty = (float(cells[1]), float(cells[2]), int(cells[3]))
    if not ok or pty is None:
        print("the CPython figures failed:\n" + out)
        return None
    version = sh(PYTHON + " -c 'import sys; print(sys.version.split()[0])'")[1].strip()
    return rows, pty, version


def main():
    rows = []
    uart = ReplayUART()
    bus = busservo.BusServo(uart)
    vendor = VendorStyle(uart)
    six = [(1, 100), (2, 200), (3, 300), (4, 400), (5, 500), (6, 600)]
    ids = (1, 2, 3, 4, 5, 6)

    def row(name, call, base=None, wire=None):
        us = us_per_call(call)
        cells = [name, "%.2f" % us, "%d" % heap(call)]
        if base:
            base_us = us_per_call(base)
            cells.append("%.2f (%d B), busservo %.1fx" % (base_us, heap(base), base_us / us))
        else:
            cells.append("")
        cells.append("%.3f %%" % (100 * us / wire_us(wire)) if wire else "")
        rows.append(cells)
        cpython = on_cpython and on_cpython[0].get(name)
        if cpython:
            cells.append(
                "%.2f (vendor-style %.2f), busservo %.1fx"
                % (cpython[0], cpython[1], cpython[1] / cpython[0])
            )
        else:
            cells.append("")

    on_cpython = cpython_figures()

    row("move", lambda: bus.move(1, 500, 1000), lambda: vendor.move(1, 500, 1000), 10)
    row("move_many, 6 servos", lambda: bus.move_many(six, 1000), wire=25)
    row("run_group", lambda: bus.run_group(8, 1), wire=7)
    row("stop_group", bus.stop_group, wire=4)
    row("set_group_speed", lambda: bus.set_group_speed(8, 200), wire=7)
    row("unload, 6 servos", lambda: bus.unload(ids), wire=11)
    row("request_battery", bus.request_battery, wire=4)
    row("request_positions, 6 servos", lambda: bus.request_positions(ids), wire=11)
    uart.__init__()
    row("poll(), idle", bus.poll)
    for name, frame in (
        ("decode RUN", RUN_8_ONCE),
        ("decode STOP", STOP),
        ("decode COMPLETE", COMPLETE_8_ONCE),
        ("decode battery", BATTERY_7500),
    ):
        uart.__init__(frame)
        assert bus.poll() == vendor.poll() == frame[3]
        row(name, bus.poll, vendor.poll, len(frame))
    # Positions come only in reply: each decode has its request before it, on both sides.
    uart.__init__(POSITIONS_ALL_500)

    def ours():
        bus.request_positions(ids)
        return bus.poll()

    def theirs():
        vendor.request_positions(ids)
        return vendor.poll()

    assert ours() == theirs() == busservo.CMD_MULT_SERVO_POS_READ
    row("request and decode 6 positions", ours, theirs, 11 + len(POSITIONS_ALL_500))

    compared = side_by_side()
    size, (mpy_import, mpy_instance), ram32 = mpy_figures(MICROPYTHON32)
    py_import, py_instance = import_ram("lib")
    print("MicroPython %s, %s" % (sys.version, sys.implementation._machine))
    print("heap: %d KB" % ((gc.mem_free() + gc.mem_alloc()) // 1024))
    print()
    print(
        "| call | us per call | heap bytes per call | vendor-style: us (heap bytes), speed-up "
        "| share of its time on the wire at 9600 baud | CPython %s: us, speed-up |"
        % (on_cpython[2] if on_cpython else "")
    )
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for cells in rows:
        print("| " + " | ".join(cells) + " |")
    print()
    if on_cpython:
        median, fastest, reads = on_cpython[1]
        print(
            "Six positions read end to end on CPython (busservo_host's port, pyserial, a pty, "
            "the simulator at its far end): median %.2f ms, fastest %.2f ms, of %d reads; "
            "the wire at 9600 baud takes %.2f ms of it (34 bytes)."
            % (median, fastest, reads, wire_us(34) / 1000)
        )
        print()
    if compared:
        bare, pairs = compared
        print("A bare `uart.any()` (a C builtin returning 0): %.3f us" % bare)
        print()
        print(
            "| call | us, this driver | us, before (%s) | this / before "
            "| this / bare any() | before / bare any() |" % BEFORE
        )
        print("| --- | ---: | ---: | ---: | ---: | ---: |")
        for name, new_us, old_us, new_x, old_x in pairs:
            print(
                "| %s | %.3f | %.3f | %.2f | %.1fx | %.1fx |"
                % (name, new_us, old_us, new_us / old_us, new_x, old_x)
            )
        print()
    print("| memory | bytes |")
    print("| --- | ---: |")
    print("| busservo.mpy (mpy-cross, line numbers kept: as built) | %d |" % size)
    print(
        "| RAM: import busservo.mpy + one BusServo | %d + %d = %d |"
        % (mpy_import, mpy_instance, mpy_import + mpy_instance)
    )
    print(
        "| RAM: import busservo.py + one BusServo | %d + %d = %d |"
        % (py_import, py_instance, py_import + py_instance)
    )
    if ram32:
        print(
            "| RAM on a 32-bit port: import busservo.mpy + one BusServo | %d + %d = %d |"
            % (ram32[0], ram32[1], ram32[0] + ram32[1])
        )


if "--cpython" in sys.argv:
    cpython_main()
else:
    main()
