# Servos 1..5 go limp, then home slowly; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# Calibrate your arm by hand, once, in about a minute: every joint goes limp and you
# 1. hold the arm in its rest pose (docs/calibrate.md's picture): each joint's 0;
# 2. move each joint through the whole range it may safely use: its limits;
# 3. put it back in its rest pose and nudge each joint a little in its positive direction;
# with Enter (or board.py's button) after each. It saves robot.json, which every example then
# uses (busservo_board.robot()), or refuses, naming the joint, what it cannot trust. Nothing
# moves under power until it is saved and you confirm a slow home(). On the simulator no one
# can turn the servos: the example's own hands do, and it saves nothing.
#
# On a board it runs at the board's REPL, where your Enter reaches it (`mpremote run`
# forwards no keys: it would wait for ever, the arm limp). With board.py on the board:
#   mpremote mip install lib/busservo_calibrate.json   # once: the driver, motion, calibration
#   mpremote cp examples/calibrate.py :calibrate.py
#   mpremote repl              then type: import calibrate      (Ctrl-] leaves mpremote)
# To calibrate again: Ctrl-D (a soft reset), then import calibrate. With a board.py that offers
# button() (boards/esp32.py: BOOT; boards/rp2.py: BOOTSEL) a press ends each step and a press
# confirms the home (a 1 s press: no home), with no keys at all: `mpremote run
# examples/calibrate.py` works then too (and the links are left out).
#   sh boards/unix.sh examples/calibrate.py     # unix port, simulated controller
import errno
import sys
import time

import busservo_board
import busservo_calibrate as bc
import busservo_motion as bm

# Set True once you hold the arm (limp, it falls) and each joint turns freely by hand.
I_HAVE_CHECKED_MY_ROBOT = False
# Your arm: each joint's servo id (roll, between wrist and gripper, if it has one). A PWM
# servo cannot tell the controller where a hand turned it: leave such a joint out.
IDS = {"base": 1, "shoulder": 2, "elbow": 3, "wrist": 4, "gripper": 5}
DPS = 30  # the first home(): no joint turns faster (degrees a second)
PATH = bm.CALIBRATION  # robot.json: every example loads it

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check

cal = bc.Calibration(bus, IDS)
print("the servos are at", bus.read_positions(cal.ids))
print(
    "this lets %s go limp, calibrates them by your hand, saves %s, and homes them at %d "
    "degrees/s once you say so" % (", ".join(cal.names), PATH, DPS)
)
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit

# On the simulator, these stand for your hands: each joint's servo position at the rest
# pose, at the two ends of its safe range, and nudged.
HANDS = {
    "base": (512, 140, 880, 560),
    "shoulder": (488, 200, 800, 440),  # mounted the other way round: forward turns it back
    "elbow": (500, 150, 860, 545),
    "wrist": (530, 180, 880, 480),  # the other way round too
    "gripper": (300, 300, 700, 350),  # closed at rest: one end of its range
}
OTHER = (500, 200, 800, 540)  # a joint you added

try:  # a board.py may offer a button(): a machine.Pin that reads 0 while pressed
    import board

    button = getattr(board, "button", None)
except ImportError:
    button = None


def hold(pose):
    """On the simulator: the hands put each servo at pose [(servo_id, position)], and let go."""
    bus.move_many(pose, 0)  # the hands: a move at once, then limp again
    bus.unload(cal.ids)


def ask(prompt, during=None):
    """Wait for the person, calling during() meanwhile: the line typed at the console after
    Enter, or "" for a press of board.py's button ("n" for a 1 s press). None with no
    console (its input has ended). A prompt that ends "then" is told which."""
    if prompt.endswith(" then"):
        prompt += " press the button" if button else " Enter:"
    if button:
        pin = button()
        print(prompt)
        while pin.value():
            if during:
                during()
            time.sleep_ms(10)
        pressed = time.ticks_ms()
        while not pin.value():
            time.sleep_ms(10)
        return "" if time.ticks_diff(time.ticks_ms(), pressed) < 1000 else "n"
    if during:
        import select

        print(prompt)  # what during() prints comes below it
        poller = select.poll()
        poller.register(sys.stdin, select.POLLIN)
        while not poller.poll(0):  # until a key comes (a whole line, at a unix terminal)
            during()
    else:
        print(prompt, end=" ")
    try:
        if sys.platform in ("linux", "darwin"):  # the unix port: its terminal echoed the line
            line = sys.stdin.readline()
            if line:
                return line.strip()
        else:
            return input().strip()
    except EOFError:
        pass
    print()  # the console has ended: end the prompt's line
    return None


class Live:
    """What a step has seen so far, printed when it changes (at most twice a second)."""

    def __init__(self, what):
        self.what = what
        self.said = self.new = ""
        self.at = time.ticks_ms()

    def show(self, text):
        self.new = text
        if time.ticks_diff(time.ticks_ms(), self.at) >= 500:
            self.end()

    def end(self):
        if self.new != self.said:
            print("  %s: %s" % (self.what, self.new))
            self.said = self.new
            self.at = time.ticks_ms()


seen = Live("range seen, degrees")
nudged = Live("nudged from the rest pose, degrees")


def read(step):
    """step()'s answer, or None for a read lost (noise on the line?): the next one will do."""
    try:
        return step()
    except OSError as e:
        if e.args[0] != errno.ETIMEDOUT:
            raise  # a servo that does not answer: its joint is named
    return None


def sample():
    ranges = read(cal.sample)
    if ranges:
        seen.show(", ".join("%s %d" % (n, ranges[n][1] - ranges[n][0]) for n in cal.names))


def nudge():
    moved = read(cal.nudge)
    if moved:
        nudged.show(", ".join("%s %+d" % (n, moved[n]) for n in cal.names))


def calibrate():
    """The three steps: True once done, False if the console ended them."""
    cal.limp()
    print("the joints are limp: hold the arm")
    if busservo_board.simulated:  # the hands do each step, and no one presses Enter
        print("1. the simulator's hands hold the arm in its rest pose")
        hold([(IDS[n], HANDS.get(n, OTHER)[0]) for n in cal.names])
        cal.rest()
        print("2. they move each joint through its safe range")
        for k in range(11):
            sweep = [HANDS.get(n, OTHER) for n in cal.names]
            hold([(IDS[n], a[1] + (a[2] - a[1]) * k // 10) for n, a in zip(cal.names, sweep)])
            sample()
        seen.end()
        print("3. they put it back in its rest pose and nudge each joint")
        hold([(IDS[n], HANDS.get(n, OTHER)[3]) for n in cal.names])
        nudge()
        nudged.end()
        return True
    if ask("1. hold the arm in its rest pose (docs/calibrate.md), then") is None:
        return False
    cal.rest()
    if ask("2. move each joint through all its safe range, then", sample) is None:
        return False
    sample()
    seen.end()
    step = "3. put it back in its rest pose, nudge each joint a little in its positive"
    if ask(step + " direction (docs/calibrate.md), hold it there, then", nudge) is None:
        return False
    nudge()
    nudged.end()
    return True


def links():
    """The links measured with a ruler, {name: mm}, or None: left out."""
    if busservo_board.simulated or button:
        return None
    from busservo_arm import LINKS  # the arm's names for them

    while True:
        names = " ".join(LINKS)
        line = ask("links in mm, axis to axis (%s), or Enter to leave them out:" % names)
        if not line:
            return None
        try:
            mm = [float(x) for x in line.split()]
            if len(mm) == len(LINKS):
                return dict(zip(LINKS, mm))
        except ValueError:
            pass
        print("  %d numbers in mm, such as: 70 105 98 60" % len(LINKS))


arm = None
try:
    if not calibrate():
        print("no console (its input ended): nothing saved; the joints stay limp")
    elif cal.problems():
        problems = cal.problems()
        for name in cal.names:
            if name in problems:
                print("refused: %s: %s" % (name, problems[name]))
        print("nothing saved; the joints stay limp: calibrate again")
    elif busservo_board.simulated:
        arm = cal.robot()
        print("on the simulator nothing is saved (%s is your arm's); it would hold:" % PATH)
    else:
        cal.save(PATH, links())
        arm = busservo_board.robot(bus, {})  # the file, as every example will load it
        print("saved %s:" % PATH)
except OSError as e:  # a servo that does not answer: its joint is named
    print("stopped: %s: nothing saved; the joints stay limp" % e)
if arm:
    for name in arm.names:
        j = arm.joints[name]
        print(
            "  %s: servo %d, trim %.1f, direction %+d, limits %.1f..%.1f degrees"
            % (name, j.servo_id, j.trim, j.direction, j.lo, j.hi)
        )
    if busservo_board.simulated:
        yes = True  # no one to ask
    elif button:
        yes = ask("home now, at %d degrees/s? a press: yes; held 1 s: no" % DPS) == ""
    else:
        answer = ask("home now, at %d degrees/s? y and Enter (Enter alone: no):" % DPS)
        yes = answer is not None and answer.lower() == "y"
    if yes:
        print("homing at %d degrees/s: every joint to its 0, the rest pose" % DPS)
        time.sleep_ms(arm.home(dps=DPS))
        where = arm.where()
        print("home:", ", ".join("%s %.1f" % (n, where[n] + 0) for n in arm.names), "degrees")
    else:
        print("no home: the joints stay limp")
