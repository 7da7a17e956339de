# busservo: MicroPython driver for the serial Bus Servo Controller
# (LOBOT/Hiwonder-style boards, frames that start 0x55 0x55, 9600 baud).
#
# Every frame on the wire, in both directions, is
#
#     0x55 0x55  Length  Cmd  Prm 1 ... Prm N        with Length = N + 2
#
# and 16-bit values travel low byte first. There is no checksum and no
# request number. Commands are encoded into buffers made in __init__; the
# controller's frames are read into another and decoded where they lie, so no
# call allocates.
import errno
import time

try:
    from micropython import const
except ImportError:  # CPython, on a computer: busservo_cpython gives what it lacks
    from busservo_cpython import bytearray8 as bytearray  # keeps the low 8 bits, as here
    from busservo_cpython import const, time

__version__ = "0.1.0"  # as package.json says

CMD_SERVO_MOVE = const(3)
CMD_ACTION_GROUP_RUN = const(6)
CMD_ACTION_GROUP_STOP = const(7)
CMD_ACTION_GROUP_COMPLETE = const(8)
CMD_ACTION_GROUP_SPEED = const(11)
CMD_GET_BATTERY_VOLTAGE = const(15)
CMD_MULT_SERVO_UNLOAD = const(20)
CMD_MULT_SERVO_POS_READ = const(21)
ALL_GROUPS = const(0xFF)  # CMD_ACTION_GROUP_SPEED: every downloaded group

_HEADER = const(0x55)
_FRAME_MAX = const(257)  # header + the largest Length byte, 255
_CHUNK = const(16)  # bytes read from the UART at a time (17 ms of them at 9600 baud)
_RX_SIZE = const(272)  # a partial frame (256 bytes at most), and a chunk behind it
_BUDGET = const(1028)  # bytes one poll() reads at most, so a flood of noise cannot hold it
_QUEUE = const(32)  # frames a blocking query may hold back for poll()
_HELD = const(96)  # where in _asked they are held (one buffer: RAM, see Memory in docs)
_HEARD = const(12)  # _waiting[_HEARD]: ticks_ms of the last read that brought bytes
_BUSY = const(13)  # _waiting[_BUSY]: 1 while decoding (a callback that polls gets None)
_LINK = const(14)  # _waiting[_LINK]: the link's latency_ms (-1: at any pace, see __init__)
_READ = const(15)  # _waiting[_READ]: bytes read (modulo 2**30), for what a timeout says
_TIMEOUT_MS = const(100)  # battery: 10 bytes at 9600 baud take about 10 ms
_TIMEOUT_PER_ID_MS = const(10)  # 4 more bytes on the wire and one servo to ask
_TIMEOUT_MAX_MS = const(60000)
_LATE_MS = const(100)  # how long after its query gave up a reply may still come
_FORGET_MS = const(1000)  # a query listens first for a reply given up on up to this long ago
_GAP_MS = const(20)  # a frame's bytes come closer together than this, FIFOs and all (and
# the link's latency_ms: a computer's port on USB hands bytes over every few ms)
_BURST_MS = const(3)  # back to back replies come closer together than this (no FIFO)
_LINGER_MS = const(10)  # a peer faster than the wire sends a reply right behind another so
_TICKS = const(0x3FFFFFFF)  # ticks modulo 2**30, as a 32-bit port's wrap
_HALF = const(0x20000000)  # half of that: a later time, or an earlier one
_AHEAD_MS = const(40000)  # more ahead than this: ticks came round (rp2's largest txbuf: 34 s)
_WAIT_MS = const(2)  # a blocking query's look at the link, if it can wait (see _run)
_SLACK_MS = const(50)  # for a UART's transmit buffer to make room, beyond the wire time


# Builtins are slow to look up; module globals are quick. The hot paths check
# their arguments' types with these. (They store 16-bit values' low bytes with
# no mask: a MicroPython bytearray keeps the low 8 bits of what it is given, and
# on CPython busservo_cpython.bytearray8, which does the same.)
_type = type
_int = int


def _check(name, value, low, high):
    # Refuse what the wire cannot carry, naming the argument, its range and what came.
    error = ValueError if _type(value) is _int else TypeError
    if error is TypeError or not low <= value <= high:
        raise error("%s must be an int in %d..%d, got %r" % (name, low, high, value))


def _count(name, items, high):
    # How many items a sequence argument holds, refused unless 1..high.
    try:
        n = len(items)
    except TypeError:  # not a sequence at all (one id, say): show it as one
        raise TypeError("%s must be a list, such as [%r], got %r" % (name, items, items))
    if not 1 <= n <= high:
        raise ValueError("%s must be a list of 1..%d items, got %d of them" % (name, high, n))
    return n


# Two of the driver's own helpers are functions of the module rather than methods: a class
# of 23 names keeps them in a table of 23 entries, one of 25 in a table of 29 (48 bytes more).


def _group_cmd(bus, cmd, group, name, value):
    # A group command (RUN, SPEED): the group, and value (name) as 16 bits.
    _check("group", group, 0, 0xFF)
    _check(name, value, 0, 0xFFFF)
    if bus._cut_at:
        bus._finish()
    tx = bus._tx
    tx[4] = group
    tx[5] = value
    tx[6] = value >> 8
    bus._send(cmd, 3)


def _hold(bus, cmd):
    # Keep a frame that came during bus's query for poll(); its state is applied.
    if cmd is not None:
        if bus._queued < _QUEUE:
            bus._asked[_HELD + bus._queued] = cmd
            bus._queued += 1
        else:
            bus.lost += 1


def _run(bus, query):
    # Run a query (ask()) to its end. A link that can wait in the OS until bytes come (a
    # computer's port: wait(ms)) waits between its steps, so that a query costs no CPU; a
    # board's UART cannot, and a board has nothing else to run meanwhile.
    wait = getattr(bus._uart, "wait", None)
    for _ in query:
        if wait:
            wait(_WAIT_MS)


def _size(bus, f, w, look=True):
    # What rx[f:w] starts with: the size of a frame of the controller's (all of it may not
    # have come yet), 0 if none starts there, or -1 if too few bytes have come to tell. The
    # controller sends these, with these Lengths (0: none): RUN 5, STOP 2, COMPLETE 5,
    # battery 4, positions 3n + 3, in reply to n >= 1 ids (Prm 1) a request in flight asked.
    rx = bus._rx
    have = w - f
    if rx[f] != _HEADER or have > 1 and rx[f + 1] != _HEADER:
        return 0
    if have < 4:
        return -1
    cmd = rx[f + 3]
    if cmd == CMD_MULT_SERVO_POS_READ:
        waiting = bus._waiting
        if not (waiting[1] or waiting[3]) or rx[f + 2] < 6:
            return 0
        if have < 5:
            return -1
        n = rx[f + 4]
        ok = 3 * n + 3 if n and bus._asked[85 + (n >> 3)] >> (n & 7) & 1 else 0
    elif cmd == CMD_ACTION_GROUP_RUN or cmd == CMD_ACTION_GROUP_COMPLETE:
        ok = 5
    elif cmd == CMD_ACTION_GROUP_STOP:
        ok = 2
    else:
        ok = 4 if cmd == CMD_GET_BATTERY_VOLTAGE else 0
    if not ok or rx[f + 2] != ok:
        return 0
    # With look, bytes tell first whether it was cut short: another frame of the
    # controller's starts where its Length says its own body goes on (then it is none, 0;
    # -1 while too few bytes tell). 55 55 where a position reply has servo 85 asked is its
    # id and a position's low byte, not a frame.
    end = f + ok + 3
    if end > w:
        end = w
    at = rx.find(b"\x55\x55", f + 3, end) if look else -1
    while at >= 0:
        n = at - f - 5  # from the first id of a position reply
        if not (cmd == CMD_MULT_SERVO_POS_READ and n % 3 == 0 and bus._asked[n // 3 + 1] == 85):
            n = _size(bus, at, w, False)
            if n:
                return 0 if n > 0 else -1
        at = rx.find(b"\x55\x55", at + 1, end)
    return ok + 2


class BusServo:
    def __init__(self, uart, baudrate=9600):
        _check("baudrate", baudrate, 1200, 1000000)
        if not hasattr(uart, "readinto"):  # a path, say: boards/unix.py opens one
            raise TypeError("uart needs any/readinto/write, got %r" % (uart,))
        self._uart = uart
        self._write = uart.write  # one lookup, not two, per command
        # How the link's bytes come: a board's UART says nothing, and they come as the wire
        # paces them. A computer's port behind USB says how much later than the wire they may
        # come (latency_ms: a USB-serial chip hands them over every few ms, a busy computer
        # later still), or None: at any pace (a pty), when no pause tells anything.
        link = getattr(uart, "latency_ms", 0)
        if link is None:
            link = -1
        else:
            _check("uart.latency_ms", link, 0, _TIMEOUT_MAX_MS)
        self._any = uart.any
        # The wire: a byte is 10 bits (8N1), 10000 / baudrate ms. _idle (ticks_ms) and _frac
        # (in 1/baudrate ms, so a byte is 10000 of them: exact) say when what was written
        # will have left it. _idle, and the times taken from it, are ticks modulo 2**30, as a
        # 32-bit port counts, compared by masked differences: right on the unix port's
        # longer ticks too.
        self._baud = baudrate
        self._idle = time.ticks_ms()
        self._frac = 0
        self._cut_at = 0  # bytes of it sent (0: nothing is cut)
        tx = self._tx = bytearray(_FRAME_MAX)
        tx[0] = tx[1] = _HEADER  # reading never uses tx: it stays
        # Reading: the UART's bytes go through _chunk into rx[_r:_w], where
        # frames are decoded. (readinto() cannot start mid-buffer without a
        # memoryview slice, which allocates.)
        self._rx = bytearray(_RX_SIZE)
        self._chunk = bytearray(_CHUNK)
        self._r = self._w = 0
        self._queued = 0  # commands of frames held back by queries: _asked[_HELD:]
        # Replies that may still come, of each kind: [battery, positions] to the
        # requests in flight, then [battery, positions] to those a query gave up
        # on (see ask()); then [battery, positions]: when (ticks_ms) the last
        # request of each kind has left the wire, and the last of those given up
        # on; then [battery, positions]: 1 if a reply that fits the request in
        # flight came too soon for it and was taken for a late one (see _apply);
        # then [battery, positions]: the peer's pace, as the last reply that
        # answered a request of that kind (the only one in flight) showed it: 1
        # sooner than the wire allows, 0 not, 2 none yet. Then _HEARD, _BUSY, _LINK, _READ.
        # And the ids of the positions asked last, with a bit for each count of
        # ids a positions request in flight asked for; then the queue.
        self._waiting = [0] * 10 + [2, 2, self._idle, 0, link, 0]  # (nothing heard yet: now)
        self._asked = bytearray(_HELD + _QUEUE)  # count, ids; bit n of 85..95: n ids (1..84)
        self.noise = 0  # bytes read that were no frame of the controller's
        self.lost = 0  # frames not held because the queue was full
        self.early = 0  # replies taken that came sooner than the wire at baudrate allows
        self.running = False
        self.group = None
        self.times = 0
        self.battery = None
        self.positions = {}

    # Commands. Each checks all its arguments before it writes anything.

    def move(self, servo_id, position, time_ms):
        """CMD_SERVO_MOVE: move one servo to position within time_ms."""
        if (
            not (_type(servo_id) is _type(position) is _type(time_ms) is _int)
            or servo_id >> 8
            or (position | time_ms) >> 16
        ):  # one quick test for the usual case; _check() says what is wrong
            _check("servo_id", servo_id, 0, 0xFF)
            _check("position", position, 0, 0xFFFF)
            _check("time_ms", time_ms, 0, 0xFFFF)
        if self._cut_at:
            self._finish()
        frame = self._tx  # header in place; Length 8, CMD_SERVO_MOVE (3), 1 servo
        frame[2] = 8
        frame[3] = CMD_SERVO_MOVE
        frame[4] = 1
        frame[5] = time_ms
        frame[6] = time_ms >> 8
        frame[7] = servo_id
        frame[8] = position
        frame[9] = position >> 8
        servo_id = time.ticks_ms()  # before the write, which may wait (see _sent)
        took = self._write(frame, 10)
        if took != 10:
            self._finish(took, servo_id)
        else:  # the usual case: the UART took it all. _sent(10, now), inline (see there).
            position = 100000  # 10 bytes
            if (self._idle - servo_id) & _TICKS < _AHEAD_MS:
                servo_id = self._idle
                position += self._frac
            self._idle = (servo_id + position // self._baud) & _TICKS
            self._frac = position % self._baud

    def move_many(self, servos, time_ms):
        """CMD_SERVO_MOVE: move 1..83 servos, given as (id, position) pairs or a
        dict {id: position}, together within time_ms."""
        n = len(servos) if _type(servos) is list else 0  # (a call costs more than a test)
        if n < 1 or n > 83 or _type(time_ms) is not _int or time_ms >> 16:
            if _type(servos) is dict:
                servos = servos.items()
            _count("servos", servos, 83)  # or say what is wrong
            _check("time_ms", time_ms, 0, 0xFFFF)
        if self._cut_at:
            self._finish()  # before tx, which may hold its rest, is overwritten
        tx = self._tx
        i = 7
        for pair in servos:
            try:
                servo_id, position = pair
            except (TypeError, ValueError):
                raise TypeError("servos must be (id, position) pairs, got %r" % (pair,))
            if (
                _type(servo_id) is not _int
                or _type(position) is not _int
                or servo_id >> 8
                or position >> 16
            ):
                _check("servo_id", servo_id, 0, 0xFF)
                _check("position", position, 0, 0xFFFF)
            tx[i] = servo_id
            tx[i + 1] = position
            tx[i + 2] = position >> 8
            i += 3
        tx[4] = (i - 7) // 3  # the pairs read: not len(), if servos changed meanwhile
        tx[5] = time_ms
        tx[6] = time_ms >> 8
        self._send(CMD_SERVO_MOVE, i - 4)  # parameters from tx[4] up to i: 3 + 3n

    def run_group(self, group, times=1):
        """CMD_ACTION_GROUP_RUN: run action group `group` `times` times; 0 = forever."""
        _group_cmd(self, CMD_ACTION_GROUP_RUN, group, "times", times)

    def stop_group(self):
        """CMD_ACTION_GROUP_STOP: stop the running action group, if any."""
        if self._cut_at:
            self._finish()
        self._send(CMD_ACTION_GROUP_STOP, 0)

    def set_group_speed(self, group, percent):
        """CMD_ACTION_GROUP_SPEED: run `group` (ALL_GROUPS for all) at percent %.
        The controller forgets this at power-off."""
        _group_cmd(self, CMD_ACTION_GROUP_SPEED, group, "percent", percent)

    def unload(self, ids):
        """CMD_MULT_SERVO_UNLOAD: let 1..252 servos go limp."""
        self._ids_cmd(CMD_MULT_SERVO_UNLOAD, ids, 252)

    def request_battery(self):
        """CMD_GET_BATTERY_VOLTAGE: ask for the voltage; the reply comes through poll()."""
        if self._cut_at:
            self._finish()
        self._send(CMD_GET_BATTERY_VOLTAGE, 0)

    def request_positions(self, ids):
        """CMD_MULT_SERVO_POS_READ: ask for 1..84 positions (the reply must fit
        in a Length byte); the reply comes through poll()."""
        self._ids_cmd(CMD_MULT_SERVO_POS_READ, ids, 84)

    def _went(self, cmd):
        # A frame has gone whole (tx holds it). If a request, one more reply
        # may come: count it, so that no reply answers a later request, and
        # note when it will have left the wire (2 ms early: ticks are whole ms).
        kind = cmd == CMD_MULT_SERVO_POS_READ
        if kind or cmd == CMD_GET_BATTERY_VOLTAGE:
            waiting = self._waiting
            waiting[kind + 4] = (self._idle - 2) & _TICKS
            if kind:
                asked = self._asked
                if not (waiting[1] or waiting[3]):  # none in flight: forget the old counts
                    for i in range(85, 96):
                        asked[i] = 0
                tx = self._tx
                n = tx[4]
                asked[85 + (n >> 3)] |= 1 << (n & 7)
                for i in range(n + 1):
                    asked[i] = tx[4 + i]  # the count and the ids, as sent
            waiting[kind] += 1

    def _ids_cmd(self, cmd, ids, high):
        n = _count("ids", ids, high)
        if self._cut_at:
            self._finish()  # before tx, which may hold its rest, is overwritten
        tx = self._tx
        i = 5
        for servo_id in ids:
            if _type(servo_id) is not _int or servo_id >> 8:
                _check("servo_id in ids", servo_id, 0, 0xFF)
            tx[i] = servo_id
            i += 1
        tx[4] = n
        self._send(cmd, n + 1)

    # The wire. A port's UART.write() takes what fits in its transmit buffer
    # and returns that count, or None if nothing fit (rp2 with timeout=0), or
    # waits for room (esp32). A frame leaves whole, or the call raises.

    def wire_ms(self):
        """How many ms of what was written are still ahead on the wire (0 when
        idle). A query's timeout counts from when its request has left it."""
        ahead = (self._idle - time.ticks_ms()) & _TICKS
        return ahead + (self._frac > 0) if ahead < _AHEAD_MS else 0

    def _send(self, cmd, nparams):
        # Send the frame in tx with nparams parameters. Its caller has finished a cut
        # frame (_finish()) before it wrote them.
        tx = self._tx
        tx[2] = nparams + 2
        tx[3] = cmd
        n = nparams + 4
        now = time.ticks_ms()
        took = self._write(tx, n)  # the first n bytes, without a slice
        if took == n:
            self._sent(n, now)
            if cmd >= CMD_GET_BATTERY_VOLTAGE:  # a request, maybe (_went() sees): not a move
                self._went(cmd)
        else:
            self._finish(took, now)

    def _sent(self, n, now):
        # n more bytes are on their way: the wire is busy until they have left,
        # behind what is on it already (or from now, if it was idle). Kept in
        # ms, which wrap after 12 days (us would after 18 minutes), and _frac.
        # now is the time before the write: one that waited for room (esp32's
        # does) has seen its first bytes leave already.
        idle = self._idle
        units = n * 10000  # 1/baudrate ms
        if (idle - now) & _TICKS < _AHEAD_MS:
            units += self._frac
        else:
            idle = now
        self._idle = (idle + units // self._baud) & _TICKS
        self._frac = units % self._baud

    def _finish(self, at=-1, now=0):
        # Write the rest of the frame in tx that the UART took only part of (from
        # at, its write begun at now; by default, the rest of a cut one) as the
        # wire makes room for it, up to a deadline the wire time sets. Past it,
        # raise; if part of the frame went (_cut_at > 0), the next command sends
        # its rest first, so the controller never reads a new frame as the tail of
        # a cut one (which is why every command finishes it before it uses tx).
        buf = self._tx
        if at == -1:
            at = self._cut_at
        else:
            at = at or 0  # write() returns None when it took nothing
            self._sent(at, now)
        end = buf[2] + 2  # the frame's length, by its Length byte
        deadline = time.ticks_add(
            time.ticks_ms(), self.wire_ms() + (end - at) * 10000 // self._baud + _SLACK_MS
        )
        while at < end:
            self._cut_at = at
            now = time.ticks_ms()
            took = self._write(buf, at, end - at) or 0
            if took:
                self._sent(took, now)
                at += took
            elif time.ticks_diff(now, deadline) >= 0:
                raise OSError(errno.EIO, "%d of %d bytes sent" % (at, end))
            else:
                time.sleep_us(10000000 // self._baud)  # room comes a byte at a time
        self._cut_at = 0
        self._went(buf[3])

    # Queries. The protocol numbers no requests, so a reply is known to answer
    # ours only if nothing else of its kind can be on its way: the requests that
    # went are counted (_went), and a query first lets their replies come
    # (poll() gets them), or its time for them run out.

    def read_battery(self, timeout_ms=_TIMEOUT_MS):
        """Battery voltage in mV. Raises OSError(ETIMEDOUT) if no reply comes
        within timeout_ms of the request leaving the wire."""
        _run(self, self.ask(None, timeout_ms))
        return self.battery

    def read_positions(self, ids, timeout_ms=None):
        """{servo_id: position} for 1..84 servos; positions are signed (a servo
        near 0 may say -3). Raises OSError(ETIMEDOUT) if no reply comes; the
        default timeout is 100 ms plus 10 ms per servo. Only a reply that
        carries exactly these ids, in this order, answers it."""
        _run(self, self.ask(ids, timeout_ms))
        got = {}
        for servo_id in ids:
            got[servo_id] = self.positions[servo_id]
        return got

    def ask(self, ids=None, timeout_ms=None, again=False):
        """A query step by step, for a scheduler such as busservo_async: a
        generator that asks for the battery (ids None) or for the positions of
        ids, yields while it waits, and ends once the reply has come (then
        battery or positions hold it). It raises as read_battery() does.
        With again, it asks again and again, for a loop that reads for ever:
        it yields None while it waits, then True once the reply has come, or
        False once none came in time (it does not raise), and its next step
        asks anew. Made once, it takes no heap a read (a new ask() takes its
        generator's)."""
        kind = ids is not None  # 0: the battery, 1: positions (as in _waiting)
        waiting = self._waiting
        ms = time.ticks_ms
        diff = time.ticks_diff
        if timeout_ms is None:
            timeout_ms = _TIMEOUT_MS + (kind and _TIMEOUT_PER_ID_MS * _count("ids", ids, 84))
        _check("timeout_ms", timeout_ms, 0, _TIMEOUT_MAX_MS)
        # A link behind USB may hand bytes over up to latency_ms later than the wire brought
        # them: each wait below is that much longer (none on a link at any pace).
        lag = waiting[_LINK]
        if lag < 0:
            lag = 0
        timeout_ms += lag
        gap = _GAP_MS + lag
        while True:  # one query (with again, one after another)
            if self._cut_at:
                self._finish()  # a request cut short goes first: its reply is waited out
            start = time.ticks_add(ms(), self.wire_ms())  # when the wire is free
            # Those given up on long ago are not listened for (their replies were likely lost),
            # but still counted: a reply too soon for this query may be one of them. Those of
            # either kind are: the controller answers in turn, and a burst of late replies of
            # the other kind may hold this kind's behind it.
            given = (waiting[2] and (start - waiting[6]) & _TICKS <= _FORGET_MS) or (
                waiting[3] and (start - waiting[7]) & _TICKS <= _FORGET_MS
            )
            while True:  # decode what has come first: none of it answers this query
                got = self._next_frame()
                _hold(self, got)
                # Earlier requests of this kind may still be answered: let their replies
                # come (as events), for as long as this query would wait for its own,
                # and a late one, in the worst case (however fast other frames come).
                # Those a query gave up on were waited for so already: now only while
                # replies keep coming (the controller answers in turn, so a burst of
                # late replies may come).
                now = ms()
                waited = diff(now, start)
                if waited > timeout_ms + _LATE_MS:
                    break
                if got is None:
                    if not waiting[kind] and (
                        not given or waited > gap and diff(now, waiting[_HEARD]) > gap
                    ):
                        break
                    yield
            # What has not come by now is given up on (and listened for no longer
            # _FORGET_MS after the last such request). Yet it may come, later still: the
            # next queries wait for it as above, and while any is given up on take no
            # reply for their answer that came before their request could have been
            # answered (see _apply).
            if waiting[kind]:
                waiting[kind + 6] = waiting[kind + 4]  # when the last of them left the wire
                waiting[kind + 2] += waiting[kind]
                waiting[kind] = 0
            if kind:
                self.request_positions(ids)  # checks the ids
            else:
                self.request_battery()
            waiting[kind + 8] = 0  # (another task's request must not clear it: not in _went)
            read = waiting[_READ]  # what a timeout says: what came meanwhile
            noise = self.noise
            # Its reply is due within timeout_ms of the request leaving the wire. One whose
            # first bytes came by then is let come whole (for _LATE_MS at most).
            deadline = time.ticks_add(ms(), self.wire_ms() + timeout_ms)
            cmd = CMD_GET_BATTERY_VOLTAGE + 6 * kind  # or CMD_MULT_SERVO_POS_READ (21)
            late = 0  # frames decoded since the deadline: a few more, then give up
            ok = True  # answered (None: and no lingering; False: not in time)
            while True:
                over = diff(ms(), deadline)
                got = self._next_frame()
                if not waiting[kind]:
                    break  # the reply: it matched the request
                _hold(self, got)
                r = self._r + 3  # the command of a frame on its way, if any: a reply's start?
                if over >= 0 and (
                    got is None
                    and (over >= _LATE_MS or r >= self._w or self._rx[r] != cmd)
                    or late > _QUEUE
                ):
                    if waiting[kind + 8]:
                        if waiting[kind + 10]:
                            # A reply that fits came too soon and was taken for a late one,
                            # and none came after it, from a peer not known to be as slow as
                            # the wire: it was this one (and the late ones were lost, as the
                            # controller answers in turn). It is no event: taken back from
                            # poll()'s, if it is the last held. If they were not lost after
                            # all, they come behind: the queries of the next second linger.
                            waiting[kind] = waiting[kind + 2] = 0
                            waiting[kind + 6] = waiting[kind + 4]
                            waiting[kind + 10] = 1
                            self.early += 1
                            got = self._queued - 1
                            if got >= 0 and self._asked[_HELD + got] == cmd:
                                self._queued = got
                            ok = None
                            break
                        # From a peer taken for one as slow as the wire: one reply showed it,
                        # which a program busy elsewhere may have read late. Not known now.
                        waiting[kind + 10] = 2
                    if not again:
                        read = (waiting[_READ] - read) & _TICKS
                        raise OSError(
                            errno.ETIMEDOUT,
                            "no reply: %d bytes came, %d of them noise"
                            % (read, self.noise - noise)
                            if read
                            else "no reply",
                        )
                    ok = False
                    break
                if got is None:
                    yield
                elif over >= 0:
                    late += 1
            # Linger while replies keep coming (until the line has been quiet for `quiet` ms,
            # or _GAP_MS at most; what comes is an event, the state holds the last): with
            # a peer faster than the wire, whose timing cannot tell a late reply from the
            # answer, one right behind this one would be this query's own, and this one an
            # earlier request's; with some given up on, a burst of late ones may be coming
            # (the controller answers in turn, both kinds) and this one its first, which the
            # next query may not listen for (two bytes' time tells).
            answered = ms()
            quiet = ok and _LINGER_MS + lag  # 0: no lingering
            recent = (answered - waiting[kind + 6]) & _TICKS <= _FORGET_MS
            if quiet and (waiting[kind + 10] != 1 or not recent):
                quiet = (recent or waiting[2] or waiting[3]) and _BURST_MS + lag
            while quiet:
                got = self._next_frame()
                _hold(self, got)
                now = ms()
                if (
                    got is None
                    and diff(now, waiting[_HEARD]) >= quiet
                    or diff(now, answered) > gap
                ):
                    break
                if got is None:
                    yield
            if not again:
                return
            yield ok is not False

    # Frames from the controller.

    def poll(self):
        """Return the command byte of the oldest frame not returned yet, after
        applying it to the state, or None. Never blocks; one frame per call."""
        if not self._queued and self._r == self._w and not self._any():
            return None  # the usual case in a control loop: one uart.any()
        return self._next_frame(True)

    def _next_frame(self, held=False):
        # Find the next whole frame in rx[_r:_w] (or with held, one a query
        # held back first), reading what the UART holds as needed; apply it to
        # the state and return its command. None once the UART holds nothing
        # more and no whole frame is in rx. _r and _w are stored before every
        # call to the UART, so an exception from it loses no byte read.
        waiting = self._waiting
        if waiting[_BUSY]:
            return None  # a callback polled while we decode: the first call goes on
        waiting[_BUSY] = 1
        try:
            if held and self._queued:  # frames a query held back come first
                queue = self._asked
                cmd = queue[_HELD]
                self._queued -= 1
                for i in range(_HELD, _HELD + self._queued):  # short, and seldom used: shift
                    queue[i] = queue[i + 1]
                return cmd
            rx = self._rx
            budget = _BUDGET
            whole = -1  # where a frame was let stand whole after a pause (below)
            while True:
                r = self._r
                w = self._w
                # Only the frames the controller sends, with their lengths, are
                # frames (_size). Anything else is noise: drop a byte and look
                # again, so that noise cannot swallow the good frames behind it.
                # Bytes decide first: a frame inside which another starts was cut
                # short, and its start was noise (_size looks).
                while r < w:
                    size = _size(self, r, w, r != whole)
                    if size > 0 and r + size <= w:
                        self._r = r + size
                        cmd = rx[r + 3]
                        self._apply(cmd, r)
                        return cmd
                    if size:
                        break  # a frame's start: the rest, or what tells, is on its way
                    r += 1
                    self.noise += 1
                self._r = r
                # No whole frame here: read more, if the UART holds any.
                n = self._any() if budget > 0 else 0
                if n:
                    if r == w:  # all decoded: start again at the front
                        self._r = self._w = r = w = 0
                    elif w > _RX_SIZE - _CHUNK:  # slide the partial frame down
                        for i in range(w - r):
                            rx[i] = rx[r + i]
                        self._w = w = w - r
                        self._r = 0
                        whole -= r
                    chunk = self._chunk
                    n = self._uart.readinto(chunk, n if n < _CHUNK else _CHUNK) or 0
                    for i in range(n):
                        rx[w + i] = chunk[i]
                    if not n:
                        return None  # any() promised more than readinto() gave
                    self._w = w + n
                    budget -= n
                    waiting[_HEARD] = time.ticks_ms()
                    waiting[_READ] = (waiting[_READ] + n) & _TICKS
                elif r < w:
                    # A frame's start, and nothing more has come. Once the line
                    # has been quiet for longer than its missing bytes take (a
                    # UART's FIFO may hold them back), the link's latency and
                    # _GAP_MS more, the frame was cut short: its start was noise.
                    # (A whole frame whose last bytes might start another, with
                    # nothing behind them, is taken as it is.) On a link at any
                    # pace no pause tells: the bytes behind it will.
                    link = waiting[_LINK]
                    have = w - r
                    missing = rx[r + 2] + 2 - have if have > 2 else _FRAME_MAX
                    quiet = time.ticks_diff(time.ticks_ms(), waiting[_HEARD])
                    if link < 0 or quiet < _GAP_MS + link + missing * 10000 // self._baud:
                        return None
                    if budget > 0 and self._any():
                        continue  # it came while this was away (a GC, a callback): read it
                    if missing > 0:
                        self._r = r + 1
                        self.noise += 1
                    whole = r
                else:
                    return None
        finally:
            waiting[_BUSY] = 0

    def _apply(self, cmd, f):
        # Apply the frame at rx[f] to the state. Parameter k is at rx[f + 3 + k].
        rx = self._rx
        if cmd == CMD_ACTION_GROUP_RUN or cmd == CMD_ACTION_GROUP_COMPLETE:
            self.running = cmd == CMD_ACTION_GROUP_RUN
            self.group = rx[f + 4]
            self.times = rx[f + 5] | rx[f + 6] << 8
        elif cmd == CMD_ACTION_GROUP_STOP:
            self.running = False
        else:  # a reply: the battery, or positions
            waiting = self._waiting
            kind = cmd == CMD_MULT_SERVO_POS_READ  # as in _waiting
            # It can answer the last request of its kind only if it came once that
            # request had left the wire and its own bytes had had time to follow. It
            # came before the read that brought it (_HEARD), and before the bytes
            # read behind it, each a byte's time at least (less 10 %: a fast clock).
            baud = self._baud
            came = waiting[_HEARD] - (self._w - self._r) * 9000 // baud
            came -= waiting[kind + 4] + (rx[f + 2] + 2) * 10000 // baud  # its earliest
            early = came & _TICKS >= _HALF
            fits = True
            if kind:  # and only if they have its ids, in order
                asked = self._asked
                fits = asked[0] == rx[f + 4]
                k = 1
                for i in range(f + 5, f + 5 + 3 * rx[f + 4], 3):
                    # Signed 16-bit, as a servo near 0 may say -3; FFFF (-1) is what
                    # a servo that does not answer (unpowered, missing) reads as: None.
                    position = ((rx[i + 1] | rx[i + 2] << 8) ^ 0x8000) - 0x8000
                    self.positions[rx[i]] = None if position == -1 else position
                    fits = fits and asked[k] == rx[i]
                    k += 1
            else:
                self.battery = rx[f + 4] | rx[f + 5] << 8
            # It answers the oldest request of its kind in flight if it fits it and came in
            # time for it, or sooner with none given up on: then nothing else can be its
            # answer, and the peer is faster than baudrate says (counted in early; its pace
            # kept, see ask()). If it does not answer that, it answers an older one in
            # flight, if there is one, or else one a query gave up on (one that fits may
            # still be the query's: ask()).
            if waiting[kind] and (fits and not (early and waiting[kind + 2]) or waiting[kind] > 1):
                if waiting[kind] == 1:  # the last request's answer: the peer's pace
                    waiting[kind + 10] = early
                    self.early += early
                waiting[kind] -= 1
            elif waiting[kind + 2]:
                waiting[kind + 2] -= 1
                waiting[kind + 8] = waiting[kind] and fits
