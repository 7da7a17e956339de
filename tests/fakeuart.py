# A scripted stand-in for machine.UART, for tests that run without hardware.
#
#   uart = FakeUART()
#   uart.feed(b"\x55\x55\x02\x07")             # bytes the controller "sent"
#   uart.reply(request, response, delay_ms=5)  # answer a write, 5 ms later than the wire could
#   FakeUART(at_once=True)                     # a peer faster than the wire: answers at once
#   uart.chunks = [1]                          # readinto() hands out 1 byte a call
#   uart.takes = [3, None]                     # write() takes 3 bytes, then none, then all
#   uart.written()                             # every byte the driver wrote
#   with SimulatedTime() as clock: ...         # the driver and the fake on simulated time
#
# Like machine.UART, read() and readinto() return None when nothing is waiting
# and any() counts the bytes waiting. any(), readinto() and write() allocate
# nothing (when no reply is scripted), so allocation tests can use it too.
# Like a controller on a 9600-baud line, a scripted reply comes no sooner than
# the wire allows: once the request's last byte has left (behind what was
# written before it, a byte every 1042 us) and the reply's own bytes have come.
# With at_once, as a peer faster than that (a controller at another baud rate,
# one on USB HID, the fake a user writes first): readable as soon as the
# request's last byte is written, within that write() (delay_ms after it, if given).
import time

BYTE_US = 1042  # 10 bits at 9600 baud, rounded up


class SimulatedTime:
    """with SimulatedTime() as clock: the driver (busservo) and FakeUART on clock, a
    tests/wire.py Clock, which moves on only as the driver sleeps (and 1 us a ticks read).
    Where a test measures time (a query that must not wait, a deadline the UART's pace
    sets), what it measures is then the driver's, however busy the machine is."""

    def __enter__(self):
        global time
        import busservo
        import wire

        self._saved = busservo.time, time
        busservo.time = time = self.clock = wire.Clock()
        return self.clock

    def __exit__(self, *exc):
        global time
        import busservo

        busservo.time, time = self._saved


class FakeUART:
    def __init__(self, chunks=None, at_once=False):
        self.chunks = chunks
        self.at_once = at_once  # sizes readinto() hands out in turn; None: all asked for
        self._turn = 0
        self._in = bytearray()
        self._head = 0
        self._out = bytearray(4096)
        self._nout = 0
        self.writes = 0  # number of write() calls
        self.takes = None  # sizes write() takes in turn, None for nothing; used up or None: all
        self._replies = {}
        self._since = 0  # where in _out the request being written in parts began
        self._later = []  # [(due ticks_ms, bytes)], in order
        self._idle = time.ticks_us()  # when what was written has left the wire

    # What the tests do.

    def feed(self, data):
        """Make data readable now."""
        self._in = self._in[self._head :] + data
        self._head = 0

    def feed_later(self, data, delay_ms):
        """Make data readable delay_ms from now."""
        due = time.ticks_add(time.ticks_ms(), delay_ms)
        at = len(self._later)
        while at and time.ticks_diff(self._later[at - 1][0], due) > 0:
            at -= 1  # keep them in the order they are due
        self._later.insert(at, (due, bytes(data)))

    def reply(self, request, response, delay_ms=0):
        """Answer every write of exactly `request` (in one write() or in parts)
        with `response`, or with each of a list of responses in turn, one a write."""
        if isinstance(response, list):
            response = [bytes(r) for r in response]  # taken one a write
        else:
            response = bytes(response)  # the same every time
        self._replies[bytes(request)] = (response, delay_ms)

    def written(self):
        return bytes(self._out[: self._nout])

    def clear(self):
        self._nout = self._since = 0
        self.writes = 0

    # What machine.UART does.

    def _arrive(self):
        while self._later and time.ticks_diff(time.ticks_ms(), self._later[0][0]) >= 0:
            self.feed(self._later.pop(0)[1])

    def any(self):
        if self._later:
            self._arrive()
        return len(self._in) - self._head

    def readinto(self, buf, nbytes=None):
        n = self.any()
        if not n:
            return None
        if nbytes is None or nbytes > len(buf):
            nbytes = len(buf)
        if n > nbytes:
            n = nbytes
        if self.chunks:
            size = self.chunks[self._turn % len(self.chunks)]
            self._turn += 1
            if n > size:
                n = size
        head = self._head
        src = self._in
        for i in range(n):
            buf[i] = src[head + i]
        self._head = head + n
        return n

    def read(self, nbytes=None):
        n = self.any()
        if not n:
            return None
        buf = bytearray(n if nbytes is None else min(n, nbytes))
        return bytes(buf[: self.readinto(buf)])

    def write(self, buf, off=None, nbytes=None):
        # The stream protocol's forms: write(buf), write(buf, n), write(buf, off, n).
        if nbytes is None:
            nbytes = len(buf) if off is None else off
            off = 0
        if off > len(buf):
            off = len(buf)
        if nbytes > len(buf) - off:
            nbytes = len(buf) - off
        if self.takes:  # a full transmit buffer: take less, or nothing (None)
            take = self.takes.pop(0)
            if take is None:
                return None
            if nbytes > take:
                nbytes = take
        now = time.ticks_us()
        if time.ticks_diff(self._idle, now) < 0:
            self._idle = now
        self._idle = time.ticks_add(self._idle, nbytes * BYTE_US)
        out = self._out
        at = self._nout
        if at + nbytes > len(out):
            out = self._out = out + bytearray(at + nbytes)
        for i in range(nbytes):
            out[at + i] = buf[off + i]
        self._nout = at + nbytes
        self.writes += 1
        if self._replies:
            self._answer(at)
        return nbytes

    def _answer(self, at):
        # A request is answered once its last byte is written: in one write, or
        # in parts (a write() that took less, then the rest).
        for since in (self._since, at):
            got = bytes(self._out[since : self._nout])
            answer = self._replies.get(got)
            if answer:
                self._since = self._nout
                response = answer[0]
                if isinstance(response, list):
                    response = response.pop(0) if response else None
                if response and self.at_once and not answer[1]:
                    self.feed(response)
                elif response:
                    wire_us = 0
                    if not self.at_once:
                        wire_us = time.ticks_diff(self._idle, time.ticks_us())
                        wire_us += len(response) * BYTE_US
                    self.feed_later(response, answer[1] + (wire_us + 999) // 1000)
                return
            for request in self._replies:
                if request.startswith(got):  # more to come
                    self._since = since
                    return
        self._since = self._nout


class Answers:
    """A controller that answers every request at once with reply, made once (FakeUART's
    answers are made as they come): it allocates nothing."""

    def __init__(self, reply):
        self.reply = reply
        self.at = len(reply)  # nothing to read until a request comes

    def any(self):
        return len(self.reply) - self.at

    def readinto(self, buf, nbytes=None):
        n = self.any()
        if nbytes is not None and nbytes < n:
            n = nbytes
        for i in range(n):
            buf[i] = self.reply[self.at + i]
        self.at += n
        return n or None

    def write(self, buf, off=None, nbytes=None):
        self.at = 0
        return len(buf) if off is None else off if nbytes is None else nbytes
