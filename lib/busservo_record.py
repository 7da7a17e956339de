# busservo_record: continuous recording of a limp arm, and smooth playback of it, on top of
# busservo_motion.
#
#   import busservo_record as br
#   rec = br.Recorder(arm, path="demo.rec")  # the joints go limp: move the arm by hand
#   while ...: rec.step()                    # from the loop (or: await rec)
#   recording = rec.stop()
#   player = recording.play(arm, speed=1.0)  # into the first pose at dps=30, then its pace
#   while not player.done: player.step()     # or: await player, or player.wait()
#   recording.save("demo.jsonl")             # JSON lines, for a computer
#   seq = recording.to_sequence(tolerance=2) # keyframes, for busservo_motion's Player
#
# A read is the driver's own query (BusServo.ask(), a generator made once that asks again after
# each answer, so a read takes no heap), a step at a time, so the loop never waits for the wire;
# a read that times out is counted in missed and skipped. Each sample
# is kept as the servos' integer positions and the ticks_ms it came (floats are heap objects:
# none is made while recording), packed as the difference from the sample before: 2 bytes of
# ms and a byte a joint (8 bytes for 6 joints), or, where a joint moved more than a byte holds,
# a key sample of the whole positions. Degrees are made from them, with the calibration the
# recording keeps, when the recording is read.
#
# The board's flash: a write may stall the board for a sector's erase (an RP2040 cannot take
# interrupts meanwhile: its UART's 32-byte FIFO is all that listens). So samples wait in RAM and
# go to the file a piece (256 bytes) at a time, only between a reply and the next request: then
# nothing is due from the controller, and the erase delays the next read, not a byte of a reply.
#
# Recording while a leader drives a follower (busservo_teleop.Teleop(..., recorder=rec)): the
# Teleop reads the leader, and gives each read to take(), between the reply and its next
# request. The leader is read once a cycle, for both.
import errno
import json
import time

try:
    from micropython import const

    _awaitable = None
except ImportError:  # CPython, on a computer: busservo_cpython gives what it lacks
    from busservo_cpython import awaitable as _awaitable
    from busservo_cpython import const, time

import busservo_motion as bm

MAGIC = b"BSREC1\n"  # the compact file's first bytes; a JSON line of its joints follows
PIECE = const(256)  # bytes written to the file at a time
HALT_MS = 100  # a playback stopped by Ctrl-C on a move's way: the servos go where they are
_KEY = const(0xFFFF)  # a key sample's first 2 bytes: whole positions follow
_DT_MAX = const(0xFFFE)  # ms a sample's 2 bytes of time hold
_END = object()  # what next() gives once a query has ended
_type = type
_int = int


def _names(robot, names):
    # The joints to record or play, in the robot's order (by servo id), each checked.
    if not isinstance(robot, bm.Robot):
        raise TypeError("robot must be a busservo_motion.Robot, got %r" % (robot,))
    if names is None:
        return list(robot.names)
    if _type(names) is str or not isinstance(names, (list, tuple)) or not names:
        raise TypeError("names must be a list of joint names, such as ['base'], got %r" % (names,))
    for name in names:
        if name not in robot.joints:
            raise ValueError(
                "no joint %r in names: the joints are %s" % (name, ", ".join(robot.names))
            )
    return [name for name in robot.names if name in names]


class Recorder:
    def __init__(self, robot, names=None, path=None, limp=True, timeout_ms=None):
        """Record the joints (names, all by default) of robot: they go limp (limp=True) to be
        moved by hand, and each step() drives a read; each reply is a sample. path: a file to
        write the compact form to as it comes ("*.jsonl": JSON lines, written at stop());
        None: kept in RAM."""
        self.names = _names(robot, names)
        if path is not None and _type(path) is not str:
            raise TypeError("path must be a file name (str) or None, got %r" % (path,))
        if timeout_ms is not None and (
            _type(timeout_ms) is not _int or not 0 <= timeout_ms <= 60000
        ):
            raise (ValueError if _type(timeout_ms) is _int else TypeError)(
                "timeout_ms must be None or an int in 0..60000 ms, got %r" % (timeout_ms,)
            )
        self.robot = robot
        self.bus = robot.bus
        self.path = path
        self.timeout_ms = timeout_ms
        joints = [robot.joints[name] for name in self.names]
        self.joints = {name: joint for name, joint in zip(self.names, joints)}
        self._ids = [joint.servo_id for joint in joints]
        n = self._n = len(joints)
        self._last = [0] * n  # the positions of the sample before
        self._got = [0] * n
        self._t = 0  # ticks_ms of the sample before
        self.samples = 0  # samples kept
        self.missed = 0  # reads skipped: timed out, or a servo did not answer
        self.done = False
        self.recording = None
        # Samples wait here for the file: PIECE bytes go at a time, and room for 4 more key
        # samples behind them (reads that time out leave no quiet moment to write in).
        self._key = 6 + 2 * n  # a key sample's bytes
        self._buf = bytearray(PIECE + 4 * self._key)
        self._piece = memoryview(self._buf)[:PIECE]
        self._w = 0  # bytes in _buf
        self._quiet = False  # the last read was answered: nothing is due from the controller
        self._query = None  # the read under way (the driver's ask())
        self._fed = False  # take() gives it the reads: it makes none of its own
        self._file = None
        self._data = bytearray()  # in RAM: no path, or JSON lines (written at stop())
        # CPython keeps about 8 KB of writes in its own buffer (some 40 s of samples), lost
        # if the process is killed: there each piece is flushed to the OS as it is written.
        # A board's flush may cost a flash erase: its pieces go as MicroPython writes them.
        self._flush = None  # the file's flush(), on CPython
        if path is not None and not path.endswith(".jsonl"):
            self._file = open(path, "wb")
            self._file.write(MAGIC)
            self._file.write(_header(self.names, self.joints).encode())
            if _awaitable:
                self._flush = getattr(self._file, "flush", None)
            if self._flush:
                self._flush()
        if limp:
            robot.limp(self.names)

    def step(self):
        """From the control loop: take a reply if one has come, and ask for the next read.
        Never waits for the wire. True if a sample was kept."""
        if self.done or self._fed:
            return False
        if self._quiet:
            if self._w >= PIECE:
                self._write()  # between a reply and the next request: nothing is due
            self._quiet = False  # this step asks again
        query = self._query
        if query is None:  # made once, it asks again at each step after an answer
            query = self._query = self.bus.ask(self._ids, self.timeout_ms, again=True)
        try:
            answered = next(query)
        except OSError:  # the UART failed (a timeout is no error: answered is False)
            self._query = None
            raise
        if answered is None:
            return False  # the reply is not in yet
        if not answered:
            self.missed += 1  # (a late reply may still come: not quiet)
            return False
        self._quiet = True
        return self._sample(time.ticks_ms(), self.bus.positions)

    def take(self, ticks_ms, positions):
        """A read made elsewhere (a busservo_teleop.Teleop's of its leader): positions
        {servo_id: position}, as the bus's positions hold a reply, taken at ticks_ms; None
        for a read that failed, counted in missed. Call it between a reply and the next
        request: a full piece goes to the file then. Once given one, step() reads nothing.
        True if a sample was kept."""
        self._fed = True
        if self.done:
            return False
        if positions is None:
            self.missed += 1
            return False
        if not self._sample(ticks_ms, positions):
            return False
        if self._w >= PIECE:
            self._write()  # between a reply and the next request: nothing is due
        return True

    def _sample(self, now, positions):
        # Keep a read's positions {servo_id: position}, taken at now. True if kept; a servo
        # that did not answer makes no sample, counted in missed.
        ids = self._ids
        got = self._got
        for i in range(self._n):
            p = positions.get(ids[i])
            if p is None:
                self.missed += 1
                return False
            got[i] = p
        self._keep(now)
        return True

    def _keep(self, now):
        # Pack the sample in got, taken at now, behind the ones before.
        last = self._last
        got = self._got
        n = self._n
        dt = time.ticks_diff(now, self._t)
        key = not self.samples or dt > _DT_MAX or dt < 0
        if not key:
            for i in range(n):
                d = got[i] - last[i]
                if d < -128 or d > 127:
                    key = True
                    break
        if self._w + self._key > len(self._buf):
            self._write()  # no quiet moment came: write now rather than lose the sample
        buf = self._buf
        w = self._w
        if key:
            if not self.samples:
                dt = 0
            buf[w] = buf[w + 1] = 0xFF
            buf[w + 2] = dt & 0xFF
            buf[w + 3] = (dt >> 8) & 0xFF
            buf[w + 4] = (dt >> 16) & 0xFF
            buf[w + 5] = (dt >> 24) & 0xFF
            w += 6
            for i in range(n):
                p = got[i]
                buf[w] = p & 0xFF
                buf[w + 1] = (p >> 8) & 0xFF
                last[i] = p
                w += 2
        else:
            buf[w] = dt & 0xFF
            buf[w + 1] = dt >> 8
            w += 2
            for i in range(n):
                buf[w] = (got[i] - last[i]) & 0xFF
                last[i] = got[i]
                w += 1
        self._w = w
        self._t = now
        self.samples += 1

    def _write(self):
        # The first PIECE bytes (or all, if fewer) to the file or RAM; the rest moves down.
        w = self._w
        buf = self._buf
        k = PIECE if w >= PIECE else w
        if k == PIECE:
            piece = self._piece
        else:
            piece = memoryview(buf)[:k]  # the last piece, at stop()
        if self._file is not None:
            self._file.write(piece)
            if self._flush:
                self._flush()
        else:
            self._data.extend(piece)
        for i in range(w - k):
            buf[i] = buf[k + i]
        self._w = w - k

    def stop(self):
        """Stop recording: what waits in RAM goes to the file, which is closed. Return the
        Recording (also self.recording). The joints stay limp."""
        if self.done:
            return self.recording
        self.done = True
        self._query = None
        while self._w:
            self._write()
        data = self._data
        if self._file is not None:
            self._file.close()
            self._file = self._flush = None
            recording = Recording.load(self.path)
        else:
            recording = Recording(self.joints, self.names, bytes(data))
            if self.path is not None:
                recording.save(self.path)
        self._data = bytearray()
        self.recording = recording
        return recording

    async def run(self, ms=None, poll_ms=2):
        """Record until stop() (or for ms), a step every poll_ms: other tasks run meanwhile.
        Returns the Recording once stopped."""
        if ms is not None:
            bm.number("ms", ms, 0)
        if _type(poll_ms) is not _int or not 0 <= poll_ms <= 1000:
            raise ValueError("poll_ms must be an int in 0..1000, got %r" % (poll_ms,))
        asyncio = bm.aio()
        start = time.ticks_ms()
        while not self.done:
            self.step()
            if ms is not None and time.ticks_diff(time.ticks_ms(), start) >= ms:
                self.stop()
            else:
                await asyncio.sleep_ms(poll_ms)
        return self.recording

    def __await__(self):
        return self.run()

    __iter__ = __await__


def _header(names, joints):
    # The JSON line a file starts with: the joints' names and calibrations.
    return json.dumps({"names": names, "joints": {n: joints[n].config() for n in names}}) + "\n"


def _joints_of(path, header):
    # (names, {name: Joint}) of a file's header line, or ValueError naming the file.
    try:
        header = json.loads(header.decode() if _type(header) is bytes else header)
        names = header["names"]
        joints = {name: bm.Joint(**header["joints"][name]) for name in names}
    except (ValueError, KeyError, TypeError) as e:
        raise ValueError(
            "%s: its first line must be the joints a Recording saves (%s)" % (path, e)
        )
    return names, joints


class Recording:
    def __init__(self, joints, names=None, data=b""):
        """Samples of joints {name: Joint} (in names' order): data is the compact form a
        Recorder makes. Recorder.stop() and Recording.load() make these."""
        if _type(joints) is not dict or not joints:
            raise TypeError("joints must be a dict {name: Joint}, got %r" % (joints,))
        self.names = list(joints) if names is None else list(names)
        self.joints = joints
        self.data = data
        self._count = None
        self._span = None

    def samples(self):
        """Each sample as (ms from the first, [servo positions, in names' order]); the list
        is the same one each time, filled anew."""
        data = self.data
        n = len(self.names)
        pos = [0] * n
        t = 0
        i = 0
        end = len(data)
        while i + 2 + n <= end:
            dt = data[i] | data[i + 1] << 8
            if dt == _KEY:
                if i + 6 + 2 * n > end:
                    break  # cut short (power lost while writing): the rest is lost
                dt = data[i + 2] | data[i + 3] << 8 | data[i + 4] << 16 | data[i + 5] << 24
                i += 6
                for k in range(n):
                    p = data[i] | data[i + 1] << 8
                    pos[k] = p - 0x10000 if p & 0x8000 else p
                    i += 2
            else:
                i += 2
                for k in range(n):
                    d = data[i]
                    pos[k] += d - 256 if d & 0x80 else d
                    i += 1
            t += dt
            yield t, pos

    def __iter__(self):
        """(ms from the first sample, {name: degrees}) of each sample, in order."""
        names = self.names
        joints = [self.joints[name] for name in names]
        for t, pos in self.samples():
            yield t, {names[k]: joints[k].degrees(pos[k]) for k in range(len(names))}

    def __len__(self):
        if self._count is None:
            self._tally()
        return self._count

    @property
    def duration_ms(self):
        """ms from the first sample to the last."""
        if self._count is None:
            self._tally()
        return self._span

    def _tally(self):
        count = span = 0
        for t, _ in self.samples():
            count += 1
            span = t
        self._count = count
        self._span = span

    # Files.

    def save(self, path):
        """Write the recording to path: JSON lines if it ends in .jsonl (a line of the
        joints, then one a sample: {"t": ms, "pose": {name: degrees}}), else the compact
        form. Recording.load() reads either."""
        if _type(path) is not str:
            raise TypeError("path must be a file name (str), got %r" % (path,))
        if path.endswith(".jsonl"):
            with open(path, "w") as f:
                f.write(_header(self.names, self.joints))
                for t, pose in self:
                    for name in pose:
                        pose[name] = round(pose[name], 2)
                    f.write(json.dumps({"t": t, "pose": pose}) + "\n")
        else:
            with open(path, "wb") as f:
                f.write(MAGIC)
                f.write(_header(self.names, self.joints).encode())
                f.write(self.data)

    @staticmethod
    def load(path):
        """The recording save() or a Recorder wrote to path (either form)."""
        with open(path, "rb") as f:
            first = f.readline()
            if not first:
                raise ValueError(
                    "%s is empty: no samples were saved (the recording ended before its "
                    "first write)" % path
                )
            if first == MAGIC or MAGIC.startswith(first):
                header = f.readline()
                if not header.endswith(b"\n"):
                    raise ValueError(
                        "%s is cut short: it ends before its first sample, within the joints "
                        "a recording starts with (no samples were saved)" % path
                    )
                names, joints = _joints_of(path, header)
                return Recording(joints, names, f.read())
            names, joints = _joints_of(path, first)
            rec = Recording(joints, names)
            # Degrees to positions as the joints' servos turn, not clamped to their limits:
            # a limp arm moved by hand may go past them, and the samples keep that.
            free = {}
            for name in names:
                config = joints[name].config()
                config["limits"] = config["dps"] = None
                free[name] = bm.Joint(**config)
            enc = _Encoder(rec)
            line = 1
            for text in f:
                line += 1
                if not text.strip():
                    continue
                try:
                    sample = json.loads(text.decode())
                    t = sample["t"]
                    pose = sample["pose"]
                    bm.number("t", t, 0)
                    got = [free[name].position(bm.number(name, pose[name])) for name in names]
                except (ValueError, KeyError, TypeError) as e:
                    raise ValueError(
                        '%s, line %d: a sample must be {"t": ms, "pose": {name: degrees}}'
                        " of every joint (%s)" % (path, line, e)
                    )
                try:
                    enc.add(round(t), got)
                except ValueError as e:  # a time that goes back: where it is, too
                    raise ValueError("%s, line %d: %s" % (path, line, e))
            rec.data = bytes(enc.data)
            return rec

    # Uses.

    def to_sequence(self, tolerance=1.0, ms=1000):
        """A busservo_motion.Sequence of keyframes: the fewest samples that the joints, going
        straight from one to the next, pass within tolerance degrees of every sample. ms: the
        time to the first pose."""
        bm.number("tolerance", tolerance, 0)
        if _type(ms) is not _int or not 0 <= ms <= 65535:
            raise ValueError("ms must be an int in 0..65535, got %r" % (ms,))
        names = self.names
        n = len(names)
        joints = [self.joints[name] for name in names]
        times = []
        degrees = []
        for t, pos in self.samples():
            times.append(t)
            degrees.append([joints[k].degrees(pos[k]) for k in range(n)])
        if not times:
            raise ValueError("the recording has no samples")
        keep = bytearray(len(times))
        keep[0] = keep[-1] = 1
        todo = [(0, len(times) - 1)]
        while todo:  # Ramer-Douglas-Peucker, over time, without recursion
            a, b = todo.pop()
            worst = tolerance
            at = -1
            span = times[b] - times[a]
            for i in range(a + 1, b):
                u = (times[i] - times[a]) / span if span else 0
                for k in range(n):
                    x = degrees[a][k] + (degrees[b][k] - degrees[a][k]) * u
                    off = abs(degrees[i][k] - x)
                    if off > worst:
                        worst = off
                        at = i
            if at >= 0:
                keep[at] = 1
                todo.append((a, at))
                todo.append((at, b))
        seq = bm.Sequence()
        before = None
        for i in range(len(times)):
            if not keep[i]:
                continue
            pose = {names[k]: round(degrees[i][k], 1) for k in range(n)}
            if before is None:
                seq.append(pose, ms)
            else:
                gap = times[i] - times[before]
                while gap > 65535:  # longer than a move: hold the pose before meanwhile
                    seq.append(seq.steps[-1][0], 65535)
                    gap -= 65535
                seq.append(pose, gap)
            before = i
        return seq

    def play(self, robot, speed=1.0, dps=30):
        """A Playback of this recording on robot: into the first pose at dps, then at the
        recorded pace times speed (0.25..2). Call its step() from a loop, await it, or wait()."""
        return Playback(robot, self, speed, dps)


class _Encoder:
    # Samples packed as a Recorder packs them, into a bytearray (for load()).
    def __init__(self, rec):
        n = len(rec.names)
        self.data = bytearray()
        self.last = [0] * n
        self.t = None

    def add(self, t, got):
        data = self.data
        dt = 0 if self.t is None else t - self.t
        if dt < 0:
            raise ValueError("t must not go back, got %r after %r" % (t, self.t))
        last = self.last
        key = self.t is None or dt > _DT_MAX
        key = key or any(not -128 <= got[k] - last[k] <= 127 for k in range(len(got)))
        if key:
            data.extend(bytes((0xFF, 0xFF, dt & 0xFF, dt >> 8 & 0xFF, dt >> 16 & 0xFF, dt >> 24)))
            for p in got:
                data.extend(bytes((p & 0xFF, p >> 8 & 0xFF)))
        else:
            data.extend(bytes((dt & 0xFF, dt >> 8)))
            data.extend(bytes((got[k] - last[k]) & 0xFF for k in range(len(got))))
        self.last = list(got)
        self.t = t


class Playback:
    def __init__(self, robot, recording, speed=1.0, dps=30):
        """Play recording on robot (its joints by name): first into its first pose at dps,
        then at the recorded pace times speed (0.25..2), each move's time the gap to the
        sample it goes to, so that the servos glide. Registers as robot.player (estop() or a
        new player stops it). Joints' limits and dps always hold."""
        if not isinstance(recording, Recording):
            raise TypeError("recording must be a Recording, got %r" % (recording,))
        if not isinstance(robot, bm.Robot):
            raise TypeError("robot must be a busservo_motion.Robot, got %r" % (robot,))
        bm.number("speed", speed, 0.25, 2)
        bm.number("dps", dps, 0)
        if not dps:
            raise ValueError("dps must be more than 0 degrees/s, got %r" % (dps,))
        _names(robot, recording.names)  # every joint is the robot's
        if not len(recording):
            raise ValueError("the recording has no samples")
        self.robot = robot
        self.recording = recording
        self.speed = speed
        self.dps = dps
        self.names = recording.names
        self._joints = [recording.joints[name] for name in self.names]
        self._ids = [robot.joints[name].servo_id for name in self.names]
        self.index = -1  # the sample the last move went to
        self.done = False
        self.slowed = 0  # moves a joint's dps made longer than the recording's pace
        self.started = None  # ticks_ms the first pose was reached and the pace began
        self.frame_ms = 0  # a move's time on the wire, as measured (0: not yet)
        self._samples = recording.samples()
        self._t, pos = next(self._samples)
        self._pos = list(pos)  # the sample ahead
        self._next = None  # (t, positions) of the one after it, read ahead
        self._query = None
        self._phase = 0  # 0: read where the joints are; 1: going to the first pose; 2: pace
        self._timeouts = 0
        self._due = 0  # ticks_ms the servos reach the last target
        if robot.player:
            robot.player.stop()
        robot.player = self

    def _pose(self, pos):
        joints = self._joints
        return {self.names[k]: joints[k].degrees(pos[k]) for k in range(len(pos))}

    def step(self):
        """Send the next move if its time has come; never waits for the wire. True if it
        sent."""
        if self.done:
            return False
        robot = self.robot
        bus = robot.bus
        if self._phase == 0:  # where are the joints? (a read step by step)
            if self._query is None:
                self._query = bus.ask(self._ids)
            try:
                if next(self._query, _END) is not _END:
                    return False
            except OSError as e:
                self._query = None
                if e.errno != errno.ETIMEDOUT or self._timeouts >= 2:
                    self.stop()
                    raise
                self._timeouts += 1
                return False
            self._query = None
            try:
                robot.where(self.names, positions=bus.positions)  # a servo silent: ENODEV
                before = bus.wire_ms()
                took = robot.move(self._pose(self._pos), dps=self.dps)
            except Exception:
                self.stop()
                raise
            self._sent(took, before)
            self.index = 0
            self._phase = 1
            return True
        now = time.ticks_ms()
        if self._phase == 2 and self._ahead() is None:  # the last move is on its way
            if time.ticks_diff(now, self._due) >= 0:
                self.stop()  # and the servos are there
            return False
        ahead = bus.wire_ms()
        frame = self.frame_ms or 3 * len(self._ids) + 8  # ms at 9600 baud, until measured
        arrive = time.ticks_add(now, ahead + frame)  # a move sent now is in then
        if time.ticks_diff(arrive, self._due) < 0:
            return False  # the servos are not there yet
        if self._phase == 1:  # the first pose is reached: the pace begins
            self._phase = 2
            self.started = self._due
            if self._ahead() is None:  # one sample: it is reached
                self.stop()
                return False
        # The sample to go to: the first whose time on the pace's clock is a frame or more
        # past this move's arrival, so that the next move can follow it in time (at 2x, the
        # wire cannot take every sample: some are passed over).
        speed = self.speed
        at = time.ticks_diff(arrive, self.started)  # the pace's ms at arrival
        while self._ahead() is not None:
            self._take()
            if self._t / speed - at >= frame:
                break
        ms = round(self._t / speed - at)
        ms = 0 if ms < 0 else 65535 if ms > 65535 else ms
        took = robot.move(self._pose(self._pos), ms=ms)
        if took > ms:
            self.slowed += 1
        self._sent(took, ahead)
        return True

    def _ahead(self):
        # The sample after the one held, read ahead (None: there is none).
        if self._next is None:
            got = next(self._samples, None)
            if got is None:
                return None
            self._next = (got[0], list(got[1]))
        return self._next

    def _take(self):
        # The sample ahead becomes the one held.
        self._t, self._pos = self._next
        self._next = None
        self.index += 1

    def _sent(self, took, before):
        # A move went (the wire had before ms ahead of it): note its time on the wire, and
        # when the servos get there.
        ahead = self.robot.bus.wire_ms()
        self._due = time.ticks_add(time.ticks_ms(), ahead + took)
        if ahead - before > self.frame_ms:
            self.frame_ms = ahead - before

    def stop(self):
        """Stop playing; nothing is sent (the move on its way is made: a sample's gap)."""
        self.done = True
        self._query = None
        if self.robot.player is self:
            self.robot.player = None

    def _wait_ms(self, most):
        # ms until the next step() may send, at most most.
        if self._phase == 0:
            return 1
        frame = self.frame_ms or 3 * len(self._ids) + 8
        now = time.ticks_ms()
        wait = time.ticks_diff(self._due, time.ticks_add(now, self.robot.bus.wire_ms() + frame))
        return 0 if wait < 0 else most if wait > most else wait

    def wait(self):
        """Play to the end, blocking; Ctrl-C stops it (and is raised again), the servos where
        they are if a move was on its way (the one into the first pose takes seconds)."""
        try:
            while not self.done:
                self.step()
                if not self.done:
                    time.sleep_ms(self._wait_ms(20))
        except KeyboardInterrupt:
            self.stop()
            if self._phase and time.ticks_diff(self._due, time.ticks_ms()) > 0:
                robot = self.robot
                try:  # where they are, read (blocking: Ctrl-C was pressed), then held
                    robot.move(robot.where(self.names), ms=HALT_MS)
                except (OSError, ValueError):
                    pass  # a servo that does not answer: the move on its way is made
            raise

    async def run(self, poll_ms=20):
        """Play to the end (or until stop()), sleeping until each move is due."""
        asyncio = bm.aio()
        while not self.done:
            self.step()
            if not self.done:
                await asyncio.sleep_ms(self._wait_ms(poll_ms))

    def __await__(self):
        return self.run()

    __iter__ = __await__


if _awaitable:  # CPython: await wants an iterator, not the coroutine MicroPython takes
    _awaitable(Recorder)
    _awaitable(Playback)
