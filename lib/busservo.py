# busservo: MicroPython driver for the serial Bus Servo Controller
# (LOBOT/Hiwonder-style boards, frames that start 0x55 0x55, 9600 baud).
#
# Every frame on the wire, in both directions, is
#
#     0x55 0x55  Length  Cmd  Prm 1 ... Prm N        with Length = N + 2
#
# and 16-bit values travel low byte first. Commands are encoded into one
# buffer made in __init__; frames from the controller are read into another
# and decoded where they lie, so neither direction allocates per call.
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
_RX_SIZE = const(320)  # one whole frame and room to read behind it
_CHUNK = const(63)  # reads that land behind a partial frame pass through here
_QUEUE = const(32)  # frames a blocking query may hold back for poll()
_TIMEOUT_MS = const(100)  # battery: 10 bytes at 9600 baud take about 10 ms
_TIMEOUT_PER_ID_MS = const(10)  # 4 more bytes on the wire and one servo to ask
_TICKS_HALF = const(0x1FFFFFFF)  # longest span time.ticks_diff() can tell


def _int(name, value, top):
    # Refuse what the wire cannot carry, naming the argument and its range.
    if type(value) is not int:
        raise TypeError("%s must be an int in 0..%d, not %s" % (name, top, type(value).__name__))
    if not 0 <= value <= top:
        raise ValueError("%s must be 0..%d, got %d" % (name, top, value))
    return value


def _count(name, items, top):
    try:
        n = len(items)
    except TypeError:
        raise TypeError("%s must be a sequence of 1..%d items" % (name, top))
    if not 1 <= n <= top:
        raise ValueError("%s must hold 1..%d items, got %d" % (name, top, n))
    return n


class BusServo:
    def __init__(self, uart):
        self._uart = uart
        self._tx = bytearray(_FRAME_MAX)
        self._tx[0] = self._tx[1] = _HEADER
        self._rx = bytearray(_RX_SIZE)
        self._r = 0  # rx[_r:_w] holds bytes read but not yet decoded
        self._w = 0
        self._f = 0  # where the frame decoded last starts in rx
        self._chunk = bytearray(_CHUNK)
        self._queue = bytearray(_QUEUE)  # command bytes held back by queries
        self._head = 0
        self._queued = 0
        self.lost = 0  # frames dropped because the queue was full
        self.running = False
        self.group = None
        self.times = 0
        self.battery = None
        self.positions = {}

    # Commands. Each checks all its arguments before it writes anything.

    def move(self, servo_id, position, time_ms):
        """CMD_SERVO_MOVE: move one servo to position within time_ms."""
        _int("servo_id", servo_id, 0xFF)
        _int("position", position, 0xFFFF)
        _int("time_ms", time_ms, 0xFFFF)
        tx = self._tx
        tx[4] = 1
        tx[5] = time_ms & 0xFF
        tx[6] = time_ms >> 8
        tx[7] = servo_id
        tx[8] = position & 0xFF
        tx[9] = position >> 8
        self._send(CMD_SERVO_MOVE, 6)

    def move_many(self, servos, time_ms):
        """CMD_SERVO_MOVE: move 1..83 servos, given as (id, position) pairs or a
        dict {id: position}, together within time_ms."""
        if type(servos) is dict:
            servos = servos.items()
        n = _count("servos", servos, 83)
        _int("time_ms", time_ms, 0xFFFF)
        tx = self._tx
        i = 7
        for pair in servos:
            try:
                servo_id, position = pair
            except (TypeError, ValueError):
                raise TypeError("servos must hold (servo_id, position) pairs")
            tx[i] = _int("servo_id in servos", servo_id, 0xFF)
            tx[i + 1] = _int("position in servos", position, 0xFFFF) & 0xFF
            tx[i + 2] = position >> 8
            i += 3
        tx[4] = n
        tx[5] = time_ms & 0xFF
        tx[6] = time_ms >> 8
        self._send(CMD_SERVO_MOVE, 3 * n + 3)

    def run_group(self, group, times=1):
        """CMD_ACTION_GROUP_RUN: run action group `group` `times` times; 0 = forever."""
        self._group_command(CMD_ACTION_GROUP_RUN, "group", group, "times", times)

    def stop_group(self):
        """CMD_ACTION_GROUP_STOP: stop the running action group, if any."""
        self._send(CMD_ACTION_GROUP_STOP, 0)

    def set_group_speed(self, group, percent):
        """CMD_ACTION_GROUP_SPEED: run `group` (ALL_GROUPS for all) at percent %.
        The controller forgets this at power-off."""
        self._group_command(CMD_ACTION_GROUP_SPEED, "group", group, "percent", percent)

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

    def _group_command(self, cmd, name, group, name16, value16):
        _int(name, group, 0xFF)
        _int(name16, value16, 0xFFFF)
        tx = self._tx
        tx[4] = group
        tx[5] = value16 & 0xFF
        tx[6] = value16 >> 8
        self._send(cmd, 3)

    def _ids_command(self, cmd, ids, top):
        n = _count("ids", ids, top)
        tx = self._tx
        i = 5
        for servo_id in ids:
            tx[i] = _int("servo_id in ids", servo_id, 0xFF)
            i += 1
        tx[4] = n
        self._send(cmd, n + 1)

    def _send(self, cmd, nparams):
        tx = self._tx
        tx[2] = nparams + 2
        tx[3] = cmd
        self._uart.write(tx, nparams + 4)  # the first n bytes, without a slice

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
        f = self._f
        return {rx[i]: rx[i + 1] | rx[i + 2] << 8 for i in range(f + 5, f + 5 + 3 * rx[f + 4], 3)}

    def _query(self, cmd, ids, timeout_ms):
        _int("timeout_ms", timeout_ms, _TICKS_HALF)
        # What already arrived answers no request of ours: hold it for poll().
        while True:
            got = self._next_frame()
            if got is None:
                break
            self._hold(got)
        if ids is None:
            self._send(cmd, 0)
        else:
            self._ids_command(cmd, ids, 84)
        start = time.ticks_ms()
        while True:
            got = self._next_frame()
            if got == cmd:
                return
            if got is not None:
                self._hold(got)
            elif time.ticks_diff(time.ticks_ms(), start) >= timeout_ms:
                raise OSError(errno.ETIMEDOUT)

    def _hold(self, cmd):
        # Keep a frame's command for poll(); its state is applied already.
        if self._queued == _QUEUE:
            self._head = (self._head + 1) % _QUEUE  # full: the oldest goes
            self._queued -= 1
            self.lost += 1
        self._queue[(self._head + self._queued) % _QUEUE] = cmd
        self._queued += 1

    # Frames from the controller.

    def poll(self):
        """Return the command byte of the oldest frame not returned yet, after
        applying it to the state, or None. Never blocks; one frame per call."""
        if self._queued:
            cmd = self._queue[self._head]
            self._head = (self._head + 1) % _QUEUE
            self._queued -= 1
            return cmd
        return self._next_frame()

    def _next_frame(self):
        # Decode the next frame, reading the UART until it holds no more.
        while True:
            cmd = self._decode()
            if cmd is not None or not self._fill():
                return cmd

    def _fill(self):
        # Move what the UART holds into rx behind the undecoded bytes. Returns
        # the number of bytes read; 0 when the UART held none.
        uart = self._uart
        n = uart.any()
        if not n:
            return 0
        rx = self._rx
        r = self._r
        w = self._w
        if r == w:  # all decoded: read straight into rx
            n = uart.readinto(rx, min(n, _RX_SIZE)) or 0
            self._r = 0
            self._w = n
            return n
        # readinto() cannot start mid-buffer without a memoryview slice, which
        # allocates, so these bytes pass through the chunk buffer.
        if w + _CHUNK > _RX_SIZE:  # make room: slide the partial frame down
            for i in range(w - r):
                rx[i] = rx[r + i]
            w -= r
            r = self._r = 0
        chunk = self._chunk
        n = uart.readinto(chunk, min(n, _CHUNK)) or 0
        for i in range(n):
            rx[w + i] = chunk[i]
        self._w = w + n
        return n

    def _decode(self):
        # Find the next whole frame in rx[_r:_w], apply it, return its command.
        # No checksum exists, so check what structure there is: the header is
        # the last two 0x55 of a run (no frame has Length 0x55), and a known
        # command must have its Length. A frame that fails is not trusted: drop
        # one byte and look again, so it cannot swallow the good frames behind.
        rx = self._rx
        r = self._r
        w = self._w
        while w - r >= 4:
            if rx[r] != _HEADER or rx[r + 1] != _HEADER or rx[r + 2] == _HEADER:
                r += 1
                continue
            length = rx[r + 2]
            cmd = rx[r + 3]
            if cmd == CMD_MULT_SERVO_POS_READ:
                if w - r < 5:
                    break
                ok = length == 3 * rx[r + 4] + 3
            elif cmd == CMD_ACTION_GROUP_RUN or cmd == CMD_ACTION_GROUP_COMPLETE:
                ok = length == 5
            elif cmd == CMD_ACTION_GROUP_STOP:
                ok = length == 2
            elif cmd == CMD_GET_BATTERY_VOLTAGE:
                ok = length == 4
            else:  # not one the controller sends: skip it whole
                ok = length >= 2
            if not ok:
                r += 1
                continue
            if r + length + 2 > w:
                break  # the rest is still on its way
            self._f = r
            self._r = r + length + 2
            self._apply(r, cmd)
            return cmd
        self._r = r
        return None

    def _apply(self, f, cmd):
        # Parameter k of the frame at rx[f] is rx[f + 3 + k].
        rx = self._rx
        if cmd == CMD_ACTION_GROUP_RUN or cmd == CMD_ACTION_GROUP_COMPLETE:
            self.running = cmd == CMD_ACTION_GROUP_RUN
            self.group = rx[f + 4]
            self.times = rx[f + 5] | rx[f + 6] << 8
        elif cmd == CMD_ACTION_GROUP_STOP:
            self.running = False
        elif cmd == CMD_GET_BATTERY_VOLTAGE:
            self.battery = rx[f + 4] | rx[f + 5] << 8
        elif cmd == CMD_MULT_SERVO_POS_READ:
            positions = self.positions
            for i in range(f + 5, f + 5 + 3 * rx[f + 4], 3):
                positions[rx[i]] = rx[i + 1] | rx[i + 2] << 8
