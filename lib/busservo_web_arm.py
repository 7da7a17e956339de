# busservo_web_arm: the web panel's jog and calibration page, imported by busservo_web only
# when a page first uses them (or when the calibration file has an arm's links), so that a
# panel without an arm keeps its RAM for the robot's program. It is the panel's own: its
# functions work on a busservo_web.Panel's insides, and nothing else should import it.
#
# Jog: the arm's tool point a step along x, y, z (mm) or its pitch (degrees), in a straight
# line at JOG_MM_S (busservo_arm's Line, streamed as a slider is: the dead-man and STOP end
# it). A calibration by hand: busservo_calibrate's three steps, a request each, the positions
# they need read as all the panel's are, through the driver's ask(), never waiting on the
# wire.
import busservo_motion as bm
import busservo_web as web

JOG_MM_S = 40  # a jog's straight line: the tool point's speed
JOG_MAX = 100  # mm (or degrees of pitch) a jog may go at once
AXES = ("x", "y", "z", "pitch")
HOME_DPS = 30  # the home after a calibration: slowly


def arm(panel, robot):
    """The Arm that the links in panel.path make on robot, or None, and why in panel.no_arm."""
    panel.no_arm = None
    try:
        import busservo_arm

        return busservo_arm.Arm.load(robot, panel.path)
    except ImportError:
        panel.no_arm = "busservo_arm is missing: install it beside busservo_web"
    except (ValueError, TypeError) as e:
        panel.no_arm = str(e)
    return None


def _adopt(panel, robot):
    # Drive robot, the calibration just saved, and the arm its file's links make, if any.
    panel.robot = robot
    panel._ids = [robot.joints[name].servo_id for name in robot.names]
    panel.to = {}
    panel.robots += 1
    panel.arm = arm(panel, robot)


def state(panel, out, at):
    # The state's arm and calibration: whether there is an arm to jog ("arm"), its tool
    # point where the joints are ("tool": x, y, z mm, pitch), the jog's target ("jog"), and
    # the calibration's step, what it has seen and what it refuses ("cal").
    arm = panel.arm
    out["arm"] = arm is not None
    if arm and None not in at:
        out["tool"] = [round(v, 1) for v in arm.point(dict(zip(panel.robot.names, at)))]
    if panel._jogged == panel._orders:
        out["jog"] = panel._jog
    if panel.cal:
        out["cal"] = panel._cal


async def _ask(panel):
    # {servo_id: position} of every joint, once it has come through the driver's ask() (a
    # step every few ms, the panel's loop going on).
    bus = panel.bus
    ids = panel._ids
    async with panel._asking:
        for _ in bus.ask(ids):
            await web.asyncio.sleep_ms(web._ASK_MS)
        return {i: bus.positions.get(i) for i in ids}


def step(panel):
    # From the panel's loop, while armed: the jog's line, a step.
    line = panel._line
    if line.done:
        panel._line = None
    else:
        line.step()  # streams the line's next point, and sends it when it can


async def jog(panel, body, token):
    panel._driver(token)
    panel._not_playing()
    arm = panel.arm
    if arm is None:
        why = panel.no_arm or "no links in %s: calibrate, and give the links" % panel.path
        raise web._Refused(409, "no arm to jog: " + why)
    axis = body.get("axis")
    if axis not in AXES:
        raise web._Refused(400, "axis must be one of %s, got %r" % (", ".join(AXES), axis))
    by = web._need(body, "by", float, -JOG_MAX, JOG_MAX)
    orders = panel._orders
    goal = panel._jog
    if panel._jogged != orders:  # something else moved the arm: start from where it is
        goal = list(arm.where(await _ask(panel)))  # where it is, from what came
        if panel._orders != orders:
            raise web._Refused(409, "stopped, or moved otherwise, while reading: jog again")
    goal = list(goal)
    goal[AXES.index(axis)] += by
    try:
        line = arm.line_to(goal[0], goal[1], goal[2], goal[3], mm_s=JOG_MM_S)
    except ValueError as e:  # out of reach, or past a joint's limits: nothing is sent
        raise web._Refused(409, "cannot jog there: %s" % e)
    panel._orders += 1
    if panel._line:
        panel._line.stop()
    panel.robot.hold()
    panel._line = line
    panel._jog = goal
    panel._jogged = panel._orders
    panel.to.update(arm.pose(goal[0], goal[1], goal[2], goal[3]))
    panel.limp = False
    return panel.state(token)


async def calibrate(panel, body, token):
    if panel.armed != token:  # (not _driver(): it refuses while a calibration is under way)
        raise web._Refused(409, "arm the panel first (another page may have it armed)")
    step = body.get("step")
    cal = panel.cal
    news = panel._cal
    if step == "start":
        if panel.player:
            raise web._Refused(409, "a sequence is playing: stop it first")
        try:
            import busservo_calibrate
        except ImportError:
            why = "busservo_calibrate is missing: install it beside busservo_web"
            raise web._Refused(500, why)
        robot = panel.robot
        ids = {}
        kinds = {}
        for name in robot.names:
            joint = robot.joints[name]
            ids[name] = joint.servo_id
            if joint.kind != bm.BUS:
                kinds[name] = joint.kind
        cal = busservo_calibrate.Calibration(panel.bus, ids, kinds)
        panel._orders += 1
        panel._still()
        panel.to = {}
        cal.limp()  # every joint: the person holds the arm
        panel.limp = True
        panel.cal = cal
        panel._cal = {"step": "rest", "seen": None, "why": None, "joints": None}
        return panel.state(token)
    if step == "cancel":
        panel.cal = None  # nothing saved; the joints stay as they are (limp)
        return panel.state(token)
    after = {"rest": "rest", "nudge": "sweep", "check": "nudge", "save": "check"}
    after["home"] = "saved"
    if step not in after:
        raise web._Refused(
            400, "step must be start, %s or cancel, got %r" % (", ".join(after), step)
        )
    if cal is None:
        raise web._Refused(409, "no calibration under way: start one")
    if news["step"] != after[step]:
        raise web._Refused(
            409, "the calibration is at its %s step, not %s's" % (news["step"], after[step])
        )
    news["why"] = None
    if step == "rest":
        cal.rest(await _ask(panel))
        news["step"] = "sweep"
    elif step == "nudge":
        news["step"] = "nudge"  # the sweep's reads so far are its range
    elif step == "check":
        if not _feel(panel, cal, await _ask(panel)):
            raise web._Refused(504, news["why"][""])
        problems = cal.problems()
        if problems:
            news["why"] = problems
            said = ["%s: %s" % (n, problems[n]) for n in cal.names if n in problems]
            raise web._Refused(409, "cannot calibrate " + "; ".join(said))
        joints = cal.joints()
        news["joints"] = [
            [joints[n].trim, joints[n].direction, joints[n].lo, joints[n].hi] for n in cal.names
        ]
        news["step"] = "check"
    elif step == "save":
        links = body.get("links")
        if links is None and panel.arm:
            links = panel.arm.links  # the arm's, kept
        try:
            robot = cal.save(panel.path, links)
        except (TypeError, ValueError) as e:
            raise web._Refused(400, str(e))
        except OSError as e:  # the board's filesystem
            raise web._Refused(500, "could not save %s: %r" % (panel.path, e))
        _adopt(panel, robot)
        news["step"] = "saved"  # limp still: nothing moves until the home is confirmed
    else:
        if body.get("confirm") is not True:
            raise web._Refused(400, 'home moves the arm: send "confirm": true')
        orders = panel._orders
        await panel.where()  # where the limp joints were left: the home's distances
        if panel._orders != orders or panel.cal is not cal:
            raise web._Refused(409, "stopped while reading: home again")
        robot = panel.robot
        pose = {n: min(max(0, j.lo), j.hi) for n, j in robot.joints.items()}
        robot.move(pose, dps=HOME_DPS)
        panel.to = pose
        panel.limp = False
        panel.cal = None
    return panel.state(token)


def feel(panel):
    # From the panel's loop, when positions have come during a calibration: the sweep's
    # sample, or the nudge's read.
    if panel._cal["step"] in ("sweep", "nudge"):
        cal = panel.cal
        _feel(panel, cal, {i: panel.bus.positions.get(i) for i in cal.ids})


def _feel(panel, cal, positions):
    # A read for a step that reads again and again (the sweep, the nudge): its news. A
    # servo that does not answer is named, and the next read may do.
    news = panel._cal
    try:
        if news["step"] == "sweep":
            got = cal.sample(positions)
        else:
            got = cal.nudge(positions)
    except (OSError, ValueError) as e:
        news["why"] = {"": str(e)}
        return False
    news["seen"] = [got[n] for n in cal.names]
    return True
