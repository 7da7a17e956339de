# busservo_web_teach: teaching and sequences, a part of busservo_web. Limp the arm and
# pose it by hand, capture the pose, add it to the sequence (or edit or remove a step),
# play the sequence back, halt it, and save and load sequences under sequences/ by a
# name of letters, digits, - and _.
#
#   POST /api/limp, /api/capture -> {"pose"}, /api/add {"pose", "ms"} (no pose: read now),
#        /api/edit {"index", "pose", "ms"}, /api/remove {"index"}, /api/clear,
#        /api/play {"speed", "loop"}, /api/stop, /api/save {"name"}, /api/load {"name"}
#   GET  /api/steps -> [{"pose": {name: degrees}, "ms"}, ...], /api/sequences -> ["name", ...]
# and in the state: "steps" (each step's ms), "edits" (one more with each change: the page
# reads the steps again), "playing" (the step playing, or None).
#
# Limp, like every order, is the armed page's (STOP is any page's), and leaves it armed.
# A sequence plays from the armed page only, and holds the joints while it plays: the
# sliders and the jog are refused until it ends, or is halted. Halted (or the page
# disarmed), the joints it moves are sent where they are, once a read of their positions
# has come (about 30 ms; the loop goes on meanwhile).
# (busservo_web's header says what a part is, and what it may use of the core.)
import os

import busservo_motion as bm
import busservo_web as web

FOLDER = "sequences"
NAME_MAX = 24
MS_DEFAULT = 1000  # time to reach an added pose, if the request gives none
_NAME_CHARS = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_"
_PLAYING = "a sequence is playing: stop it first"
_LIMP = "arm the panel first: Limp is the armed page's (STOP lets go from any page)"


def _name(body):
    # A sequence's name, safe as a file name under FOLDER.
    name = body.get("name")
    if (
        type(name) is not str
        or not 1 <= len(name) <= NAME_MAX
        or name.strip(_NAME_CHARS)  # a character not among them
    ):
        raise web.Refused(
            400, "name must be 1..%d letters, digits, - or _, got %r" % (NAME_MAX, name)
        )
    return FOLDER + "/" + name + ".json"


class Teach:
    def __init__(self, panel):
        self.panel = panel
        self.sequence = bm.Sequence()
        self.edits = 0  # changes to the sequence: the page reads it again when this grows
        self.player = None

    # Playing.

    def play(self, token, speed, loop):
        """Play the sequence from the page of token (armed), at speed, looping if loop."""
        panel = self.panel
        panel.driving(token, self)
        if not self.sequence.steps:
            raise web.Refused(409, "the sequence is empty: add poses first")
        if self.player:
            self.player.stop()
        panel.order(self)  # the stream and a jog end
        panel.to = {}
        self.player = self.sequence.play(panel.robot, speed, loop)
        panel.busy = (self, _PLAYING)
        panel.limp = False

    def stop(self, halt=True):
        """Stop the sequence; with halt, its pose on the way too (which would go on for
        its ms): the joints it moves are sent where they are, once their positions came."""
        player = self.player
        self._done()
        if player and not player.done:
            player.stop()
            if halt:
                names = set()
                for pose, _ in self.sequence.steps:
                    names.update(pose)
                self.panel.halt(list(names))

    def _done(self):
        self.player = None
        if self.panel.busy and self.panel.busy[0] is self:
            self.panel.busy = None

    def _not_playing(self):
        if self.player:
            raise web.Refused(409, _PLAYING)

    def _step(self, body):
        # The index of a step of the sequence, checked; none while it plays.
        steps = self.sequence.steps
        if not steps:
            raise web.Refused(409, "the sequence is empty")
        self._not_playing()
        return web.need(body, "index", int, 0, len(steps) - 1)

    def _changed(self, token):
        self.edits += 1
        return self.panel.state(token)

    # What the core calls.

    def state(self, out, token):
        steps = out["steps"] = []
        for _, ms in self.sequence.steps:
            steps.append(ms)
        out["edits"] = self.edits
        out["playing"] = self.player.index if self.player else None

    def tick(self, read):
        if self.player:
            if self.player.done:
                self._done()
            else:
                self.player.step()

    def still(self, halt):
        self.stop(halt)

    # The routes.

    async def post_limp(self, body, token):
        # Limp is teaching, the armed page's (STOP, from any page, is what lets go to be
        # safe): it ends what drives the joints (a sequence, a stream: no halt, they let go)
        # and the page stays armed, so that a slider, the jog or Play takes them again.
        panel = self.panel
        if panel.armed != token:
            raise web.Refused(409, _LIMP)
        panel.order()
        panel.robot.limp()
        panel.limp = True
        panel.to = {}
        return panel.state(token)

    async def post_capture(self, body, token):
        return {"pose": await self.panel.where()}

    async def post_add(self, body, token):
        # The pose given (the one the page showed, maybe edited), else the one read now.
        panel = self.panel
        ms = MS_DEFAULT if body.get("ms") is None else web.need(body, "ms", int, 0, 65535)
        pose = body.get("pose")
        pose = await panel.where() if pose is None else panel.pose(pose, "pose")
        self.sequence.append(pose, ms)
        return self._changed(token)

    async def post_edit(self, body, token):
        i = self._step(body)
        pose, ms = self.sequence.steps[i]
        if body.get("pose") is not None:
            pose = dict(self.panel.pose(body["pose"], "pose"))
        if body.get("ms") is not None:
            ms = web.need(body, "ms", int, 0, 65535)
        self.sequence.steps[i] = (pose, ms)
        return self._changed(token)

    async def post_remove(self, body, token):
        self.sequence.steps.pop(self._step(body))
        return self._changed(token)

    async def post_clear(self, body, token):
        self._not_playing()
        self.sequence = bm.Sequence()
        return self._changed(token)

    async def get_steps(self, body, token):
        steps = []
        for pose, ms in self.sequence.steps:
            steps.append({"pose": pose, "ms": ms})
        return steps

    async def post_play(self, body, token):
        speed = 1.0 if body.get("speed") is None else web.need(body, "speed", float, 0.1, 10)
        self.play(token, speed, bool(body.get("loop")))
        return self.panel.state(token)

    async def post_stop(self, body, token):
        self.panel.order(self, halt=True)  # a replay on its way stops where it is too
        self.stop()
        return self.panel.state(token)

    async def get_sequences(self, body, token):
        try:
            names = os.listdir(FOLDER)
        except OSError:
            names = []
        found = []
        for n in names:
            if n.endswith(".json"):
                found.append(n[:-5])
        found.sort()
        return found

    async def post_save(self, body, token):
        path = _name(body)
        if not self.sequence.steps:
            raise web.Refused(409, "the sequence is empty: add poses first")
        try:
            os.mkdir(FOLDER)
        except OSError:
            pass  # it is there
        try:
            self.sequence.save(path)
        except OSError as e:  # the board's filesystem, not the controller
            raise web.Refused(500, "could not save %s: %r" % (path, e))
        return {}

    async def post_load(self, body, token):
        path = _name(body)
        self._not_playing()
        try:
            sequence = bm.Sequence.load(path)
        except OSError:
            raise web.Refused(404, "no sequence %r" % body["name"])
        except (ValueError, KeyError, TypeError) as e:
            raise web.Refused(400, "%s is not a sequence: %s" % (path, e))
        joints = self.panel.robot.joints
        for pose, _ in sequence.steps:
            for name in pose:
                if name not in joints:
                    raise web.Refused(
                        400, "%s moves joint %r, which this robot has not" % (path, name)
                    )
        self.sequence = sequence
        return self._changed(token)


def attach(panel):
    teach = Teach(panel)
    panel.add(teach)
    return teach
