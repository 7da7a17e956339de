# The link's figures (issue 40), on CPython: per link model, the queries a second a program
# gets, its timeouts and its wrong answers, this driver beside the one before the link's timing
# (BEFORE, taken from the git history), in one run on simulated time (tests/wire.py's LINKS:
# a USB-serial chip's hand-overs, a busy computer's delay, a program preempted after its
# writes, a HID controller's reports; a board's rp2 UART as the reference); then the CPU a
# blocking query takes while it waits for a silent controller, on real time.
#
#   .venv/bin/python tests/bench_links.py          # 60 s of simulated time a model
#   .venv/bin/python tests/bench_links.py quick    # 4 s a model: tests/test_bench_links.py
#
# The queries: the battery and six servos' positions in turn, back to back, each with a value
# of its own (the simulated controller's battery, servo 1's position), so that an answer that
# belongs to another query is seen: wrong. Simulated time is the same run after run, whatever
# the machine does; the CPU figures are real (a busy machine's scheduler shows in them).
import importlib.util
import os
import subprocess
import sys
import tempfile
import time
import tty

sys.path[:0] = ["tests", "lib"]

import busservo_cpython  # noqa: E402

for _name in ("ticks_ms", "ticks_us", "ticks_diff", "ticks_add", "sleep_ms", "sleep_us"):
    setattr(time, _name, getattr(busservo_cpython.time, _name))
import asyncio  # noqa: E402

asyncio.sleep_ms = busservo_cpython.async_sleep_ms

import busservo  # noqa: E402
import wire  # noqa: E402

BEFORE = "908c229"  # the last commit before the link's timing
QUICK = "quick" in sys.argv
SECONDS = 4 if QUICK else 60
SIX = [1, 2, 3, 4, 5, 6]

# (name, port, world's keywords): the links, then two with faults.
MODELS = (
    ("CH340, a quiet computer", "ch340", {}),
    ("FTDI, a quiet computer", "ftdi", {}),
    ("FTDI, a busy computer (0..8 ms more a hand-over)", "ftdi", {"busy_ms": 8}),
    ("FTDI, a very busy computer (0..20 ms more)", "ftdi", {"busy_ms": 20}),
    ("CH340, the program preempted 0..30 ms after 1 write in 5", "ch340", {"preempt": (5, 30)}),
    ("HID, a quiet computer", "hid", {}),
    ("HID, a very busy computer (0..20 ms more)", "hid", {"busy_ms": 20}),
    ("a board's UART (rp2), for reference", "rp2", {}),
)
FAULTS = (
    ("FTDI, very busy; a reply 300 ms late every 2 s", "ftdi", {"busy_ms": 20}, "late"),
    ("FTDI, very busy; a reply lost every 2 s", "ftdi", {"busy_ms": 20}, "lost"),
    ("HID, very busy; a reply 300 ms late every 2 s", "hid", {"busy_ms": 20}, "late"),
)


def driver_before():
    """The driver at BEFORE, as a module of its own (busservo_before), or None."""
    folder = tempfile.mkdtemp(prefix="busservo-bench-links-")
    path = os.path.join(folder, "busservo_before.py")
    with open(path, "wb") as f:
        got = subprocess.run(["git", "show", BEFORE + ":lib/busservo.py"], stdout=f)
    if got.returncode:
        return None
    spec = importlib.util.spec_from_file_location("busservo_before", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    os.remove(path)
    os.rmdir(folder)
    return module


def run(driver, port, kw, fault=None, seconds=SECONDS):
    """(queries, timeouts, wrong answers, faults made) over seconds of the world's time."""
    w = wire.World(port, seed=7, **kw)
    driver.time = w.clock
    bus = driver.BusServo(w.uart)
    n = timeouts = wrong = faults = 0
    next_fault = 2000000
    while w.clock.now_us < seconds * 1000000:
        if fault and w.clock.now_us >= next_fault:
            next_fault += 2000000
            faults += 1
            if fault == "late":
                w.late(300)
            else:
                w.cut_reply(0)
        n += 1
        value = n % 1000
        try:
            if n % 2:
                w.sim.battery = 6000 + value
                got = bus.read_battery() - 6000
            else:
                w.sim.write(
                    b"\x55\x55\x08\x03\x01\x00\x00\x01" + bytes((value & 0xFF, value >> 8))
                )
                got = bus.read_positions(SIX)[1]
        except OSError:
            timeouts += 1
            continue
        wrong += got != value
    return n, timeouts, wrong, faults


def cell(result, seconds=SECONDS):
    n, timeouts, wrong, _ = result
    return "%.1f | %d (%.1f %%) | %d" % (n / seconds, timeouts, 100.0 * timeouts / n, wrong)


def silent_pty_cpu(driver, seconds=3):
    """The CPU (percent of one core) that read_battery() takes while it waits seconds on a
    silent controller: a pty with nothing at its far end, through busservo_host's port."""
    import busservo_host

    master, slave = os.openpty()
    tty.setraw(slave)
    try:
        with busservo_host.serial_port(os.ttyname(slave)) as uart:
            driver.time = busservo_cpython.time
            bus = driver.BusServo(uart)
            wall, cpu = time.monotonic(), time.process_time()
            try:
                bus.read_battery(seconds * 1000)
            except OSError:
                pass
            return 100 * (time.process_time() - cpu) / (time.monotonic() - wall)
    finally:
        os.close(master)
        os.close(slave)


def silent_hid_cpu(driver, seconds=3):
    """The same through busservo_hid, with tests/test_hid.py's binding: a HID controller
    that never answers (its read with a timeout waits in the OS: a sleep)."""
    import busservo_hid
    import test_hid

    xarm = test_hid.Controller()
    saved = {name: sys.modules.get(name) for name in ("hid", "hidraw")}
    sys.modules["hid"] = sys.modules["hidraw"] = test_hid.Binding(xarm)
    try:
        uart = busservo_hid.hid_port(wake_ms=0)
        driver.time = busservo_cpython.time
        bus = driver.BusServo(uart)
        wall, cpu = time.monotonic(), time.process_time()
        try:
            bus.read_battery(seconds * 1000)
        except OSError:
            pass
        return 100 * (time.process_time() - cpu) / (time.monotonic() - wall)
    finally:
        for name, module in saved.items():
            if module is None:
                sys.modules.pop(name, None)
            else:
                sys.modules[name] = module


def main():
    before = driver_before()
    print("%d s of simulated time a model; the driver before: %s" % (SECONDS, BEFORE))
    print()
    print(
        "| link (no fault injected: every reply comes whole, well within its query's time) "
        "| queries/s | timed out | wrong | before: queries/s | timed out | wrong |"
    )
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name, port, kw in MODELS:
        old = cell(run(before, port, kw)) if before else "n/a | n/a | n/a"
        print("| %s | %s | %s |" % (name, cell(run(busservo, port, kw)), old))
    print()
    print("| link, with faults | faults | timed out | wrong | before: timed out | wrong |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for name, port, kw, fault in FAULTS:
        n, timeouts, wrong, faults = run(busservo, port, kw, fault)
        old = "n/a | n/a"
        if before:
            _, old_out, old_wrong, _ = run(before, port, kw, fault)
            old = "%d | %d" % (old_out, old_wrong)
        print("| %s | %d | %d | %d | %s |" % (name, faults, timeouts, wrong, old))
    print()
    seconds = 1 if QUICK else 3
    print(
        "| a blocking query waits %d s on a silent controller | CPU, this driver | before |"
        % seconds
    )
    print("| --- | ---: | ---: |")
    for name, measure in (
        ("a serial port (busservo_host, a pty)", silent_pty_cpu),
        ("a HID controller (busservo_hid, test_hid's binding)", silent_hid_cpu),
    ):
        old = "%.1f %%" % measure(before, seconds) if before else "n/a"
        print("| %s | %.1f %% | %s |" % (name, measure(busservo, seconds), old))


if __name__ == "__main__":
    main()
