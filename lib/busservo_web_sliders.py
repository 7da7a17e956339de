# busservo_web_sliders: the panel's sliders, a part of busservo_web. A slider dragged on
# the armed page sends its joint's target; the robot's stream sends the latest to the
# servos (Robot.stream(): nothing queues behind it), stepped by the panel's loop.
#
#   POST /api/target {"targets": {name: degrees}}   -> {}
#
# (busservo_web's header says what a part is, and what it may use of the core.)


class Sliders:
    def __init__(self, panel):
        self.panel = panel

    def target(self, token, targets):
        """Stream targets {name: degrees} from the page of token: refused unless it is armed,
        while a sequence plays, or past a joint's limits."""
        panel = self.panel
        panel.driving(token, self)  # (a sequence playing holds the joints)
        targets = panel.pose(targets, "targets")
        panel.order(self)  # the sliders take over (from a jog, say)
        panel.robot.stream(targets)
        panel.to.update(targets)
        panel.limp = False

    def still(self, halt):
        self.panel.robot.hold()  # the stream ends: each joint stops at its last target

    async def post_target(self, body, token):
        self.target(token, body.get("targets"))
        return {}


def attach(panel):
    sliders = Sliders(panel)
    panel.add(sliders)
    return sliders
