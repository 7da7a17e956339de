# busservo_web_record: recording, replay and teleoperation, a part of busservo_web, loaded
# when a page first asks for one of its routes (it and busservo_record cost a panel that never
# records no RAM), or as the panel starts when the program gave a leader arm:
#
#   asyncio.run(busservo_web.serve(robot, "a password of yours", leader=robot2))
#
#   POST /api/record {"on": true}    every joint goes limp: move the arm by hand, each read of
#                                    the positions is kept (busservo_record's Recorder); with
#                                    the teleop on, the leader is recorded, from its reads
#   POST /api/record {"on": false}   stop: the recording ends and is kept (the teleop goes
#                                    on), or the replay ends
#   POST /api/replay {"speed"}       play the recording (speed 0.25..2, default 1): into its
#                                    first pose at DPS degrees/s, then at its recorded pace
#   POST /api/teleop {"on"}          the leader arm, limp, drives the robot (serve()'s leader)
# and in the state: "rec" {"recording", "leader" (the recording is the leader's), "s",
# "samples", "missed", "playing", "speed"} and
# "teleop": None without a leader, else {"on", "hz" (the leader's reads a second), "engaged",
# "held" (a joint that does not answer), "warning"}.
#
# Each is the armed page's, and holds the joints while it runs (panel.busy, as a sequence
# does): a slider, a jog or a sequence is refused until it ends, and a recording is refused
# while a sequence plays. One runs at a time. Disarming, the dead-man, STOP, and another
# part's order end them (a recording is kept, the joints limp).
#
# The recording reads the positions itself, through the driver's ask() a step each turn of
# the panel's loop; meanwhile the loop asks for none of its own (panel.read_ms None), so that
# no two reads cut into each other on the bus. So does teleoperation (the leader's reads may
# share the bus); a recording made while it is on is of the leader, each of the teleop's reads
# given to it (busservo_teleop's recorder), so the leader is read once for both. The recording
# goes to FILE as it comes, a piece at a time, and stops by itself after MAX_S seconds.
# (busservo_web's header says what a part is, and what it may use of the core.)
import time

import busservo_motion as bm
import busservo_record as br
import busservo_web as web

if not hasattr(time, "ticks_ms"):  # CPython, on a computer: busservo_cpython gives what it lacks
    from busservo_cpython import time

FILE = "recording.rec"  # where a recording goes (busservo_record's compact form)
MAX_S = 120  # a recording stops by itself after this (6 joints at 25 reads a second: 24 KB)
DPS = 30  # into a replay's first pose, or the leader's pose, at this speed
_RECORDING = "recording: stop it first"
_PLAYING = "the recording is playing: stop it first"
_TELEOP = "teleop is on: turn it off first"


class Record:
    def __init__(self, panel):
        leader = panel.options.get("leader")
        if leader is not None and (not isinstance(leader, bm.Robot) or leader is panel.robot):
            raise ValueError("leader must be a busservo_motion.Robot other than the panel's")
        self.panel = panel
        self.leader = leader
        self.recorder = None  # a busservo_record.Recorder under way
        self.recording = None  # the last Recording made
        self.player = None  # its Playback, playing
        self.speed = 1.0
        self.teleop = None  # a busservo_teleop.Teleop, on
        self.warning = None  # the teleop's last warning
        self._started = 0  # ticks_ms a recording began
        self._read_ms = None  # the panel's read_ms, while this part reads

    def _hold(self, why, reads):
        # This part holds the joints; with reads, it reads the positions, not the loop.
        panel = self.panel
        panel.busy = (self, why)
        if reads and panel.read_ms is not None:
            self._read_ms = panel.read_ms
            panel.read_ms = None

    def _free(self):
        panel = self.panel
        if panel.busy and panel.busy[0] is self:
            panel.busy = None
        if self._read_ms is not None:
            panel.read_ms = self._read_ms
            self._read_ms = None

    def _idle(self):
        # Refused while one of this part's own runs.
        for on, why in ((self.recorder, _RECORDING), (self.player, _PLAYING)):
            if on:
                raise web.Refused(409, why)
        if self.teleop:
            raise web.Refused(409, _TELEOP)

    def stop(self, halt=True):
        """End what runs: the recording (kept; the joints stay limp), the replay (with halt,
        the joints stop where they are: the move into its first pose takes seconds) or the
        teleop (the leader stays limp)."""
        player = self.player
        if player:
            self.player = None
            if not player.done:
                player.stop()
                if halt:
                    self.panel.halt(player.names)
        if self.teleop:
            self.teleop.stop()
            self.teleop = None
        self._free()
        self._keep()

    def _keep(self):
        # End the recording under way, if any, and keep it (a teleop on goes on).
        recorder = self.recorder
        self.recorder = None
        if self.teleop:
            self.teleop.recorder = None
        if recorder:
            try:
                recording = recorder.stop()
                self.recording = recording if len(recording) else None
            except (OSError, ValueError) as e:  # the board's filesystem
                self.recording = None
                self.panel.failed(e)

    def _warn(self, text):
        self.warning = text

    # What the core calls.

    def state(self, out, token):
        recorder = self.recorder
        recording = self.recording
        if recorder:
            ms = time.ticks_diff(time.ticks_ms(), self._started)
            samples, missed = recorder.samples, recorder.missed
        else:
            ms = recording.duration_ms if recording else 0
            samples, missed = len(recording) if recording else 0, 0
        out["rec"] = {
            "recording": recorder is not None,
            "leader": recorder is not None and recorder.robot is self.leader,
            "s": round(ms / 1000, 1),
            "samples": samples,
            "missed": missed,
            "playing": self.player is not None,
            "speed": self.speed,
        }
        t = self.teleop
        if self.leader is None:
            out["teleop"] = None
        else:
            out["teleop"] = {
                "on": t is not None,
                "hz": round(1000 / t.period_ms, 1) if t and t.period_ms else 0,
                "engaged": bool(t and t.engaged),
                "held": t and t.held,
                "warning": self.warning,
            }

    def tick(self, read):
        try:
            if self.teleop:
                if self.teleop.done:  # the robot's estop(), or another player
                    self.stop()
                else:
                    self.teleop.step()  # and gives the recorder its reads, if one is on
            elif self.recorder:
                self.recorder.step()
            elif self.player:
                if self.player.done:
                    self.stop()
                else:
                    self.player.step()
            if self.recorder and time.ticks_diff(time.ticks_ms(), self._started) >= MAX_S * 1000:
                if self.teleop:
                    self._keep()  # long enough: kept, and the teleop goes on
                else:
                    self.stop()  # long enough: kept
        except Exception as e:  # the controller, the file: shown, and ended
            self.panel.failed(e)
            self.stop()

    def still(self, halt):
        self.stop(halt)

    async def close(self):
        self.stop()  # a recording under way: its file closed, kept

    # The routes.

    async def post_record(self, body, token):
        panel = self.panel
        if not web.need(body, "on", bool):
            if self.teleop:
                self._keep()  # the recording of the leader ends, the teleop goes on
            else:
                self.stop()
            return panel.state(token)
        panel.driving(token, self)  # armed, and no sequence playing
        if self.teleop and not self.recorder:  # the leader, from the teleop's reads
            try:
                recorder = br.Recorder(self.leader, self.teleop.names, FILE, limp=False)
            except OSError as e:
                raise web.Refused(500, "could not record to %s: %r" % (FILE, e))
            self.teleop.recorder = self.recorder = recorder
            self._started = time.ticks_ms()
            return panel.state(token)
        self._idle()
        panel.order(self)  # the stream, a jog end
        panel.to = {}
        try:
            self.recorder = br.Recorder(panel.robot, path=FILE)  # every joint limp
        except OSError as e:
            raise web.Refused(500, "could not record to %s: %r" % (FILE, e))
        self._started = time.ticks_ms()
        panel.limp = True
        self._hold(_RECORDING, True)
        return panel.state(token)

    async def post_replay(self, body, token):
        panel = self.panel
        speed = 1.0 if body.get("speed") is None else web.need(body, "speed", float, 0.25, 2)
        panel.driving(token, self)
        self._idle()
        if not self.recording:
            raise web.Refused(409, "nothing recorded yet: record first")
        panel.order(self)  # the stream, a jog end
        panel.to = {}
        self.player = self.recording.play(panel.robot, speed, DPS)
        self.speed = speed
        panel.limp = False
        self._hold(_PLAYING, False)
        return panel.state(token)

    async def post_teleop(self, body, token):
        panel = self.panel
        if not web.need(body, "on", bool):
            if self.teleop:
                self.stop()
            return panel.state(token)
        if self.leader is None:
            raise web.Refused(
                409, "no leader arm: the program gives one, as serve(robot, password, leader=arm)"
            )
        panel.driving(token, self)
        self._idle()
        import busservo_teleop  # its RAM only once used

        panel.order(self)
        panel.to = {}
        # Not from rest: the arms may be anywhere when the page turns it on.
        teleop = busservo_teleop.Teleop(self.leader, panel.robot, DPS, rest=False)
        teleop.warn = self._warn
        self.warning = None
        self.teleop = teleop
        panel.limp = False
        self._hold(_TELEOP, True)
        return panel.state(token)


def attach(panel):
    record = Record(panel)
    panel.add(record)
    return record
