# busservo: MicroPython driver for the serial Bus Servo Controller
# (LOBOT/Hiwonder-style boards, frames that start 0x55 0x55, 9600 baud).
#
# Every frame on the wire, in both directions, is
#
#     0x55 0x55  Length  Cmd  Prm 1 ... Prm N        with Length = N + 2
#
# and 16-bit values travel low byte first. Commands are encoded into buffers
# made in __init__; frames from the controller are read into another and
# decoded where they lie, so no call allocates.
import errno
import time
from micropython import const

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
_RX_SIZE = const(288)  # a whole frame, and room to read behind it
_QUEUE = const(32)  # frames a blocking query may hold back for poll()
_TIMEOUT_MS = const(100)  # battery: 10 bytes at 9600 baud take about 10 ms
_TIMEOUT_PER_ID_MS = const(10)  # 4 more bytes on the wire and one servo to ask
_TICKS_HALF = const(0x1FFFFFFF)  # the longest span time.ticks_diff() can tell

# Builtins are slow to look up; module globals are quick. The hot paths check
# their arguments' types with these. (They store 16-bit values' low bytes with
# no mask: a MicroPython bytearray keeps the low 8 bits of what it is given.)
_type = type
_int = int


def _check(name, value, low, high):
    # Refuse what the wire cannot carry, naming the argument and its range.
    if _type(value) is not _int or not low <= value <= high:
        error = TypeError if _type(value) is not _int else ValueError
        raise error("%s must be an int in %d..%d, got %r" % (name, low, high, value))


def _count(name, items, high):
    # How many items a sequence argument holds, refused unless 1..high.
    try:
        n = len(items)
    except TypeError:
        n = -1  # not a sequence at all
    if not 1 <= n <= high:
        error = TypeError if n < 0 else ValueError
        raise error("%s must be a sequence of 1..%d items" % (name, high))
    return n


class BusServo:
    def __init__(self, uart):
        self._uart = uart
        self._write = uart.write  # one lookup, not two, per command
        self._tx = bytearray(_FRAME_MAX)
        # move() is the call a control loop makes most: it has a frame of its
        # own, with the header, Length, command and count already in place.
        self._move = bytearray((_HEADER, _HEADER, 8, CMD_SERVO_MOVE, 1, 0, 0, 0, 0, 0))
        self._rx = bytearray(_RX_SIZE)
        self._r = self._w = 0  # rx[_r:_w]: read, not decoded yet
        self._f = 0  # where in rx the frame decoded last starts
        self._queue = bytearray(_QUEUE)  # commands of frames held back by queries
        self._queued = 0
        self.lost = 0  # frames not held because the queue was full
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
        frame = self._move
        frame[5] = time_ms
        frame[6] = time_ms >> 8
        frame[7] = servo_id
        frame[8] = position
        frame[9] = position >> 8
        self._write(frame)

    def move_many(self, servos, time_ms):
        """CMD_SERVO_MOVE: move 1..83 servos, given as (id, position) pairs or a
        dict {id: position}, together within time_ms."""
        if _type(servos) is dict:
            servos = servos.items()
        n = _count("servos", servos, 83)
        _check("time_ms", time_ms, 0, 0xFFFF)
        tx = self._tx
        i = 7
        for pair in servos:
            try:
                servo_id, position = pair
            except (TypeError, ValueError):
                raise TypeError("servos must hold (servo_id, position) pairs")
            if (
                _type(servo_id) is not _int
                or _type(position) is not _int
                or servo_id >> 8
                or position >> 16
            ):
                _check("servo_id in servos", servo_id, 0, 0xFF)
                _check("position in servos", position, 0, 0xFFFF)
            tx[i] = servo_id
            tx[i + 1] = position
            tx[i + 2] = position >> 8
            i += 3
        tx[4] = n
        tx[5] = time_ms
        tx[6] = time_ms >> 8
        self._send(CMD_SERVO_MOVE, 3 * n + 3)

    def run_group(self, group, times=1):
        """CMD_ACTION_GROUP_RUN: run action group `group` `times` times; 0 = forever."""
        self._group_command(CMD_ACTION_GROUP_RUN, group, "times", times)

    def stop_group(self):
        """CMD_ACTION_GROUP_STOP: stop the running action group, if any."""
        self._send(CMD_ACTION_GROUP_STOP, 0)

    def set_group_speed(self, group, percent):
        """CMD_ACTION_GROUP_SPEED: run `group` (ALL_GROUPS for all) at percent %.
        The controller forgets this at power-off."""
        self._group_command(CMD_ACTION_GROUP_SPEED, group, "percent", percent)

    def unload(self, ids):
        """CMD_MULT_SERVO_UNLOAD: let 1..252 servos go limp."""
        self._ids_command(CMD_MULT_SERVO_UNLOAD, ids, 252)

    def request_battery(self):
        """CMD_GET_BATTERY_VOLTAGE: ask for the voltage; the reply comes through poll()."""
        self._send(CMD_GET_BATTERY_VOLTAGE, 0)

    def request_positions(self, ids):
        """CMD_MULT_SERVO_POS_READ: ask for 1..84 positions (the reply must fit
        in a Length byte); the reply comes through poll()."""
        self._ids_command(CMD_MULT_SERVO_POS_READ, ids, 84)

    def _group_command(self, cmd, group, name, value):
        _check("group", group, 0, 0xFF)
        _check(name, value, 0, 0xFFFF)
        tx = self._tx
        tx[4] = group
        tx[5] = value
        tx[6] = value >> 8
        self._send(cmd, 3)

    def _ids_command(self, cmd, ids, high):
        n = _count("ids", ids, high)
        tx = self._tx
        i = 5
        for servo_id in ids:
            if _type(servo_id) is not _int or servo_id >> 8:
                _check("servo_id in ids", servo_id, 0, 0xFF)
            tx[i] = servo_id
            i += 1
        tx[4] = n
        self._send(cmd, n + 1)

    def _send(self, cmd, nparams):
        tx = self._tx
        tx[0] = tx[1] = _HEADER  # reads may have used tx (see _next_frame)
        tx[2] = nparams + 2
        tx[3] = cmd
        self._write(tx, nparams + 4)  # the first n bytes, without a slice

    # Blocking queries. They return as soon as the reply is complete.

    def read_battery(self, timeout_ms=_TIMEOUT_MS):
        """Battery voltage in mV. Raises OSError(ETIMEDOUT) if no reply comes."""
        self._query(CMD_GET_BATTERY_VOLTAGE, None, timeout_ms)
        return self.battery

    def read_positions(self, ids, timeout_ms=None):
        """{servo_id: position} for 1..84 servos. Raises OSError(ETIMEDOUT) if no
        reply comes; the default timeout is 100 ms plus 10 ms per servo."""
        if timeout_ms is None:
            timeout_ms = _TIMEOUT_MS + _TIMEOUT_PER_ID_MS * _count("ids", ids, 84)
        self._query(CMD_MULT_SERVO_POS_READ, ids, timeout_ms)
        rx = self._rx
        got = {}
        for i in range(self._f + 5, self._f + 5 + 3 * rx[self._f + 4], 3):
            got[rx[i]] = rx[i + 1] | rx[i + 2] << 8
        return got

    def _query(self, cmd, ids, timeout_ms):
        _check("timeout_ms", timeout_ms, 0, _TICKS_HALF)
        start = None  # not asked yet: what comes now answers no request of ours
        while True:
            got = self._next_frame()
            if got is None:
                if start is None:  # all that had come is read: ask now
                    if ids is None:
                        self._send(cmd, 0)
                    else:
                        self._ids_command(cmd, ids, 84)
                    start = time.ticks_ms()
                elif time.ticks_diff(time.ticks_ms(), start) >= timeout_ms:
                    raise OSError(errno.ETIMEDOUT)
            elif got == cmd and start is not None:
                return
            elif self._queued < _QUEUE:  # hold it for poll(); its state is applied
                self._queue[self._queued] = got
                self._queued += 1
            else:
                self.lost += 1

    # Frames from the controller.

    def poll(self):
        """Return the command byte of the oldest frame not returned yet, after
        applying it to the state, or None. Never blocks; one frame per call."""
        if self._queued:  # frames a query held back come first
            queue = self._queue
            cmd = queue[0]
            self._queued -= 1
            for i in range(self._queued):  # short, and seldom used: shift it
                queue[i] = queue[i + 1]
            return cmd
        return self._next_frame()

    def _next_frame(self):
        # Find the next whole frame in rx[_r:_w], reading what the UART holds
        # as needed; apply it to the state and return its command. None once
        # the UART holds nothing more and no whole frame is in rx.
        rx = self._rx
        r = self._r
        w = self._w
        while True:
            # No checksum exists, so check what structure there is: the header
            # is the last two 0x55 of a run (no frame has Length 0x55), and a
            # frame the controller sends must have its command's Length. One
            # that fails is not trusted: drop a byte and look again, so it
            # cannot swallow the good frames behind it.
            while w - r >= 4:  # the smallest frame: 55 55 02 07
                if rx[r] != _HEADER or rx[r + 1] != _HEADER or rx[r + 2] == _HEADER:
                    r += 1
                    continue
                length = rx[r + 2]
                cmd = rx[r + 3]
                if cmd == CMD_ACTION_GROUP_RUN or cmd == CMD_ACTION_GROUP_COMPLETE:
                    ok = length == 5
                elif cmd == CMD_ACTION_GROUP_STOP:
                    ok = length == 2
                elif cmd == CMD_GET_BATTERY_VOLTAGE:
                    ok = length == 4
                elif cmd == CMD_MULT_SERVO_POS_READ:
                    if w - r < 5:
                        break
                    ok = length == 3 * rx[r + 4] + 3
                else:  # a command the controller does not send: skip it whole
                    ok = length >= 2
                if not ok:
                    r += 1
                    continue
                if r + length + 2 > w:
                    break  # the rest is still on its way
                self._f = r
                self._r = r + length + 2
                self._w = w
                # Apply it. Parameter k is at rx[r + 3 + k].
                if cmd == CMD_ACTION_GROUP_RUN or cmd == CMD_ACTION_GROUP_COMPLETE:
                    self.running = cmd == CMD_ACTION_GROUP_RUN
                    self.group = rx[r + 4]
                    self.times = rx[r + 5] | rx[r + 6] << 8
                elif cmd == CMD_ACTION_GROUP_STOP:
                    self.running = False
                elif cmd == CMD_GET_BATTERY_VOLTAGE:
                    self.battery = rx[r + 4] | rx[r + 5] << 8
                elif cmd == CMD_MULT_SERVO_POS_READ:
                    positions = self.positions
                    for i in range(r + 5, r + 5 + 3 * rx[r + 4], 3):
                        positions[rx[i]] = rx[i + 1] | rx[i + 2] << 8
                return cmd
            # No whole frame here: read more, if the UART holds any.
            uart = self._uart
            n = uart.any()
            if n:
                if r == w:  # all decoded: read straight into rx
                    r = 0
                    n = w = uart.readinto(rx, n if n < _RX_SIZE else _RX_SIZE) or 0
                else:
                    # readinto() cannot start mid-buffer without a memoryview
                    # slice, which allocates, so these bytes pass through tx,
                    # idle while we read. Slide the partial frame down first if
                    # little room is left behind it (it is 256 bytes at most).
                    if _RX_SIZE - w < 32:
                        for i in range(w - r):
                            rx[i] = rx[r + i]
                        w -= r
                        r = 0
                    room = _RX_SIZE - w
                    tx = self._tx
                    n = uart.readinto(tx, n if n < room else room) or 0
                    for i in range(n):
                        rx[w + i] = tx[i]
                    w += n
            if not n:
                self._r = r
                self._w = w
                return None
