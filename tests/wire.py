# A world as faithful as the wire, for tests: a clock the test steps, a board's
# UART modelled on MicroPython's own ports, the serial line at 10 bits a byte,
# and the simulated controller (lib/busservo_sim.py) at its far end.
#
#   w = wire.World("rp2")            # or "esp32"; wire.PORTS names them all
#   busservo.time = w.clock          # the driver's clock is the world's
#   bus = busservo.BusServo(w.uart)
#   w.clock.advance_ms(20)           # time passes; bytes cross the wire meanwhile
#   w.frames(), w.garbled            # what the controller received
#   w.noise(b"\x55\x55\x05")         # faults: noise, drop, cut_reply, late,
#   w.uart.fail("readinto", OSError(5)), w.uart.during(...), w.uart.stall(True)
#
# What the models do, as read in MicroPython's source:
# - ports/rp2/machine_uart.c: the transmit and receive rings hold txbuf and
#   rxbuf bytes (256 each by default; allocated one larger, as py/ringbuf.h
#   keeps one slot free), behind 32-byte hardware FIFOs. write() puts in the
#   ring what fits, then waits for room while less than `timeout` ms (0 by
#   default) have passed since it began, or `timeout_char` ms (at least 13 bit
#   times: 2 ms at 9600 baud) since the last byte it put; when that runs out it
#   returns what it put, or EAGAIN (None) if nothing. any() and read() first
#   move the hardware FIFO into the ring; bytes that find both full are lost
#   (an overrun). read() waits for each byte as write() does for room.
# - ports/esp32/machine_uart.c: txbuf and rxbuf default to 256 bytes (128-byte
#   FIFOs); write() is uart_write_bytes(), which blocks until all of it is in the
#   buffer. Received bytes reach the buffer, and any(), from the FIFO when the
#   rx full threshold has gathered or the line has been idle for the rx
#   timeout. With timeout_char=0 (the default) MicroPython sets the threshold
#   to 1 byte; with a longer timeout_char it keeps ESP-IDF's 120 and sets the
#   rx timeout to timeout_char in character times, so up to 120 bytes can sit
#   unseen in the FIFO in the middle of a long frame. When both are full the
#   FIFO overflows and is flushed.
# - py/stream.c: write(buf, n) writes the first n bytes, write(buf, off, n) n
#   bytes from off (clamped to the buffer); readinto(buf, n) clamps n to
#   len(buf); a read or write that could do nothing returns None.
# - extmod/modtime.c: ticks wrap at 2**30 on 32-bit ports; ticks_diff() is
#   signed modulo that period; ticks_add() refuses a delta of half of it.
import busservo_sim

PORTS = ("rp2", "esp32")

_PERIOD = 1 << 30
_MASK = _PERIOD - 1
_HALF = _PERIOD >> 1

# Command byte -> Length of the commands the controller takes (None: by count).
_LENGTHS = {3: None, 6: 5, 7: 2, 11: 5, 15: 2, 20: None, 21: None}


class Clock:
    """MicroPython's time, as drivers use it, on simulated time. Every ticks
    read costs cost_us, so that a busy-wait loop moves on."""

    def __init__(self, cost_us=1, us_wrap_s=1, ms_wrap_s=3):
        self.now_ns = 0
        self.cost_ns = cost_us * 1000
        self._us0 = _PERIOD - us_wrap_s * 1000000  # ticks_us wraps us_wrap_s in
        self._ms0 = _PERIOD - ms_wrap_s * 1000
        self.world = None

    @property
    def now_us(self):
        return self.now_ns // 1000

    def _spend(self, ns):
        self.now_ns += ns
        if self.world:
            self.world._update()

    def ticks_us(self):
        self._spend(self.cost_ns)
        return (self.now_ns // 1000 + self._us0) & _MASK

    def ticks_ms(self):
        self._spend(self.cost_ns)
        return (self.now_ns // 1000000 + self._ms0) & _MASK

    def ticks_diff(self, end, start):
        return ((end - start + _HALF) & _MASK) - _HALF

    def ticks_add(self, ticks, delta):
        if not -_HALF < delta < _HALF:
            raise OverflowError("ticks interval overflow")
        return (ticks + delta) & _MASK

    def sleep_us(self, us):
        self._spend(us * 1000)

    def sleep_ms(self, ms):
        self._spend(ms * 1000000)

    advance_us = sleep_us
    advance_ms = sleep_ms


class UART:
    """A port's machine.UART, its transmit side draining onto the wire."""

    def __init__(self, world, port, txbuf=256, rxbuf=256, timeout=0, timeout_char=0, call_us=5):
        self.world = world
        self.port = port
        self.timeout = timeout
        if port == "rp2":  # at least 13 bit times: 2 ms at 9600 baud, rounded up
            self.timeout_char = max(timeout_char, 2)
            self.threshold = self.idle_chars = 1
        else:  # esp32: the rx full threshold and timeout MicroPython sets
            self.timeout_char = timeout_char
            self.idle_chars = max(1, timeout_char * 96 // 100)  # char times at 9600 baud
            self.threshold = 1 if self.idle_chars == 1 and not timeout_char else 120
        self.fifo = 32 if port == "rp2" else 128
        self.tx_room = txbuf + self.fifo  # bytes written, not yet on the wire
        self.rx_room = rxbuf + (self.fifo if port == "rp2" else 0)
        self.call_ns = call_us * 1000
        self.rx = bytearray()  # what any() counts
        self.hidden = []  # esp32: (arrival ns, byte) in the FIFO, not yet in the buffer
        self.overrun = 0  # bytes lost to a full receive side
        self.stalled = False
        self.asked = []  # (method, n asked, len(buf)) of every read, for tests
        self._faults = []  # [method, skip, times, exc or None, callback, when]

    # Faults.

    def fail(self, method, exc, skip=0, times=1):
        self._faults.append([method, skip, times, exc, None, "before"])

    def during(self, method, callback, when="before", skip=0, times=1):
        self._faults.append([method, skip, times, None, callback, when])

    def stall(self, on=True):
        self.world._update()
        self.stalled = on
        if not on:
            self.world._restart_tx()

    def _enter(self, method):
        self.world.clock._spend(self.call_ns)
        after = None
        for fault in self._faults:
            if fault[0] == method and fault[2] > 0:
                if fault[1] > 0:
                    fault[1] -= 1
                    continue
                fault[2] -= 1
                if fault[3] is not None:
                    raise fault[3]
                if fault[5] == "before":
                    fault[4]()
                else:
                    after = fault[4]
        return after

    # machine.UART's methods.

    def any(self):
        after = self._enter("any")
        n = len(self.rx)
        if after:
            after()
        return n

    def readinto(self, buf, nbytes=None):
        after = self._enter("readinto")
        n = len(buf) if nbytes is None else min(nbytes, len(buf))
        self.asked.append(("readinto", nbytes, len(buf)))
        got = self._read(n)
        for i in range(len(got)):
            buf[i] = got[i]
        if after:
            after()
        return len(got) or None

    def read(self, nbytes=None):
        after = self._enter("read")
        got = self._read(len(self.rx) if nbytes is None else nbytes)
        if after:
            after()
        return bytes(got) if got else None

    def _read(self, n):
        got = bytearray()
        clock = self.world.clock
        while len(got) < n:
            if self.rx:
                take = min(n - len(got), len(self.rx))
                got += self.rx[:take]
                self.rx = self.rx[take:]
                continue
            if self.port != "rp2":
                break
            # rp2: wait for the next byte, up to timeout (first) or timeout_char.
            wait = self.timeout_char if got else self.timeout
            start_ms = clock.now_ns // 1000000
            while not self.rx and clock.now_ns // 1000000 - start_ms <= wait:
                clock._spend(10000)
            if not self.rx:
                break
        return got

    def write(self, buf, a=None, b=None):
        after = self._enter("write")
        if b is None:
            off, n = 0, len(buf) if a is None else min(a, len(buf))
        else:
            off = min(a, len(buf))
            n = min(b, len(buf) - off)
        data = bytes(buf[off : off + n])
        world = self.world
        clock = world.clock
        put = self._put(data)
        if self.port == "esp32":
            while put < n and not self.stalled:  # blocks until all is in its buffer
                clock._spend(10000)
                put += self._put(data[put:])
            if put < n:  # stalled: its driver would block for ever; a test gives up here
                clock._spend(1000000000)
        else:
            start_ms = clock.now_ns // 1000000
            wait = self.timeout
            while put < n:
                while world.tx_pending() >= self.tx_room:
                    if clock.now_ns // 1000000 - start_ms > wait:
                        break
                    clock._spend(10000)
                else:
                    put += self._put(data[put : put + 1])
                    start_ms = clock.now_ns // 1000000
                    wait = self.timeout_char
                    continue
                break
        if after:
            after()
        return put or (None if n else 0)

    def _put(self, data):
        world = self.world
        world._update()
        room = self.tx_room - world.tx_pending()
        take = data[: max(0, room)]
        world._transmit(take)
        return len(take)


class World:
    def __init__(self, port="rp2", baudrate=9600, call_us=5, cost_us=1, **uart):
        self.port = port
        self.clock = Clock(cost_us)
        self.byte_ns = 10 * 1000000000 // baudrate
        self.uart = UART(self, port, call_us=call_us, **uart)
        self._t = 0  # the time the controller lives at while it is fed
        # The simulator does its ticks arithmetic with its module's time: the world's.
        busservo_sim.time = self.clock
        self.sim = busservo_sim.SimController(ticks_ms=self._sim_ticks_ms)
        self._tx = bytearray()  # board -> controller, not yet arrived
        self._tx_end = 0  # when the byte on the wire now has arrived
        self._line = []  # controller -> board: [arrival ns, byte], in order
        self._line_free = 0  # when the return line is free
        self._received = bytearray()
        self._drop = []  # [skip, n]
        self._cut = None
        self._late = []  # [ms, count]
        self.clock.world = self

    def _sim_ticks_ms(self):
        return (self._t // 1000000 + self.clock._ms0) & _MASK

    # Faults on the line from the controller.

    def noise(self, data):
        """These bytes go onto the line to the board next, at the baud rate."""
        self._update()
        self._send_back(bytes(data), self.clock.now_ns, raw=True)

    def drop(self, n=1, skip=0):
        self._drop.append([skip, n])

    def cut_reply(self, keep):
        self._cut = keep

    def late(self, ms, count=1):
        self._late.append([ms, count])

    # What the controller received.

    def received(self):
        self._update()
        return bytes(self._received)

    def frames(self):
        """The whole frames the controller received, by the protocol's lengths;
        bytes that formed none are counted in garbled."""
        data = self.received()
        frames = []
        garbled = 0
        i = 0
        while i < len(data):
            if data[i : i + 2] != b"\x55\x55" or len(data) - i < 4:
                garbled += 1
                i += 1
                continue
            length, cmd = data[i + 2], data[i + 3]
            want = _LENGTHS.get(cmd, -1)
            if want is None:
                if len(data) - i < 5:
                    garbled += len(data) - i
                    break
                want = 3 * data[i + 4] + 5 if cmd == 3 else data[i + 4] + 3
            if want != length or len(data) - i < length + 2:
                garbled += 1
                i += 1
                continue
            frames.append(data[i : i + length + 2])
            i += length + 2
        self.garbled = garbled
        return frames

    @property
    def garbled(self):
        self.frames()
        return self._garbled

    @garbled.setter
    def garbled(self, value):
        self._garbled = value

    def tx_backlog_us(self):
        self._update()
        if not self._tx:
            return 0
        return (self._tx_end + (len(self._tx) - 1) * self.byte_ns - self.clock.now_ns) // 1000

    # The wire.

    def tx_pending(self):
        return len(self._tx)

    def _transmit(self, data):
        if not data:
            return
        if not self._tx and not self.uart.stalled:
            self._tx_end = self.clock.now_ns + self.byte_ns
        self._tx += data

    def _restart_tx(self):
        if self._tx:
            self._tx_end = self.clock.now_ns + self.byte_ns

    def _update(self):
        now = self.clock.now_ns
        # Board -> controller: each byte is the controller's when its last bit is in.
        while self._tx and not self.uart.stalled and self._tx_end <= now:
            self._t = self._tx_end
            byte = self._tx[0]
            self._tx = self._tx[1:]
            self._received.append(byte)
            self.sim.write(bytes((byte,)))
            self._answer(self._t)
            if self._tx:
                self._tx_end += self.byte_ns
        # What the controller says by itself (COMPLETE when a group ends).
        self._t = now
        self._answer(now)
        # Controller -> board.
        line = self._line
        uart = self.uart
        while line and line[0][0] <= now:
            t, byte = line.pop(0)
            if uart.port == "esp32":
                uart.hidden.append((t, byte))
            elif len(uart.rx) < uart.rx_room:
                uart.rx.append(byte)
            else:
                uart.overrun += 1
        if uart.port == "esp32" and uart.hidden:
            idle = now - uart.hidden[-1][0] >= uart.idle_chars * self.byte_ns
            if len(uart.hidden) >= uart.threshold or idle:
                for _, byte in uart.hidden:
                    if len(uart.rx) < uart.rx_room:
                        uart.rx.append(byte)
                    else:
                        uart.overrun += 1
                uart.hidden = []
            elif len(uart.hidden) > uart.fifo:
                uart.overrun += len(uart.hidden)
                uart.hidden = []

    def _answer(self, t):
        data = self.sim.read()
        if data:
            self._send_back(data, t)

    def _send_back(self, data, t, raw=False):
        if not raw:
            if self._cut is not None:
                data = data[: self._cut]
                self._cut = None
            if self._late:
                t += self._late[0][0] * 1000000
                self._late[0][1] -= 1
                if not self._late[0][1]:
                    self._late.pop(0)
        start = max(t, self._line_free)
        for byte in data:
            if not raw and self._drop:
                d = self._drop[0]
                if d[0] > 0:
                    d[0] -= 1
                else:
                    d[1] -= 1
                    if not d[1]:
                        self._drop.pop(0)
                    continue
            start += self.byte_ns
            self._line.append([start, byte])
        self._line_free = start
