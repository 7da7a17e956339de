# busservo_web_calibrate: the calibration page, a part of busservo_web, loaded when a
# page first asks for it (it and busservo_calibrate cost a panel that never calibrates no
# RAM). busservo_calibrate's three steps by hand, a request each, the positions they need
# read as all the panel's are, through the driver's ask(), never waiting on the wire. A
# calibration makes room as it starts (the jog lets its arm go), and lets go of
# busservo_calibrate and of this part as it ends: a board's heap holds the one or the other.
#
#   POST /api/calibrate {"step": "start"|"rest"|"nudge"|"check"|"save"|"home"|"cancel"}
#        ("save" may give "links" {name: mm}; "home" needs "confirm": true) -> the state
# and in the state, while one is under way: "cal" {"step", "seen", "why", "joints"}.
#
# Only the armed page calibrates; while it does, the calibration holds the joints (limp:
# the person moves them) and nothing else drives them. Disarming, the dead-man and STOP
# give it up, with nothing saved and the joints limp.
# (busservo_web's header says what a part is, and what it may use of the core.)
import busservo_motion as bm
import busservo_web as web

HOME_DPS = 30  # the home after a calibration: slowly
READ_MS = 100  # positions read this often while a calibration sweeps or is nudged
_BUSY = "a calibration is under way: finish or cancel it first"
# The step each request ends: the step the calibration must be at for it.
_AFTER = {"rest": "rest", "nudge": "sweep", "check": "nudge", "save": "check", "home": "saved"}


class Calibrate:
    def __init__(self, panel):
        self.panel = panel
        self.cal = None  # a busservo_calibrate.Calibration under way
        self.news = None  # its news for the page: {"step", "seen", "why", "joints"}
        self._read_ms = panel.read_ms

    def _end(self):
        # No calibration under way: the joints are free to drive, read as often as before.
        panel = self.panel
        self.cal = None
        if panel.busy and panel.busy[0] is self:
            panel.busy = None
        panel.read_ms = self._read_ms
        panel.unload("busservo_calibrate")  # (4 KB) loaded again by the next start
        panel.unplug(__name__)  # (3 KB) this part too, until next asked for

    # What the core calls.

    def state(self, out, token):
        if self.cal:
            out["cal"] = self.news

    def tick(self, read):
        # The positions just read: the sweep's sample, or the nudge's read.
        if self.cal and read and self.news["step"] in ("sweep", "nudge"):
            cal = self.cal
            positions = self.panel.bus.positions
            self._feel({i: positions.get(i) for i in cal.ids})

    def still(self, halt):
        if self.cal and self.panel.armed is None:
            self._end()  # disarmed: given up, nothing saved, the joints limp

    def _feel(self, positions):
        # A read for a step that reads again and again (the sweep, the nudge): its news. A
        # servo that does not answer is named, and the next read may do.
        news = self.news
        try:
            if news["step"] == "sweep":
                got = self.cal.sample(positions)
            else:
                got = self.cal.nudge(positions)
        except (OSError, ValueError) as e:
            news["why"] = {"": str(e)}
            return False
        news["seen"] = [got[n] for n in self.cal.names]
        return True

    def _start(self):
        panel = self.panel
        panel.order(self)  # the stream, a jog or a sequence ends (a recording gives read_ms back)
        if self.cal is None:
            self._read_ms = panel.read_ms  # given back as it ends
        panel.busy = (self, _BUSY)  # nothing else drives (the jog says so, its arm let go)
        robot = panel.robot
        ids = {}
        kinds = {}
        for name in robot.names:
            joint = robot.joints[name]
            ids[name] = joint.servo_id
            if joint.kind != bm.BUS:
                kinds[name] = joint.kind
        try:
            panel.free(self)  # room for the calibration's code: the jog's arm (10 KB)
            self.cal = panel.load("busservo_calibrate").Calibration(panel.bus, ids, kinds)
        except Exception as e:
            self._end()
            if isinstance(e, ImportError):
                why = "busservo_calibrate is missing: install it beside busservo_web"
                raise web.Refused(500, why)
            raise
        panel.to = {}
        self.cal.limp()  # every joint: the person holds the arm
        panel.limp = True
        panel.read_ms = READ_MS
        self.news = {"step": "rest", "seen": None, "why": None, "joints": None}

    # The route.

    async def post_calibrate(self, body, token):
        panel = self.panel
        # Armed, and no other part holds the joints (a sequence playing); this one may.
        panel.driving(token, self)
        step = body.get("step")
        if step == "start":
            self._start()
            return panel.state(token)
        if step == "cancel":
            self._end()  # nothing saved; the joints stay as they are (limp)
            return panel.state(token)
        if step not in _AFTER:
            raise web.Refused(
                400, "step must be start, %s or cancel, got %r" % (", ".join(_AFTER), step)
            )
        cal = self.cal
        news = self.news
        if cal is None:
            raise web.Refused(409, "no calibration under way: start one")
        if news["step"] != _AFTER[step]:
            raise web.Refused(
                409, "the calibration is at its %s step, not %s's" % (news["step"], _AFTER[step])
            )
        news["why"] = None
        if step == "rest":
            cal.rest(await panel.positions(cal.ids))
            news["step"] = "sweep"
        elif step == "nudge":  # the sweep is over: its reads so far are the ranges
            short = cal.unswept()
            if short:
                news["why"] = short
                said = ["%s: %s" % (n, short[n]) for n in cal.names if n in short]
                raise web.Refused(409, "sweep each joint first: " + "; ".join(said))
            news["step"] = "nudge"
        elif step == "check":
            if not self._feel(await panel.positions(cal.ids)):
                raise web.Refused(504, news["why"][""])
            problems = cal.problems()
            if problems:
                news["why"] = problems
                said = ["%s: %s" % (n, problems[n]) for n in cal.names if n in problems]
                raise web.Refused(409, "cannot calibrate " + "; ".join(said))
            joints = cal.joints()
            news["joints"] = [
                [joints[n].trim, joints[n].direction, joints[n].lo, joints[n].hi]
                for n in cal.names
            ]
            news["step"] = "check"
        elif step == "save":
            self._save(body.get("links"))
            news["step"] = "saved"  # limp still: nothing moves until the home is confirmed
        else:
            await self._home(body)
        return panel.state(token)

    def _save(self, links):
        # The calibration to the file, with links if given, else those saved before
        # (busservo_calibrate keeps what else the file holds), and drive it.
        panel = self.panel
        if links is None and panel.arm:
            links = panel.arm.links  # the program's arm's, kept
        if links is not None:
            panel.load("busservo_arm")  # it checks them: loaded for that, then let go
        try:
            robot = self.cal.save(panel.path, links, panel.dps)  # the panel's cap kept
        except (TypeError, ValueError) as e:
            raise web.Refused(400, str(e))
        except OSError as e:  # the board's filesystem
            raise web.Refused(500, "could not save %s: %r" % (panel.path, e))
        finally:
            panel.unload("busservo_arm")  # (the jog makes its arm once this calibration ends)
        panel.adopt(robot)

    async def _home(self, body):
        panel = self.panel
        if body.get("confirm") is not True:
            raise web.Refused(400, 'home moves the arm: send "confirm": true')
        cal = self.cal
        orders = panel.orders
        await panel.where()  # where the limp joints were left: the home's distances
        if panel.orders != orders or self.cal is not cal:
            raise web.Refused(409, "stopped while reading: not homed (the calibration is saved)")
        robot = panel.robot
        pose = {n: min(max(0, j.lo), j.hi) for n, j in robot.joints.items()}
        self._end()
        robot.move(pose, dps=HOME_DPS)
        panel.to = pose
        panel.limp = False


def attach(panel):
    calibrate = Calibrate(panel)
    panel.add(calibrate)
    return calibrate
