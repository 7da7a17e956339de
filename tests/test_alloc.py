# Heap bytes per call, measured as gc.mem_alloc() deltas with the collector
# off. Exact and repeatable on MicroPython, so these are tests, not benchmarks.
import gc
import sys
import unittest

try:
    import micropython
except ImportError:  # CPython (tests/cpython.py): the tests that measure the heap skip there
    micropython = None

import busservo
from fakeuart import Answers, FakeUART
from test_frames import BATTERY_7500, COMPLETE_8_ONCE, POSITIONS_ALL_500, RUN_8_ONCE, STOP

CALLS = 20


def heap_per_call(call, before=None):
    """Heap bytes that CALLS calls of call() take, after one call to warm up.
    before() runs ahead of every call, outside the measurement. On CPython (tests/cpython.py)
    it skips the test: CPython has no gc.mem_alloc(), and its objects are not a board's."""
    if sys.implementation.name != "micropython":
        raise unittest.SkipTest("heap bytes per call: MicroPython's measure (not on CPython)")
    if before:
        before()
    call()
    total = 0
    gc.collect()
    gc.disable()
    try:
        for _ in range(CALLS):
            if before:
                before()
            start = gc.mem_alloc()
            call()
            total += gc.mem_alloc() - start
    finally:
        gc.enable()
    return total


class Allocation(unittest.TestCase):
    def setUp(self):
        self.uart = FakeUART()
        self.bus = busservo.BusServo(self.uart)

    def assertNoHeap(self, call, before=None):
        self.assertEqual(heap_per_call(call, before), 0)

    def commands(self):
        # Every command, as a call; move() first.
        bus = self.bus
        six = [(1, 100), (2, 200), (3, 300), (4, 400), (5, 500), (6, 600)]
        ids = (1, 2, 3, 4, 5, 6)
        return (
            lambda: bus.move(1, 500, 1000),
            lambda: bus.move_many(six, 1000),
            lambda: bus.run_group(8, 1),
            lambda: bus.stop_group(),
            lambda: bus.set_group_speed(busservo.ALL_GROUPS, 200),
            lambda: bus.unload(ids),
            lambda: bus.request_battery(),
            lambda: bus.request_positions(ids),
        )

    def test_commands_allocate_nothing(self):
        for call in self.commands():
            self.uart.clear()
            self.assertNoHeap(call)

    def test_idle_poll_allocates_nothing(self):
        self.assertNoHeap(self.bus.poll)

    def test_decoding_status_and_battery_frames_allocates_nothing(self):
        for frame in (RUN_8_ONCE, STOP, COMPLETE_8_ONCE, BATTERY_7500, POSITIONS_ALL_500):
            for chunks in (None, [1], [3]):
                self.uart.chunks = chunks
                # feed() allocates, so it runs outside the measurement.
                self.assertNoHeap(self.bus.poll, lambda f=frame: self.uart.feed(f))
                self.assertEqual(self.bus.poll(), None)

    def test_a_split_frame_allocates_nothing(self):
        # Half a frame now, the rest later: the chunked path, with the slide.
        state = [0]

        def half():
            state[0] ^= 1
            self.uart.feed(RUN_8_ONCE[:3] if state[0] else RUN_8_ONCE[3:] + b"\x00" * 61)

        self.assertNoHeap(self.bus.poll, half)

    def test_finishing_a_frame_the_uart_took_part_of_allocates_nothing(self):
        # write() takes 3 bytes, then none, then the rest: uart.write(buf, off, n).
        six = [(1, 100), (2, 200), (3, 300), (4, 400), (5, 500), (6, 600)]
        for call in (lambda: self.bus.move(1, 500, 0), lambda: self.bus.move_many(six, 0)):
            self.uart.clear()
            self.assertNoHeap(call, lambda: setattr(self.uart, "takes", [3, None, 100]))

    def test_a_query_made_once_reads_again_and_again_with_no_heap(self):
        # ask(again=True) is made once (its generator is the heap it takes); each read after
        # takes none: a recording's or a teleop's loop that reads for ever, collected never.
        ids = (1, 2, 3, 4, 5, 6)
        bus = busservo.BusServo(Answers(POSITIONS_ALL_500))
        query = bus.ask(ids, 200, again=True)

        def read():
            while next(query) is None:
                pass

        self.assertNoHeap(read)

    def test_wire_ms_allocates_nothing(self):
        self.bus.move(1, 500, 0)  # with the wire busy, and idle
        self.assertNoHeap(self.bus.wire_ms)

    def test_the_hot_paths_run_with_the_heap_locked(self):
        # Stricter than a net change of 0: MicroPython's VM keeps a big function's locals
        # (the parser's) in a heap block for the call's length, and with the heap locked it
        # must fall back to the C stack. Every call runs once, then again with the lock on.
        bus = self.bus
        commands = self.commands()
        frames = (RUN_8_ONCE, STOP, COMPLETE_8_ONCE, BATTERY_7500, POSITIONS_ALL_500)
        got = [None] * (len(frames) + 1)  # made before the lock: filled, never grown

        def hot():
            for call in commands:  # move(), the first, is cut by the UART, then finished
                call()
            bus.wire_ms()
            for i in range(len(got)):
                got[i] = bus.poll()  # one frame a call, decoded where it lies

        for locked in (False, True):
            self.uart.clear()
            for frame in frames:
                self.uart.feed(frame)
            self.uart.takes = [3, None, 100]
            if locked:
                micropython.heap_lock()
            try:
                hot()
            finally:
                if locked:
                    micropython.heap_unlock()
            self.assertEqual(got, [6, 7, 8, 15, 21, None])
            self.assertEqual(bus.battery, 7500)
            self.assertEqual(self.uart.takes, [])  # the cut path ran: 3 bytes, none, the rest
            self.assertEqual(self.uart.written()[:10], bytes.fromhex("5555080301e80301f401"))

    def test_the_fake_uart_itself_allocates_nothing(self):
        # Else the figures above would measure the fake, not the driver.
        buf = bytearray(8)
        self.uart.feed(bytes(200))
        self.assertNoHeap(lambda: self.uart.readinto(buf, 8))
        self.assertNoHeap(lambda: self.uart.write(buf, 8))
        self.assertNoHeap(self.uart.any)


if __name__ == "__main__":
    unittest.main()
