# busservo_sim: a simulated Bus Servo Controller, for trying busservo with no
# controller wired (at a board's REPL, or on the unix port).
#
#   import busservo, busservo_sim
#   sim = busservo_sim.SimController()
#   bus = busservo.BusServo(sim)    # sim has machine.UART's any/read/readinto/write
#
# It decodes what the driver writes and answers as the protocol says:
# - servos move linearly from where they are to their target over time_ms, so a
#   position read mid-move gives the value in between (servos start at 500);
# - a servo turns 0..1000 only: a target beyond 1000 stops at 1000, as a real
#   servo stops at its limit, and counts one `clamped` (`pwm`, a set of ids,
#   makes those PWM servos of an LSC board instead: 0..2500 us);
# - action groups (`groups`, {group: ms per run}) run `times` times or forever,
#   sending RUN as they start, COMPLETE as they end, STOP when stopped (by a STOP
#   command, or by a RUN of another group); a run longer than the ticks can span
#   (65535 times at 1 %: months) ends on time too, if anything calls the sim at
#   least every 3 days;
# - ACTION_GROUP_SPEED scales a group's durations (ALL_GROUPS: every group);
#   power_cycle() forgets it, as the controller does at power-off;
# - unload lets servos go limp where they are (`limp`) until they are moved, and
#   turn(servo_id, position) is a person's hand: it turns a limp servo there at once,
#   as a hand puts it (True); a servo under power holds where it is (False);
# - a servo in `missing` (ids) does not answer: a position read gives 65535 for it,
#   as a controller does for a servo unpowered or not on the bus;
# - the battery reads `battery` mV;
# - a malformed frame counts one `beeps` (the controller's "beep beep");
# - it is at the far end of a 9600-baud line (`baudrate`; 10 bits a byte): a frame
#   written to it is in once its last byte would have arrived, and what it says
#   comes out a byte every 1.04 ms behind what it said before. So a reply comes
#   no sooner than on a real wire (baudrate=None: no line, every byte at once, as
#   a peer faster than the wire; or for a test world that models the line itself).
# Time comes from time.ticks_ms(), or from the ticks_ms function given, which a
# test can step. Setting `silent` makes it answer nothing at all, as a controller
# with its TX unplugged; so does the frame 55 55 03 F0 01 (F0 00 undoes it),
# which a real controller would beep at.
import time

try:
    import micropython  # noqa: F401 (on a board; CPython has none)
except ImportError:  # CPython, on a computer: busservo_cpython gives what it lacks
    from busservo_cpython import time

from busservo import (
    ALL_GROUPS,
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_RUN,
    CMD_ACTION_GROUP_SPEED,
    CMD_ACTION_GROUP_STOP,
    CMD_GET_BATTERY_VOLTAGE,
    CMD_MULT_SERVO_POS_READ,
    CMD_MULT_SERVO_UNLOAD,
    CMD_SERVO_MOVE,
)

SIM_SILENT = 0xF0  # the simulator's own command: Prm 1 = 1 silent, 0 talking
GROUPS = {0: 1000, 1: 500, 2: 2000, 8: 1500}  # default action groups, ms per run
CENTER = 500  # where a servo starts
LIMIT = 1000  # the far end of a servo's range, 0..1000
PWM_LIMIT = 2500  # a PWM servo's, in us
# ms a run's end moves at a time: ticks_add() refuses half the ticks' period
# (2**29 ms on most boards, 2**28 where small ints have 30 bits).
_SPAN = 1 << 27


class SimController:
    def __init__(self, groups=None, battery=7500, ticks_ms=time.ticks_ms, baudrate=9600):
        self.groups = dict(GROUPS if groups is None else groups)
        self.battery = battery
        self.silent = False
        self.beeps = 0
        self.clamped = 0
        self.pwm = set()
        self.limp = set()
        self.missing = set()
        self._ticks_ms = ticks_ms
        self._baud = baudrate  # None: no line
        self._servos = {}  # id: (from, to, start ticks, time_ms)
        self._in = bytearray()  # written by the driver, not yet decoded
        self._out = bytearray()  # for the driver to read
        self.power_cycle()

    def power_cycle(self):
        """Power off and on: groups stop (silently) and speeds are forgotten."""
        self._speed = {}  # group: percent
        self._running = None  # (group, times, end ticks or None for forever, ms after end)
        self._in = bytearray()
        self._out = bytearray()
        # The line: when (ticks) what was written is in, and when what it says
        # has gone, each with the fraction of a ms more (in 1/baudrate ms: a byte is
        # 10000); [start ticks, bytes, bytes read, fraction] of each frame said, not
        # yet read.
        self._in_at = self._out_at = self._frame_in = self._ticks_ms()
        self._in_frac = self._out_frac = self._frame_frac = 0
        self._said = []

    def position(self, servo_id):
        """Where servo_id is now."""
        start, target, t0, time_ms = self._servos.get(servo_id, (CENTER, CENTER, 0, 0))
        done = time.ticks_diff(self._ticks_ms(), t0)
        if not 0 <= done < time_ms:  # done, or a servo never moved (t0 = 0)
            return target
        return start + (target - start) * done // time_ms

    def turn(self, servo_id, position):
        """Turn servo_id by hand to position: a limp servo is there at once (True); one
        under power holds where it is, and this returns False."""
        end = PWM_LIMIT if servo_id in self.pwm else LIMIT
        if type(position) is not int or not 0 <= position <= end:
            raise ValueError("position must be an int in 0..%d, got %r" % (end, position))
        if servo_id not in self.limp:
            return False  # its motor holds it against the hand
        self._servos[servo_id] = (position, position, self._ticks_ms(), 0)
        return True

    def speed(self, group):
        """The group's speed in percent."""
        return self._speed.get(group, 100)

    @property
    def running(self):
        """The group running now, or None."""
        self._tick()
        return self._running and self._running[0]

    # machine.UART's methods, as the driver sees them.

    def any(self):
        self._tick()
        if not self._baud:
            return len(self._out)
        n = 0  # the bytes that have come down the line by now
        now = self._ticks_ms()
        for start, size, read, frac in self._said:
            come = time.ticks_diff(now, start)
            come = size if come > 2 * size + 2 else min(size, (come * self._baud - frac) // 10000)
            if come > 0:
                n += come - read
            if come < size:
                break  # the rest are behind it
        return n

    def readinto(self, buf, nbytes=None):
        n = min(self.any(), len(buf) if nbytes is None else min(nbytes, len(buf)))
        if not n:
            return None
        for i in range(n):
            buf[i] = self._out[i]
        self._take(n)
        return n

    def read(self, nbytes=None):
        n = self.any() if nbytes is None else min(self.any(), nbytes)
        if not n:
            return None
        data = bytes(self._out[:n])
        self._take(n)
        return data

    def _take(self, n):
        self._out = self._out[n:]
        said = self._said
        while n and said:
            frame = said[0]
            k = min(n, frame[1] - frame[2])
            frame[2] += k
            n -= k
            if frame[2] == frame[1]:
                said.pop(0)

    def write(self, buf, off=None, nbytes=None):
        # The stream protocol's forms: write(buf), write(buf, n), write(buf, off, n).
        if nbytes is None:
            off, nbytes = 0, len(buf) if off is None else off
        off = min(off, len(buf))
        n = min(nbytes, len(buf) - off)
        self._in += buf[off : off + n]
        if self._baud:  # its bytes are in when the line has brought them
            now = self._ticks_ms()
            if time.ticks_diff(self._in_at, now) < 0:  # the line was idle
                self._in_at, self._in_frac = now, 0
            self._in_at, self._in_frac = self._line(self._in_at, self._in_frac, n)
        self._tick()
        self._decode()
        return n

    # The controller.

    def _line(self, at, frac, n):
        # When n bytes sent back to back from at (ticks, and frac 1/baudrate ms more) have
        # come down the line: (ticks, fraction). The fractions are carried, so that the line
        # runs at the baud rate exactly however its bytes are written (a byte a write, as
        # serve() writes them).
        units = frac + n * 10000
        return time.ticks_add(at, units // self._baud), units % self._baud

    def _send(self, cmd, *params, at=None):
        # Say a frame: at once, or on the line from when `at` (ticks: by default,
        # when the frame it answers was in) and the line is free.
        if self.silent:
            return
        frame = bytes((0x55, 0x55, len(params) + 2, cmd) + params)
        self._out += frame
        if self._baud:
            start, frac = (self._frame_in, self._frame_frac) if at is None else (at, 0)
            if time.ticks_diff(self._out_at, start) >= 0:  # behind what it said before
                start, frac = self._out_at, self._out_frac
            self._said.append([start, len(frame), 0, frac])
            self._out_at, self._out_frac = self._line(start, frac, len(frame))

    def _tick(self):
        # An action group that has run its course completes. A long run's end
        # moves _SPAN at a time, so no ticks span is more than ticks_add() takes.
        run = self._running
        while run and run[2] is not None and time.ticks_diff(self._ticks_ms(), run[2]) >= 0:
            group, times, end, rest = run
            if not rest:
                self._running = None
                self._send(CMD_ACTION_GROUP_COMPLETE, group, times & 0xFF, times >> 8, at=end)
                return
            step = min(rest, _SPAN)
            run = self._running = (group, times, time.ticks_add(end, step), rest - step)

    def _decode(self):
        d = self._in
        i = 0
        while len(d) - i >= 4:
            if d[i] != 0x55 or d[i + 1] != 0x55 or d[i + 2] == 0x55:
                i += 1
                continue
            cmd = d[i + 3]
            if cmd in (CMD_SERVO_MOVE, CMD_MULT_SERVO_UNLOAD, CMD_MULT_SERVO_POS_READ):
                if len(d) - i < 5:
                    break
                per = 3 if cmd == CMD_SERVO_MOVE else 1
                length = per * d[i + 4] + per + 2
            else:
                length = _LENGTHS.get(cmd)
            if length != d[i + 2]:  # malformed or unknown: beep, look again
                self.beeps += 1
                i += 1
                continue
            if len(d) - i < length + 2:
                break
            i += length + 2
            self._in = d[i:]  # taken before it is done: a frame that raises is gone
            if self._baud:  # it was in before the bytes behind it came
                units = self._in_frac - (len(d) - i) * 10000
                self._frame_in = time.ticks_add(self._in_at, units // self._baud)
                self._frame_frac = units % self._baud
            self._do(cmd, bytes(d[i - length + 2 : i]))  # its parameters
        self._in = d[i:]

    def _do(self, cmd, p):
        now = self._ticks_ms()
        if cmd == CMD_SERVO_MOVE:
            time_ms = p[1] | p[2] << 8
            for k in range(3, 3 * p[0] + 3, 3):
                servo_id, target = p[k], p[k + 1] | p[k + 2] << 8
                end = PWM_LIMIT if servo_id in self.pwm else LIMIT
                if target > end:  # the wire carries up to 65535; the servo stops at its end
                    target = end
                    self.clamped += 1
                self._servos[servo_id] = (self.position(servo_id), target, now, time_ms)
                self.limp.discard(servo_id)
        elif cmd == CMD_ACTION_GROUP_RUN:
            group, times = p[0], p[1] | p[2] << 8
            if group not in self.groups:
                self.beeps += 1
                return
            if self.running is not None:
                self._running = None
                self._send(CMD_ACTION_GROUP_STOP)
            end = rest = None  # forever
            if times:
                rest = times * (self.groups[group] * 100 // self.speed(group))
                step = min(rest, _SPAN)
                end, rest = time.ticks_add(now, step), rest - step
            self._running = (group, times, end, rest)
            self._send(CMD_ACTION_GROUP_RUN, group, p[1], p[2])
        elif cmd == CMD_ACTION_GROUP_STOP:
            if self.running is not None:
                self._running = None
                self._send(CMD_ACTION_GROUP_STOP)
        elif cmd == CMD_ACTION_GROUP_SPEED:
            percent = p[1] | p[2] << 8
            if not percent:
                self.beeps += 1
                return
            for group in self.groups if p[0] == ALL_GROUPS else (p[0],):
                self._speed[group] = percent
        elif cmd == CMD_GET_BATTERY_VOLTAGE:
            self._send(CMD_GET_BATTERY_VOLTAGE, self.battery & 0xFF, self.battery >> 8)
        elif cmd == CMD_MULT_SERVO_UNLOAD:
            for servo_id in p[1:]:
                here = self.position(servo_id)
                self._servos[servo_id] = (here, here, now, 0)
                self.limp.add(servo_id)
        elif cmd == CMD_MULT_SERVO_POS_READ:
            reply = [p[0]]
            for servo_id in p[1:]:
                here = 0xFFFF if servo_id in self.missing else self.position(servo_id)
                reply += (servo_id, here & 0xFF, here >> 8)
            self._send(CMD_MULT_SERVO_POS_READ, *reply)
        elif cmd == SIM_SILENT:
            self.silent = bool(p[0])


# Length of each fixed-size command the controller takes.
_LENGTHS = {
    CMD_ACTION_GROUP_RUN: 5,
    CMD_ACTION_GROUP_STOP: 2,
    CMD_ACTION_GROUP_SPEED: 5,
    CMD_GET_BATTERY_VOLTAGE: 2,
    SIM_SILENT: 3,
}


def uart():
    """A board file's uart(), for when there is no board: the simulated controller."""
    return SimController()


def serve(stream_in, stream_out):
    """Be the controller on a byte stream: what stream_in brings is written to a
    SimController, what it answers goes to stream_out. Runs until stream_in ends."""
    import select

    sim = SimController()
    poller = select.poll()
    poller.register(stream_in, select.POLLIN)
    buf = bytearray(1)
    while True:
        # One byte per poll, so a blocking stream cannot block; 5 ms at most
        # between looks, so COMPLETE goes out on time.
        for _, event in poller.poll(5):
            if event & (select.POLLHUP | select.POLLERR):
                return
            n = stream_in.readinto(buf, 1)
            if n == 0:
                return  # end of stream
            if n:
                sim.write(buf, 1)
        data = sim.read()
        if data:
            stream_out.write(data)


if __name__ == "__main__":
    import sys

    serve(sys.stdin.buffer, sys.stdout.buffer)
