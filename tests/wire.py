# A world as faithful as the wire, for tests: a clock the test steps, a board's
# UART modelled on MicroPython's own ports, the serial line at 10 bits a byte,
# and the simulated controller (lib/busservo_sim.py) at its far end.
#
#   w = wire.World("rp2")            # or "esp32": wire.PORTS names them all
#   busservo.time = w.clock          # the driver's clock is the world's
#   bus = busservo.BusServo(w.uart)
#   w.clock.advance_ms(20)           # time passes; the wire catches up when looked at
#   w.frames(), w.garbled            # what the controller received
#   w.arrivals()                     # (us, frame): when each frame was in
#   w.frames_total, w.frames(first)  # how many came; those from the first-th on
#   w.on_frame = f                   # f(us, frame) as each whole frame is in
#   w.noise(b"\x55\x55\x05")         # faults: noise, drop, cut_reply, late,
#   w.uart.fail("readinto", OSError(5)), w.uart.during(...), w.uart.stall(True)
#   wire.World("rp2", clock=wire.RealClock(), call_us=0)   # the same, live, on real time
#   wire.World("ftdi", busy_ms=20)   # a computer's port behind USB (LINKS), busy
#
# Time is whole microseconds (w.clock.now_us), and nothing real is used: the
# same test gives the same bytes at the same times, every run. Each ticks read
# costs cost_us and each UART call call_us, so a busy loop moves on; a UART
# call that waits (as a port's does) moves the clock to where the wait ends.
# The wire is lazy: whatever a UART call or a World method looks at, the wire
# is first brought up to the clock, event by event in time order.
#
# Nothing grows with traffic, so a world can run for days: it keeps the last
# KEEP_BYTES bytes the controller received (received()) and of them the last
# KEEP whole frames (keep=), with their times; the times of the last KEEP_LOG
# bytes received (sent_at), the last KEEP_LOG garbled ones (garbage()) and the
# last KEEP_LOG that reached the board's pin (arrived); and it counts them all
# (received_total, frames_total, garbled, arrived_total). Frames are parsed as
# their bytes come, once. All that is kept is in buffers made with the world:
# nothing it keeps is a small object of its own, scattered over the heap, where
# it would leave no room for a large one. The queues of what is on its way (the
# rings, what the controller says, the faults set) hold what is still to come.
#
# What the models do, as read in MicroPython's source:
# - extmod/machine_uart.c binds UART.read, readinto and write to py/stream.c's
#   read1, readinto1 and write1: ONE call of the port's read or write function
#   a call, no retry loop. py/stream.c: write(buf, n) and readinto(buf, n) take
#   MIN(len(buf), n), write(buf, off, n) clamps off to len(buf) and n to the
#   rest; off and n are size_t, so a negative one means "no limit". A size of 0
#   calls nothing and gives 0 (read(0): b""). A port's EAGAIN gives None. read()
#   with no size reads 256 (or what is left of 256) a port call until EAGAIN,
#   None if nothing came. readinto() takes (buf) or (buf, n) only.
# - py/ringbuf.h keeps one slot free: rp2 allocates rxbuf+1 and txbuf+1, so its
#   rings hold rxbuf and txbuf bytes (256 by default, at least 32).
# - ports/rp2/machine_uart.c: timeout is 0 and timeout_char at least
#   13000 // baud + 1 ms (2 at 9600). Behind each ring a 32-byte hardware FIFO
#   (UART_FIFO_SIZE_RX; the PL011's TX FIFO is as deep), and the transmitter
#   holds the byte on the wire besides. write() puts in the ring what fits,
#   moves the ring into the TX FIFO (uart_fill_tx_fifo), then for each byte
#   left waits for ring room "while elapsed <= timeout" in whole ms of
#   mp_hal_ticks_ms: `timeout` for the first, `timeout_char` after each byte put
#   (so with timeout=0 it waits until the ms counter ticks: at most 1 ms).
#   It returns the count put, or EAGAIN if none. Room comes only when bytes
#   move to the FIFO: at a write, or at the TX interrupt, which the port turns
#   on with the Pico SDK's uart_set_irq_enables(): at the PL011's lowest levels,
#   RX at 4 bytes in the FIFO, TX down to 4 bytes. read() takes each byte from
#   the ring; when the ring is empty and the RX FIFO is not, it moves up to 33
#   bytes from FIFO to ring; else it waits as write() does (timeout, then
#   timeout_char), EAGAIN if nothing came.
#   any() moves up to 33 FIFO bytes into the ring (as far as it has room) and
#   counts the ring: bytes left in the FIFO by a full ring are not counted. The
#   RX interrupt (FIFO at 4 bytes, or 32 bit times after the last byte: the
#   RX timeout) moves up to 23 bytes (UART_FIFO_TRIGGER_LEVEL_RX - 1). When ring
#   and FIFO are full, a byte that comes is lost (the PL011 keeps its FIFO and
#   loses the new byte). flush() waits up to (33 + ring size) * 26e6 / baud us.
# - ports/esp32/machine_uart.c: txbuf and rxbuf 256, timeout and timeout_char 0
#   by default; 128-byte hardware FIFOs. rx timeout = timeout_char //
#   (12000 // baud + 1) characters; below 1 it sets the rx-full threshold to 1
#   and the rx timeout to 1 character, else it keeps the driver's threshold of
#   120. write() is ESP-IDF's uart_write_bytes() and read() uart_read_bytes()
#   (1 byte with pdMS_TO_TICKS(timeout), then the rest with that of
#   timeout_char: no wait at all by default; FreeRTOS ticks are 10 ms); any()
#   is uart_get_buffered_data_len(). In that ESP-IDF driver (what the port
#   calls, read for this model): the RX interrupt comes when the FIFO holds MORE
#   than the threshold, or the line has been idle for the rx timeout (taken
#   here as that many times 10 bit times), and moves
#   the whole FIFO into the 256-byte ring (what any() counts); if the ring
#   cannot take all of it, it keeps it aside and stops RX interrupts until a
#   read has made room. A byte that finds the FIFO full overflows it, and the
#   driver resets the FIFO: its 128 bytes are lost with the new one.
#   uart_write_bytes() blocks with no time limit (portMAX_DELAY) until it has
#   put all of it into the TX ring: a 12-byte descriptor, then chunks of at most
#   ((txbuf / 2 rounded up to 4) - 8) / 2 = 60 bytes, each item taking its
#   length rounded up to 4 plus an 8-byte header, and never wrapping round the
#   ring's end (FreeRTOS's no-split ring buffer). The TX interrupt fills the
#   FIFO from the ring when the FIFO holds fewer than 10 bytes.
# - extmod/modtime.c, py/mpconfig.h: ticks wrap at MP_SMALL_INT_POSITIVE_MASK+1
#   = 2**30 on a 32-bit port; ticks_diff(a, b) = ((a - b + 2**29) & (2**30 - 1))
#   - 2**29; ticks_add() raises OverflowError("ticks interval overflow") unless
#   -2**29 < delta < 2**29; sleep_ms(n < 0) and sleep_us(n <= 0) do nothing.
#
# Choices where the source leaves the model to choose:
# - A stalled esp32 write would block for ever. Here it blocks for hang_ms
#   (1000) of simulated time without room, then returns what it put (None if
#   nothing), so that a test can go on and see what its driver makes of it;
#   World(..., hang="raise") raises wire.Hang there instead.
# - The simulated controller answers at the instant the last bit of a frame is
#   in, and speaks unprompted (COMPLETE) on a whole ms: it is looked at every ms
#   while a group runs, at each byte it receives, and at the catch-up after a
#   test looked at it (w.sim: it may have been told something off the wire).
#   Its clock is the world's ms, unwrapped: it does its ticks arithmetic with
#   the unix port's time module.
# - Faults act on what the controller says after they are set: a reply already
#   on its way is not cut, dropped or delayed. cut_reply() acts before drop().
import asyncio
import time

import busservo_sim

_yield = asyncio.sleep_ms  # taken now: a test may put async_sleep_ms in its place

PORTS = ("rp2", "esp32")

PERIOD = 1 << 30  # ticks period of a 32-bit port
_MASK = PERIOD - 1
_HALF = PERIOD >> 1
_TICK_US = 10000  # a FreeRTOS tick on esp32 (100 Hz)

# Command byte -> Length of the commands the controller takes; (per, extra):
# Length = per * count + extra, the count being the first parameter.
_LENGTHS = {3: (3, 5), 6: 5, 7: 2, 11: 5, 15: 2, 20: (1, 3), 21: (1, 3)}
METHODS = ("any", "read", "readinto", "write", "flush", "txdone", "wait")
KEEP = 1000  # whole frames a world keeps, by default: 10 s of 10-byte moves
KEEP_BYTES = 16384  # bytes received it keeps: 17 s of the wire at 9600 baud
KEEP_LOG = 1024  # the times of the bytes received, the garbled ones, those at the pin


class Hang(Exception):
    """A write a real board would never return from."""


class Clock:
    """MicroPython's time, as drivers use it, on simulated time: a drop-in for
    `time` (ticks_ms, ticks_us, ticks_diff, ticks_add, sleep_ms, sleep_us). Each
    ticks read costs cost_us. By default ticks_ms wraps 3 s in and ticks_us 1 s
    in; start=None starts both at 0, start=(ms, us) where asked."""

    def __init__(self, start="wrap", cost_us=1):
        if start is None:
            start = (0, 0)
        elif start == "wrap":
            start = (PERIOD - 3000, PERIOD - 1000000)
        self._ms0, self._us0 = start
        self.cost_us = cost_us
        self.now_us = 0  # simulated time since the start, in us

    def ticks_ms(self):
        t = (self._ms0 + self.now_us // 1000) & _MASK
        self.now_us += self.cost_us
        return t

    def ticks_us(self):
        t = (self._us0 + self.now_us) & _MASK
        self.now_us += self.cost_us
        return t

    ticks_cpu = ticks_us

    def ticks_diff(self, end, start):
        return ((end - start + _HALF) & _MASK) - _HALF

    def ticks_add(self, ticks, delta):
        if not isinstance(delta, int):
            raise TypeError("can't convert %s to int" % type(delta).__name__)
        if not -_HALF < delta < _HALF:
            raise OverflowError("ticks interval overflow")
        return (ticks + delta) & _MASK

    def sleep_ms(self, ms):
        if ms >= 0:
            self.now_us += ms * 1000

    def sleep_us(self, us):
        if us > 0:
            self.now_us += us

    def sleep(self, s):
        if s > 0:
            self.now_us += int(s * 1000000)

    def advance_ms(self, ms):
        self.now_us += ms * 1000

    def advance_us(self, us):
        self.now_us += us


class RealClock(Clock):
    """The same clock on real time (the unix port's): for a world that runs live,
    such as the web panel's server under a browser test. Where the world moves
    the clock on (a UART call that waits), it sleeps until then."""

    def __init__(self, start="wrap"):
        self._t0 = time.ticks_us()
        super().__init__(start, cost_us=0)

    @property
    def now_us(self):
        return time.ticks_diff(time.ticks_us(), self._t0)

    @now_us.setter
    def now_us(self, t):
        ahead = t - time.ticks_diff(time.ticks_us(), self._t0)
        if ahead > 0:
            time.sleep_us(ahead)


class _Ring:
    # A byte FIFO of fixed capacity: a ring buffer or a hardware FIFO.
    def __init__(self, capacity):
        self.buf = bytearray(capacity)
        self.cap = capacity
        self.i = 0  # where the oldest byte is
        self.n = 0  # how many bytes it holds

    def put(self, b):
        self.buf[(self.i + self.n) % self.cap] = b
        self.n += 1

    def get(self):
        b = self.buf[self.i]
        self.i = (self.i + 1) % self.cap
        self.n -= 1
        return b

    def clear(self):
        self.i = self.n = 0


class _Log:
    # The last len(items) things of a kind, in items (a list, or a bytearray for
    # bytes), made once: adding one overwrites the oldest. total counts them all.
    def __init__(self, items):
        self.items = items
        self.total = 0

    def add(self, x):
        items = self.items
        items[self.total % len(items)] = x
        self.total += 1

    def last(self, first=0):
        # Those kept, oldest first, from the first-th of all on (a list, or bytes).
        return self.span(first, self.total)

    def span(self, first, end):
        # Those kept of the first-th to the one before the end-th.
        items = self.items
        size = len(items)
        first = max(first, self.total - size, 0)
        end = min(end, self.total)
        if first >= end:
            return [] if isinstance(items, list) else b""
        i = first % size
        j = i + end - first
        if j <= size:
            out = items[i:j]
        else:
            out = items[i:] + items[: j - size]
        return out if isinstance(items, list) else bytes(out)


class _ItemRing:
    # FreeRTOS's no-split ring buffer, as ESP-IDF's UART driver keeps its TX
    # ring: items of (8-byte header + length rounded up to 4) that never wrap;
    # freed oldest first. Each item is [position, data or None, bytes taken].
    def __init__(self, size):
        self.size = size
        self.acq = 0  # where the next item goes
        self.full = False
        self.items = []

    def fits(self, n):
        cost = ((n + 3) & ~3) + 8
        if not self.items:
            return True
        free = self.items[0][0]
        if self.full:
            return False
        if free > self.acq:
            return cost <= free - self.acq
        return cost <= self.size - self.acq or cost <= free

    def put(self, n, data):
        cost = ((n + 3) & ~3) + 8
        if self.size - self.acq < cost:  # the rest of the ring is dummy: wrap
            self.acq = 0
        self.items.append([self.acq, data, 0])
        self.acq += cost
        if self.size - self.acq < 8:
            self.acq = 0
        if self.acq == self.items[0][0]:
            self.full = True

    def pop(self):
        self.items.pop(0)
        self.full = False

    def pending(self):
        return sum(len(it[1]) - it[2] for it in self.items if it[1] is not None)


class _Line:
    # One direction of the wire: byte k of a burst (bytes back to back) has
    # arrived at start + (k + 1) * 10_000_000 // baud us.
    def __init__(self, baudrate):
        self.baudrate = baudrate
        self.start = 0
        self.k = -1
        self.end = -1  # when the last byte sent has arrived

    def send(self, t):
        if t == self.end:  # right behind the byte before
            self.k += 1
        else:
            self.start = t
            self.k = 0
        self.end = self.start + (self.k + 1) * 10000000 // self.baudrate
        return self.end

    def after(self, n):
        # When n more bytes, sent back to back behind the last one, have arrived.
        return self.start + (self.k + 1 + n) * 10000000 // self.baudrate


def _split(data):
    # The frames (by their Length byte) of what the controller says.
    out = []
    i = 0
    while i < len(data):
        j = len(data)
        if data[i] == 0x55 and i + 2 < len(data) and data[i + 1] == 0x55:
            j = min(j, i + data[i + 2] + 2)
        out.append(data[i:j])
        i = j
    return out


def parse(data, ends=None):
    """(frames, garbage, rest) of bytes a controller received, strictly by the
    protocol's lengths of the commands it takes; rest: the start of a frame
    that may still be arriving. Given a list as ends, it gets each frame's end:
    the index in data just past its last byte."""
    frames = []
    garbage = bytearray()
    i = 0
    n = len(data)
    while i < n:
        rest = n - i
        if data[i] != 0x55 or (rest > 1 and data[i + 1] != 0x55):
            garbage.append(data[i])
            i += 1
            continue
        if rest < 4:
            break
        length = data[i + 2]
        want = _LENGTHS.get(data[i + 3])
        if isinstance(want, tuple):
            if rest < 5:
                break
            want = want[0] * data[i + 4] + want[1]
        if want != length:
            garbage.append(data[i])
            i += 1
            continue
        if rest < length + 2:
            break
        frames.append(bytes(data[i : i + length + 2]))
        i += length + 2
        if ends is not None:
            ends.append(i)
    return frames, bytes(garbage), bytes(data[i:])


class UART:
    """The board's machine.UART: any(), read([n]), readinto(buf[, n]), write(buf[,
    off][, n]), flush(), txdone(), with the stream protocol's semantics and the
    port's. Faults: fail(), during(), stall(). `overrun` counts received bytes
    lost to a full receive side."""

    def __init__(self, world, timeout, hang_ms, hang):
        self._w = world
        self.timeout = timeout
        self.hang_ms = hang_ms
        self.hang = hang
        self.overrun = 0
        self._stalled = False
        self._faults = {}  # method: [[skip, times, exc]]
        self._hooks = {}  # method: [[skip, times, callback, when]]

    # Faults.

    def fail(self, method, exc, skip=0, times=1):
        """The skip+1-th next call of method raises exc, times calls in a row;
        a failing call takes and gives nothing (and during() does not count it)."""
        self._check(method)
        self._faults.setdefault(method, []).append([skip, times, exc])

    def during(self, method, callback, when="before", skip=0, times=1):
        """callback() runs inside the skip+1-th next call of method (times calls
        in a row): before it does its work, or after, before it returns."""
        self._check(method)
        if when not in ("before", "after"):
            raise ValueError("when must be 'before' or 'after', got %r" % (when,))
        self._hooks.setdefault(method, []).append([skip, times, callback, when])

    def stall(self, on=True):
        """A stuck transmitter: what is written stays in the UART (the byte on
        the wire now still arrives) until stall(False)."""
        w = self._w
        w.sync()
        self._stalled = on
        if not on:
            w._tx_kick()

    @property
    def stalled(self):
        return self._stalled

    def _check(self, method):
        if method not in METHODS:
            raise ValueError("method must be one of %s, got %r" % (METHODS, method))

    @staticmethod
    def _due(table, method):
        # Count one call against each entry of table[method]; the entries that
        # fire on it. Spent entries go, and a method left with none.
        entries = table.get(method)
        if not entries:
            return ()
        fired = []
        for e in entries:
            if e[0] > 0:
                e[0] -= 1
            elif e[1] > 0:
                e[1] -= 1
                fired.append(e)
        entries[:] = [e for e in entries if e[1] > 0]
        if not entries:
            del table[method]
        return fired

    def _enter(self, method):
        # Kept small: a MicroPython function with many locals takes its frame
        # from the heap, and this runs at every UART call.
        w = self._w
        w.clock.now_us += w.call_us
        w._run_to(w.clock.now_us)
        if self._faults or self._hooks:
            return self._fault(method)
        return None

    def _fault(self, method):
        # The faults and callbacks set on this call of method.
        w = self._w
        fired = self._due(self._faults, method)
        if fired:
            raise fired[0][2]
        after = []
        for e in self._due(self._hooks, method):
            if e[3] == "before":
                e[2]()
                w.sync()
            else:
                after.append(e[2])
        return after

    def _leave(self, after):
        for callback in after:
            callback()

    # machine.UART's methods.

    def any(self):
        after = self._enter("any")
        n = self._any()
        if after:
            self._leave(after)
        return n

    def read(self, nbytes=None):
        after = self._enter("read")
        if nbytes is None or nbytes == -1:
            got = self._readall()
        elif nbytes < -1:
            raise MemoryError
        elif nbytes == 0:
            got = b""
        else:
            buf = bytearray(nbytes)
            n = self._io_read(buf, 0, nbytes)
            got = None if n is None else bytes(buf[:n])
        if after:
            self._leave(after)
        return got

    def readinto(self, buf, nbytes=None):
        if isinstance(buf, (bytes, str)):
            raise TypeError("object with buffer protocol required")
        after = self._enter("readinto")
        n = len(buf)
        if nbytes is not None and 0 <= nbytes < n:
            n = nbytes
        got = self._io_read(buf, 0, n) if n else 0
        if after:
            self._leave(after)
        return got

    def write(self, buf, off=None, nbytes=None):
        if isinstance(buf, str):
            buf = buf.encode()
        after = self._enter("write")
        size = len(buf)
        if nbytes is None:  # write(buf) or write(buf, n)
            start = 0
            if off is not None and 0 <= off < size:
                size = off
        else:  # write(buf, off, n)
            start = off if 0 <= off <= size else size
            size -= start
            if 0 <= nbytes < size:
                size = nbytes
        n = self._io_write(memoryview(buf)[start : start + size]) if size else 0
        if after:
            self._leave(after)
        return n

    def flush(self):
        after = self._enter("flush")
        w = self._w
        if not w._wait(self._txdone, w._t + self._flush_us()):
            raise OSError(110)  # ETIMEDOUT
        if after:
            self._leave(after)

    def txdone(self):
        after = self._enter("txdone")
        done = self._txdone()
        if after:
            self._leave(after)
        return done

    def _readall(self):
        got = bytearray()
        buf = bytearray(256)
        ask = 256
        while True:
            n = self._io_read(buf, 0, ask)
            if n is None:
                return bytes(got) if got else None
            got += buf[:n]
            ask = ask - n if n < ask else 256

    def _txdone(self):
        return not self._tx_pending() and not self._w._tx_busy


class _RP2(UART):
    FIFO = 32

    def __init__(self, world, timeout, timeout_char, txbuf, rxbuf, hang_ms, hang):
        UART.__init__(self, world, timeout, hang_ms, hang)
        baud = world.baudrate
        self.timeout_char = max(timeout_char, 13000 // baud + 1)
        rxbuf = 256 if rxbuf is None else rxbuf
        txbuf = 256 if txbuf is None else txbuf
        if max(rxbuf, txbuf) > 32766:
            raise ValueError("rxbuf and txbuf are at most 32766")
        self._rx_ring = _Ring(max(rxbuf, 32))
        self._rx_fifo = _Ring(32)
        self._tx_ring = _Ring(max(txbuf, 32))
        self._tx_fifo = _Ring(32)
        self._rt_us = 32 * 1000000 // baud  # the RX timeout: 32 bit times
        self._rt_at = None

    def _any(self):
        if self._rx_fifo.n:
            self._drain_rx(33)
        return self._rx_ring.n

    def _drain_rx(self, most):
        fifo, ring = self._rx_fifo, self._rx_ring
        while fifo.n and ring.n < ring.cap and most > 0:
            ring.put(fifo.get())
            most -= 1

    def _rx_ready(self):
        return self._rx_ring.n or self._rx_fifo.n

    def _io_read(self, buf, off, n):
        w = self._w
        ring = self._rx_ring
        start = w._t // 1000
        timeout = self.timeout
        for i in range(n):
            while not ring.n:
                if self._rx_fifo.n:
                    self._drain_rx(33)
                    break
                if not w._wait(self._rx_ready, (start + timeout + 1) * 1000):
                    return i or None
            buf[off + i] = ring.get()
            start = w._t // 1000
            timeout = self.timeout_char
        return n

    def _tx_room(self):
        return self._tx_ring.n < self._tx_ring.cap

    def _io_write(self, mv):
        w = self._w
        ring = self._tx_ring
        n = len(mv)
        i = 0
        start = w._t // 1000
        timeout = self.timeout
        while i < n and ring.n < ring.cap:
            ring.put(mv[i])
            i += 1
        self._fill_tx()
        while i < n:
            if not w._wait(self._tx_room, (start + timeout + 1) * 1000):
                return i or None
            ring.put(mv[i])
            i += 1
            start = w._t // 1000
            timeout = self.timeout_char
            self._fill_tx()
        return n

    def _fill_tx(self):
        fifo, ring = self._tx_fifo, self._tx_ring
        while fifo.n < 32 and ring.n:
            fifo.put(ring.get())
        self._w._tx_kick()

    def _tx_take(self):
        # The transmitter takes the next byte from the FIFO; down to 4 bytes,
        # the TX interrupt refills the FIFO from the ring.
        fifo = self._tx_fifo
        if not fifo.n:
            return -1
        b = fifo.get()
        if fifo.n <= 4:
            ring = self._tx_ring
            while fifo.n < 32 and ring.n:
                fifo.put(ring.get())
        return b

    def _tx_pending(self):
        return self._tx_ring.n + self._tx_fifo.n

    def _rx_arrive(self, t, b):
        fifo = self._rx_fifo
        if fifo.n == 32:  # overrun: the FIFO keeps its bytes, the new one is lost
            self.overrun += 1
            return
        fifo.put(b)
        self._rt_at = t + self._rt_us
        if fifo.n >= 4:  # the RX interrupt
            self._drain_rx(23)

    def _rx_start(self):
        self._rt_at = None  # a byte is coming: the line is not idle

    def _rx_timer(self):
        return self._rt_at if self._rx_fifo.n else None

    def _rx_timer_fire(self, t):
        if self._rt_at is not None and self._rt_at <= t:
            self._rt_at = None
            self._drain_rx(23)

    def _flush_us(self):
        return (33 + self._tx_ring.cap + 1) * 26000000 // self._w.baudrate


class _ESP32(UART):
    FIFO = 128

    def __init__(self, world, timeout, timeout_char, txbuf, rxbuf, hang_ms, hang):
        UART.__init__(self, world, timeout, hang_ms, hang)
        baud = world.baudrate
        self.timeout_char = timeout_char
        rxbuf = 256 if rxbuf is None else rxbuf
        txbuf = 256 if txbuf is None else txbuf
        if min(rxbuf, txbuf) <= 128:
            raise ValueError("rxbuf and txbuf must be more than the 128-byte FIFO")
        chars = timeout_char // (12000 // baud + 1)
        self._threshold = 1 if chars < 1 else 120
        self._tout_us = max(chars, 1) * 10000000 // baud
        self._tout_at = None
        self._rx_fifo = _Ring(128)
        self._rx_ring = _Ring(rxbuf)
        self._stash = None  # what the RX interrupt took and the ring could not
        self._tx_fifo = _Ring(128)
        self._tx_ring = _ItemRing(txbuf)
        self._txbuf = txbuf
        self._chunk = ((((txbuf // 2) + 3) & ~3) - 8) // 2

    def _any(self):
        return self._rx_ring.n

    # Receiving.

    def _rx_arrive(self, t, b):
        fifo = self._rx_fifo
        if fifo.n == 128:  # RXFIFO_OVF: the driver resets the FIFO
            self.overrun += fifo.n + 1
            fifo.clear()
            return
        fifo.put(b)
        self._tout_at = t + self._tout_us
        if self._stash is None and fifo.n > self._threshold:
            self._isr_rx()

    def _rx_start(self):
        self._tout_at = None  # a byte is coming: the line is not idle

    def _rx_timer(self):
        if self._stash is None and self._rx_fifo.n:
            return self._tout_at
        return None

    def _rx_timer_fire(self, t):
        if self._tout_at is not None and self._tout_at <= t:
            self._isr_rx()

    def _isr_rx(self):
        fifo, ring = self._rx_fifo, self._rx_ring
        self._tout_at = None
        if ring.cap - ring.n >= fifo.n:
            while fifo.n:
                ring.put(fifo.get())
            return
        data = bytearray(fifo.n)
        for i in range(len(data)):
            data[i] = fifo.get()
        self._stash = data

    def _check_buf_full(self):
        # After a read: the stash into the ring, if it fits now; RX interrupts
        # on again, and one that was waiting comes at once.
        stash, ring = self._stash, self._rx_ring
        if stash is None or ring.cap - ring.n < len(stash):
            return False
        for b in stash:
            ring.put(b)
        self._stash = None
        fifo = self._rx_fifo
        due = self._tout_at is not None and self._tout_at <= self._w._t
        if fifo.n and (fifo.n > self._threshold or due):
            self._isr_rx()
        return True

    def _ring_has(self):
        return self._rx_ring.n

    def _io_read(self, buf, off, n):
        got = self._read_bytes(buf, off, 1, self.timeout // 10)
        if n > 1 and got:
            got += self._read_bytes(buf, off + 1, n - 1, self.timeout_char // 10)
        return got or None

    def _read_bytes(self, buf, off, length, ticks):
        w = self._w
        ring = self._rx_ring
        copied = 0
        while length:
            if not ring.n and ticks:
                w._wait(self._ring_has, (w._t // _TICK_US + ticks) * _TICK_US)
            if not ring.n:
                if self._check_buf_full():
                    continue
                break
            k = min(length, ring.n)
            for _ in range(k):
                buf[off + copied] = ring.get()
                copied += 1
            length -= k
            self._check_buf_full()
        return copied

    # Sending.

    def _io_write(self, mv):
        n = len(mv)
        if not self._put_item(12, None):  # the descriptor
            return self._hung(0)
        off = 0
        while off < n:
            k = min(self._chunk, n - off)
            if not self._put_item(k, bytes(mv[off : off + k])):
                return self._hung(off)
            off += k
            self._isr_tx()
            self._w._tx_kick()
        return n

    def _put_item(self, size, data):
        ring = self._tx_ring
        w = self._w
        if not ring.fits(size):

            def room():
                return ring.fits(size)

            if not w._wait(room, w._t + self.hang_ms * 1000):
                return False
        ring.put(size, data)
        return True

    def _hung(self, put):
        if self.hang == "raise":
            raise Hang("an esp32 write() would block for ever here (%d bytes in)" % put)
        return put or None

    def _isr_tx(self):
        fifo = self._tx_fifo
        if fifo.n >= 10:
            return
        ring = self._tx_ring
        items = ring.items
        while fifo.n < 128 and items:
            item = items[0]
            data = item[1]
            if data is None:
                ring.pop()
                continue
            k = item[2]
            while k < len(data) and fifo.n < 128:
                fifo.put(data[k])
                k += 1
            item[2] = k
            if k == len(data):
                ring.pop()

    def _tx_take(self):
        fifo = self._tx_fifo
        if not fifo.n:
            return -1
        b = fifo.get()
        if fifo.n < 10:
            self._isr_tx()
        return b

    def _tx_pending(self):
        return self._tx_ring.pending() + self._tx_fifo.n

    def _flush_us(self):
        return (3 + self._txbuf) * 13000 * 2 // self._w.baudrate * _TICK_US


# The computer's side of a controller on USB: the port a program opens there. A USB-serial
# chip (an FTDI, a CH340) takes the controller's bytes off the 9600-baud wire and hands them
# to the computer every few ms (the FTDI's latency timer, 16 ms by default), or as soon as
# `most` wait; a HID controller answers at USB speed, a frame to a report, a report a poll of
# its endpoint (1 ms). Each hand-over reaches the program a busy computer's 0..busy_ms later
# (never before the one before it). name: (ms between hand-overs, bytes a hand-over carries
# at most, a frame to a hand-over, the line's baudrate: None, the world's).
LINKS = {
    "ch340": (2, 62, False, None),
    "ftdi": (16, 62, False, None),
    "hid": (1, 64, True, 1000000),
}
# What a computer may add to each hand-over when it is busy: the computer's ports say their
# latency_ms as their hand-overs' period and this (busservo_host.BUSY_MS: tests/test_host.py
# checks that they agree).
BUSY_MS = 20


class _USB(UART):
    """A computer's port behind USB (LINKS): write() takes what it is given at once (the OS's
    buffer is large) and the chip sends it at the baud rate; what the controller sends comes
    to any() and readinto() in hand-overs, as above. One write in preempt[0] leaves the
    program preempted for 0..preempt[1] ms (the clock moves on before write() returns).
    latency_ms is what the computer's port says of itself (busservo_host, busservo_hid)."""

    def __init__(self, world, link, busy_ms, preempt, seed):
        UART.__init__(self, world, 0, 1000, "return")
        every_ms, self._most, self._reports, _ = LINKS[link]
        self.latency_ms = every_ms + BUSY_MS
        self._every_us = every_ms * 1000
        self._busy_us = busy_ms * 1000
        self._preempt = preempt
        self._seed = seed
        self._phase = self._random(self._every_us)  # the chip's timer runs from its own start
        self._chip = bytearray()  # taken off the wire, not handed over yet
        self._tick_at = None  # the chip's next hand-over, while it holds bytes
        self._handed = []  # [due us, bytes]: handed over, not at the program yet
        self._due = 0  # when the last hand-over reaches the program
        self._host = bytearray()  # at the program: what any() counts
        self._tx_ring = _Ring(4096)

    def _random(self, n):
        # 0..n-1, the same run of them for the same seed.
        self._seed = (self._seed * 1103515245 + 12345) & 0x7FFFFFFF
        return (self._seed >> 8) % n if n > 0 else 0

    # Receiving.

    def _any(self):
        return len(self._host)

    def _io_read(self, buf, off, n):
        host = self._host
        k = min(n, len(host))
        for i in range(k):
            buf[off + i] = host[i]
        self._host = host[k:]  # (MicroPython's bytearray has no del of a slice)
        return k or None

    def wait(self, ms):
        """As a computer's port does: until bytes have come, or ms have passed (the clock
        moves on meanwhile), what a blocking query does between its steps."""
        w = self._w
        after = self._enter("wait")
        w._wait(self._any, w.clock.now_us + ms * 1000)
        if after:
            self._leave(after)

    def _rx_arrive(self, t, b):
        self._chip.append(b)
        if self._tick_at is None:
            every = self._every_us
            self._tick_at = t + every - (t - self._phase) % every
        if not self._reports and len(self._chip) >= self._most:
            self._hand_over(t)

    def _rx_start(self):
        pass

    def _take(self):
        # What one hand-over carries: up to `most` bytes, or a report's frame (by its Length;
        # its first `most` bytes if longer), None while the frame is still coming.
        chip = self._chip
        n = min(len(chip), self._most)
        if self._reports and n and chip[0] == 0x55:
            want = chip[2] + 2 if len(chip) > 2 else 257
            if len(chip) < min(want, self._most):
                return None
            n = min(want, self._most)
        data = bytes(chip[:n])
        self._chip = chip[n:]
        return data

    def _hand_over(self, t):
        data = self._take()
        if data:
            due = max(t + self._random(self._busy_us + 1), self._due)
            self._due = due
            self._handed.append([due, data])

    def _rx_timer(self):
        t = self._tick_at if self._chip else None
        if self._handed and (t is None or self._handed[0][0] < t):
            t = self._handed[0][0]
        return t

    def _rx_timer_fire(self, t):
        handed = self._handed
        while handed and handed[0][0] <= t:
            self._host += handed.pop(0)[1]
        if self._tick_at is not None and self._tick_at <= t:
            self._hand_over(t)
            self._tick_at = t + self._every_us if self._chip else None
        while handed and handed[0][0] <= t:
            self._host += handed.pop(0)[1]

    # Sending.

    def _io_write(self, mv):
        ring = self._tx_ring
        n = min(len(mv), ring.cap - ring.n)
        for i in range(n):
            ring.put(mv[i])
        self._w._tx_kick()
        preempt = self._preempt
        if n and preempt and not self._random(preempt[0]):
            self._w.clock.now_us += self._random(preempt[1] * 1000 + 1)
        return n or None

    def _tx_take(self):
        ring = self._tx_ring
        return ring.get() if ring.n else -1

    def _tx_pending(self):
        return self._tx_ring.n

    def _flush_us(self):
        return (self._tx_ring.cap + 1) * 10000000 // self._w.baudrate


class World:
    """A board's UART (w.uart), the wire, and a SimController (w.sim) at its far
    end, all on w.clock. keep: how many whole frames it keeps. Keyword arguments
    beyond the UART's go to the SimController (groups=, battery=)."""

    def __init__(
        self,
        port="rp2",
        baudrate=9600,
        call_us=5,
        cost_us=1,
        start="wrap",
        timeout=0,
        timeout_char=0,
        txbuf=None,
        rxbuf=None,
        hang_ms=1000,
        hang="return",
        clock=None,
        keep=KEEP,
        busy_ms=0,
        preempt=None,
        seed=1,
        deaf_ms=0,
        **sim,
    ):
        if port not in PORTS and port not in LINKS:
            raise ValueError(
                "port must be one of %s, got %r" % (PORTS + tuple(sorted(LINKS)), port)
            )
        if port in LINKS and LINKS[port][3]:
            baudrate = LINKS[port][3]  # HID: the controller takes and answers at USB speed
        self.port = port
        self.baudrate = baudrate
        self._deaf_us = deaf_ms * 1000  # the controller answers nothing before then
        self.call_us = call_us
        self.byte_us = 10000000 // baudrate  # (a byte takes this or 1 us more)
        self.clock = clock or Clock(start, cost_us)  # RealClock(): a live world
        self._t = 0  # how far the wire has been brought
        self._tx_line = _Line(baudrate)
        self._tx_busy = False
        self._tx_end = 0
        self._tx_byte = 0
        self._rx_line = _Line(baudrate)
        self._rx_busy = False
        self._rx_end = 0
        self._rx_byte = 0
        self._rx_queue = []  # [not before, bytearray, next index, noise?], in order
        self._drops = []  # [skip, n]
        self._cuts = []  # keep, one a frame
        self._lates = []  # [ms, count]
        # What the controller received, and when each byte was in; the frames in
        # it, parsed as the bytes come: _part holds the start of one still coming,
        # and is looked at again once it holds _need bytes.
        self._got = _Log(bytearray(KEEP_BYTES))
        self._got_at = _Log([0] * KEEP_LOG)
        self._junk = _Log(bytearray(KEEP_LOG))
        self._starts = _Log([0] * keep)  # where each frame starts in _got (its count)
        self._frame_at = _Log([0] * keep)
        self._part = bytearray(260)  # a frame is 257 bytes at most
        self._partn = 0
        self._need = 1
        self.on_frame = None  # called (us, frame) as each whole frame is in
        # What reached the board's pin.
        self._pin = _Log(bytearray(KEEP_LOG))
        self._pin_at = _Log([0] * KEEP_LOG)
        self._one = bytearray(1)
        self._sim = busservo_sim.SimController(ticks_ms=self._sim_ms, baudrate=None, **sim)
        self._says = hasattr(self._sim, "running")  # else: look at it every ms
        self._sim_active = False  # a group runs: look at the controller every ms
        self._poll_at = 0
        self._looked = False  # w.sim was looked at: it may have been told something
        if port in LINKS:
            self.uart = _USB(self, port, busy_ms, preempt, seed)
        else:
            cls = _RP2 if port == "rp2" else _ESP32
            self.uart = cls(self, timeout, timeout_char, txbuf, rxbuf, hang_ms, hang)

    @property
    def sim(self):
        """The controller, with the wire brought up to now."""
        self.sync()
        self._looked = True  # what it is told off the wire is collected at the next sync
        return self._sim

    def _sim_ms(self):
        # The controller's clock: the world's ms, unwrapped (the simulator does
        # its ticks arithmetic with the unix port's time, whose period is 2**62).
        return self.clock._ms0 + self._t // 1000

    # Observations.

    def received(self):
        """The bytes the controller has received (the last KEEP_BYTES)."""
        self.sync()
        return self._got.last()

    @property
    def sent_at(self):
        """When each of the last KEEP_LOG bytes received had arrived, in us."""
        self.sync()
        return self._got_at.last()

    @property
    def received_total(self):
        """How many bytes the controller has received."""
        self.sync()
        return self._got.total

    def frames(self, first=0):
        """The whole frames the controller received, by the protocol's lengths:
        the last keep of them (of those in the bytes kept), or those kept from
        the first-th on (counting from 0, as frames_total does)."""
        return [frame for _, frame in self.arrivals(first)]

    def arrivals(self, first=0):
        """(us, frame) of each whole frame of frames(first), in order: us is when
        its last byte had arrived, so when the controller had it."""
        self.sync()
        got = self._got
        gone = got.total - len(got.items)  # bytes no longer kept
        out = []
        for start, at in zip(self._starts.last(first), self._frame_at.last(first)):
            if start >= gone:
                size = got.items[(start + 2) % len(got.items)] + 2  # its Length byte
                out.append((at, got.span(start, start + size)))
        return out

    @property
    def frames_total(self):
        """How many whole frames the controller has received."""
        self.sync()
        return self._starts.total

    @property
    def garbled(self):
        """How many bytes the controller received formed no frame."""
        self.sync()
        return self._junk.total

    def garbage(self):
        """The bytes the controller received that formed no frame (the last KEEP_LOG)."""
        self.sync()
        return self._junk.last()

    def rest(self):
        """The start of a frame the controller is receiving (or that was cut)."""
        self.sync()
        return bytes(self._part[: self._partn])

    @property
    def arrived(self):
        """(us, byte) of each byte that reached the board's pin (the last KEEP_LOG)."""
        self.sync()
        return list(zip(self._pin_at.last(), self._pin.last()))

    @property
    def arrived_total(self):
        """How many bytes reached the board's pin."""
        self.sync()
        return self._pin.total

    def tx_backlog_us(self):
        """How long until the board's transmit side is empty (None: stalled)."""
        self.sync()
        pending = self.uart._tx_pending()
        if not self._tx_busy:
            return None if pending else 0
        if pending and self.uart._stalled:
            return None
        return self._tx_line.after(pending) - self._t

    def tx_pending(self):
        """How many bytes written have not arrived yet (the one on the wire too)."""
        self.sync()
        return self.uart._tx_pending() + self._tx_busy

    @property
    def overrun(self):
        self.sync()
        return self.uart.overrun

    # Faults on the line from the controller.

    def noise(self, data):
        """These bytes go onto the line to the board next (behind the byte on
        it now, before what the controller says next), at the baud rate."""
        self.sync()
        if data:
            q = self._rx_queue
            i = 0
            while i < len(q) and q[i][3]:  # behind the noise before it
                i += 1
            q.insert(i, [self._t, bytearray(data), 0, True])
            self._rx_kick(self._t)

    def drop(self, n=1, skip=0):
        """Of the bytes the controller says from now, skip skip, then lose n."""
        self.sync()
        self._drops.append([skip, n])

    def cut_reply(self, keep):
        """The next frame the controller says loses all but its first keep bytes."""
        self.sync()
        self._cuts.append(keep)

    def late(self, ms, count=1):
        """The next count frames the controller says go out ms later."""
        self.sync()
        self._lates.append([ms, count])

    # Time.

    def sync(self):
        """Bring the wire up to the clock."""
        self._run_to(self.clock.now_us)

    def run_ms(self, ms):
        """Let ms pass, and bring the wire up to it."""
        self.clock.sleep_ms(ms)
        self.sync()

    async def async_sleep_ms(self, ms):
        """asyncio.sleep_ms for the world: the clock moves, then the other tasks run."""
        self.clock.sleep_ms(ms)
        await _yield(0)

    # The wire.

    def _wait(self, cond, deadline):
        # A UART call waits: the clock moves event by event until cond() or the
        # deadline. True if cond().
        clock = self.clock
        while not cond():
            t = self._next()
            if t is None or t > deadline:
                if deadline > clock.now_us:
                    clock.now_us = deadline
                self._run_to(clock.now_us)
                return bool(cond())
            if t > clock.now_us:
                clock.now_us = t
            self._run_to(t)
        return True

    def _next(self):
        t = None
        if self._tx_busy:
            t = self._tx_end
        if self._rx_busy:
            if t is None or self._rx_end < t:
                t = self._rx_end
        elif self._rx_queue:
            nb = max(self._rx_queue[0][0], self._t)
            if t is None or nb < t:
                t = nb
        u = self.uart._rx_timer()
        if u is not None:
            u = max(u, self._t)
            if t is None or u < t:
                t = u
        if self._sim_active and (t is None or self._poll_at < t):
            t = self._poll_at
        return t

    def _run_to(self, target):
        if self._looked:
            self._looked = False
            self._collect(self._t)  # what it was told off the wire (w.sim.write()) says
        while True:
            t = self._next()
            if t is None or t > target:
                break
            self._t = t
            self._step(t)
        if target > self._t:
            self._t = target

    def _step(self, t):
        if self._tx_busy and self._tx_end == t:
            self._tx_done(t)
        if self._rx_busy and self._rx_end == t:
            self._rx_done(t)
        if self._rx_queue and not self._rx_busy:
            self._rx_kick(t)
        u = self.uart._rx_timer()
        if u is not None and u <= t:
            self.uart._rx_timer_fire(t)
        if self._sim_active and self._poll_at <= t:
            self._poll_at = (t // 1000 + 1) * 1000
            self._collect(t)

    def _tx_kick(self):
        # The transmitter starts the next byte, if idle and it has one.
        if self._tx_busy or self.uart._stalled:
            return
        b = self.uart._tx_take()
        if b >= 0:
            self._tx_byte = b
            self._tx_busy = True
            self._tx_end = self._tx_line.send(self._t)

    def _tx_done(self, t):
        # A byte's last bit is in: the controller has it.
        self._tx_busy = False
        b = self._tx_byte
        got = self._got
        k = got.total
        got.items[k % KEEP_BYTES] = b  # got.add(b) and _got_at.add(t), at a byte's cost
        self._got_at.items[k % KEEP_LOG] = t
        got.total = self._got_at.total = k + 1
        self._one[0] = b
        self._sim.write(self._one, 1)
        n = self._partn
        self._part[n] = b
        self._partn = n + 1
        if n + 1 >= self._need:
            self._parse(t)
        self._collect(t)
        self._tx_kick()

    def _parse(self, t):
        # What the bytes in _part are, as parse() has it, byte by byte: noise, a
        # whole frame, or the start of one (then _need: when to look again).
        p = self._part
        n = self._partn
        while n:
            noise = p[0] != 0x55 or (n > 1 and p[1] != 0x55)
            if not noise:
                if n < 4:
                    self._need = 2 if n < 2 else 4
                    break
                length = p[2]
                want = _LENGTHS.get(p[3])
                if isinstance(want, tuple):
                    if n < 5:
                        self._need = 5
                        break
                    want = want[0] * p[4] + want[1]
                noise = want != length
                if not noise:
                    if n < length + 2:
                        self._need = length + 2
                        break
                    self._whole(t, length + 2, n)
                    n = self._shift(length + 2, n)
                    continue
            self._junk.add(p[0])
            n = self._shift(1, n)
        else:
            self._need = 1
        self._partn = n

    def _shift(self, k, n):
        # The first k of n bytes in _part have been taken: the rest to its front.
        p = self._part
        for i in range(n - k):
            p[i] = p[k + i]
        return n - k

    def _whole(self, t, size, n):
        # A whole frame: the first size of the n bytes in _part.
        self._starts.add(self._got.total - n)
        self._frame_at.add(t)
        if self.on_frame is not None:
            self.on_frame(t, bytes(self._part[:size]))

    def _collect(self, t):
        # What the controller says goes onto the line to the board.
        sim = self._sim
        if sim.any():
            self._said(t, sim.read())
        active = sim.running is not None if self._says else True
        if active and not self._sim_active:
            self._poll_at = (t // 1000 + 1) * 1000
        self._sim_active = active

    def _said(self, t, data):
        if t < self._deaf_us:
            return  # just opened: it leaves its first moments unanswered
        for frame in _split(data):
            if self._cuts:
                frame = frame[: self._cuts.pop(0)]
            at = t
            if self._lates:
                late = self._lates[0]
                at += late[0] * 1000
                late[1] -= 1
                if late[1] <= 0:
                    self._lates.pop(0)
            if self._drops:
                frame = self._drop(frame)
            if frame:
                self._rx_queue.append([at, bytearray(frame), 0, False])
        self._rx_kick(t)

    def _drop(self, frame):
        kept = bytearray()
        for b in frame:
            lost = False
            for d in self._drops:
                if d[0] > 0:
                    d[0] -= 1
                elif d[1] > 0:
                    d[1] -= 1
                    lost = True
            if not lost:
                kept.append(b)
        self._drops = [d for d in self._drops if d[1] > 0]
        return kept

    def _rx_kick(self, t):
        # The line to the board starts its next byte, if idle and one is due.
        if self._rx_busy or not self._rx_queue:
            return
        seg = self._rx_queue[0]
        if seg[0] > t:
            return
        data = seg[1]
        k = seg[2]
        self._rx_byte = data[k]
        if k + 1 == len(data):
            self._rx_queue.pop(0)
        else:
            seg[2] = k + 1
        self._rx_busy = True
        self._rx_end = self._rx_line.send(t)
        self.uart._rx_start()

    def _rx_done(self, t):
        self._rx_busy = False
        b = self._rx_byte
        pin = self._pin
        k = pin.total
        pin.items[k % KEEP_LOG] = b
        self._pin_at.items[k % KEEP_LOG] = t
        pin.total = self._pin_at.total = k + 1
        self.uart._rx_arrive(t, b)
