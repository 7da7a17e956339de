# busservo_web_jog: the arm's jog, a part of busservo_web. The tool point a step along
# x, y, z (mm) or its pitch (degrees), in a straight line at JOG_MM_S (busservo_arm's
# Line, streamed as a slider is: the dead-man and STOP end it).
#
#   POST /api/jog {"axis": "x"|"y"|"z"|"pitch", "by"} -> the state
# and in the state: "arm" (there is an arm to jog), "no_arm" (why not, in words), "tool"
# (x, y, z mm and pitch where the joints are), "jog" (where the jogs are going) and
# "jog_note" (the last jog went along the edge of the reach, and how far short).
#
# A jog whose line leaves the reach is refused, in busservo_arm's words, and nothing moves;
# but one that leaves it by at most EDGE_MM goes along its edge: a stretched arm (its rest
# pose, straight up) can move sideways only so.
#
# The arm is the one the program gave serve(), or the one the calibration file's links
# make. serve() plugs this part in only then (or when a page first jogs, to say why not),
# so that a panel without an arm keeps its RAM, and busservo_arm's, for the robot's
# program; without it the state has no "arm".
# (busservo_web's header says what a part is, and what it may use of the core.)
import busservo_web as web

JOG_MM_S = 40  # a jog's straight line: the tool point's speed
JOG_MAX = 100  # mm (or degrees of pitch) a jog may go at once
AXES = ("x", "y", "z", "pitch")
EDGE_MM = 2  # a jog that leaves the reach by at most this goes along its edge


class Jog:
    def __init__(self, panel):
        self.panel = panel
        self.line = None  # a jog's busservo_arm.Line on its way
        self.goal = None  # [x, y, z, pitch] the jogs have reached, while jogged is the order
        self.jogged = -1
        self.note = None  # what the page is told of the last jog (it went along the edge)
        self.arm = panel.arm
        self.robots = panel.robots if self.arm else None  # the robot the arm is on
        self.no_arm = None  # why there is no arm to jog
        self._arm()

    def _load(self):
        # The Arm that the links in the calibration file make, or None, and why in no_arm.
        panel = self.panel
        self.no_arm = None
        if not panel.saved("links"):
            self.no_arm = "no links in %s: calibrate, and give the links" % panel.path
            return None
        try:
            return panel.load("busservo_arm").Arm.load(panel.robot, panel.path)
        except ImportError:
            self.no_arm = "busservo_arm is missing: install it beside busservo_web"
        except (ValueError, TypeError) as e:
            self.no_arm = str(e)
        return None

    def _arm(self):
        # The arm, made (again) from the file when the panel has a new robot (calibrated), or
        # once free() let it go; but not while another part holds the joints (a calibration:
        # a board's heap holds its code or the arm), nor while the heap has no room for it
        # (tried again at the next call).
        panel = self.panel
        if self.robots != panel.robots:
            self.arm = None  # (another robot's)
            if panel.busy:
                self.no_arm = panel.busy[1]
            else:
                try:
                    self.arm = self._load()
                    self.robots = panel.robots
                except MemoryError:
                    self.no_arm = "no room for the arm now (out of memory): tried again soon"
        return self.arm

    # What the core calls.

    def state(self, out, token):
        arm = self._arm()
        out["arm"] = arm is not None
        if arm is None:
            out["no_arm"] = self.no_arm
        elif None not in out["at"]:
            at = dict(zip(self.panel.robot.names, out["at"]))
            out["tool"] = [round(v, 1) for v in arm.point(at)]
        if self.jogged == self.panel.orders:
            out["jog"] = self.goal
            out["jog_note"] = self.note

    def tick(self, read):
        line = self.line
        if line and self.panel.armed is not None:
            if line.done:
                self.line = None
            else:
                line.step()  # streams the line's next point, sent when it can be

    def still(self, halt):
        if self.line:
            self.line.stop()
            self.line = None
            self.panel.robot.hold()

    def free(self):
        # A calibration begins: the arm the file made, and busservo_arm (10 KB), are let go
        # while it holds the joints, and made again then, from the new calibration.
        panel = self.panel
        if self.arm is not None and self.arm is not panel.arm:
            self.still(False)
            self.arm = self.robots = None
            self.no_arm = panel.busy[1] if panel.busy else "let go: ask again"
        panel.unload("busservo_arm")  # (unless the program imported it)

    def _along_the_edge(self, arm, goal):
        # A jog a hair past the reach (the arm stretched: from its rest pose, any step but
        # down leaves it): the line to the nearest point the arm reaches, if that is within
        # EDGE_MM of the goal, and the goal made that point; else None.
        x, y, z = arm.reach(goal[0], goal[1], goal[2], goal[3])
        off = ((x - goal[0]) ** 2 + (y - goal[1]) ** 2 + (z - goal[2]) ** 2) ** 0.5
        if not 0 < off <= EDGE_MM:
            return None
        try:
            line = arm.line_to(x, y, z, goal[3], mm_s=JOG_MM_S)
        except ValueError:
            return None
        self.note = "at the edge of the reach: %.1f mm short of the step" % off
        goal[0], goal[1], goal[2] = round(x, 1), round(y, 1), round(z, 1)
        return line

    # The route.

    async def post_jog(self, body, token):
        panel = self.panel
        panel.driving(token, self)  # (a sequence playing holds the joints)
        arm = self._arm()
        if arm is None:
            raise web.Refused(409, "no arm to jog: " + self.no_arm)
        axis = body.get("axis")
        if axis not in AXES:
            raise web.Refused(400, "axis must be one of %s, got %r" % (", ".join(AXES), axis))
        by = web.need(body, "by", float, -JOG_MAX, JOG_MAX)
        orders = panel.orders
        goal = self.goal
        if self.jogged != orders:  # something else moved the arm: start from where it is
            robot = panel.robot
            ids = [robot.joints[name].servo_id for name in robot.names]
            goal = arm.where(await panel.positions(ids))  # where it is, from what came
            if panel.orders != orders:
                raise web.Refused(409, "stopped, or moved otherwise, while reading: jog again")
        goal = list(goal)
        goal[AXES.index(axis)] += by
        self.note = None
        try:
            line = arm.line_to(goal[0], goal[1], goal[2], goal[3], mm_s=JOG_MM_S)
        except ValueError as e:  # out of reach, or past a joint's limits: nothing is sent
            line = self._along_the_edge(arm, goal)
            if line is None:
                raise web.Refused(409, "cannot jog there: %s" % e)
        self.jogged = panel.order(self)  # the stream, or a jog on its way, ends
        self.still(False)
        panel.robot.hold()
        self.line = line
        self.goal = goal
        panel.to.update(arm.pose(goal[0], goal[1], goal[2], goal[3]))
        panel.limp = False
        return panel.state(token)


def attach(panel):
    jog = Jog(panel)
    panel.add(jog)
    return jog
