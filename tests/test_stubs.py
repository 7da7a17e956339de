# The type stubs (lib/*.pyi) against the modules as MicroPython runs them. Every public name a
# module has (its functions, classes and constants; a class's methods, and an instance's
# attributes) is in its stub, of the same kind, and the stub has none the module lacks. Each
# function's parameters (names, order, which have defaults) are what calling it with the wrong
# arguments tells, and a default the stub spells out is the source's. MicroPython has no
# typing module: the stubs, and the sources' defaults, are read as text.
import unittest

import busservo
import busservo_arm
import busservo_async
import busservo_board
import busservo_calibrate
import busservo_motion
import busservo_record
import busservo_sim
import busservo_teleop
import busservo_web

MODULES = (
    busservo,
    busservo_async,
    busservo_board,
    busservo_sim,
    busservo_motion,
    busservo_web,
    busservo_arm,
    busservo_calibrate,
    busservo_teleop,
    busservo_record,
)

# AsyncBusServo.__getattr__ forwards to its BusServo: its stub declares what it forwards, with
# the signatures of BusServo's methods. {class: (the module, the class it forwards to)}
FORWARDS = {"AsyncBusServo": (busservo, "BusServo")}

# Public at run time, left out of the stub on purpose (editors then flag their use).
UNSTUBBED = {
    # BusServo.ask() is the step-by-step query AsyncBusServo runs under its lock; run on the
    # AsyncBusServo it would go around the lock, and its reply past the waiting tasks.
    "busservo_async.AsyncBusServo.ask",
    # What MicroPython's exceptions carry besides args (an OSError's errno, StopIteration's
    # value): not the panel's Refused's to say.
    "busservo_web.Refused.errno",
    "busservo_web.Refused.value",
}


def instances():
    """An instance of each public class, to see its attributes."""
    sim = busservo_sim.SimController()
    bus = busservo.BusServo(sim)
    robot = busservo_motion.Robot(bus, {"base": busservo_motion.Joint(1)})
    sequence = busservo_motion.Sequence([({"base": 10}, 100)])
    joints = {name: busservo_motion.Joint(i + 1) for i, name in enumerate(busservo_arm.JOINTS)}
    links = {"base_height": 70, "upper_arm": 105, "forearm": 98, "hand": 150}
    arm = busservo_arm.Arm(busservo_motion.Robot(bus, joints), links)
    arm.move_to(100, 0, 50, ms=0)  # known: the line reads nothing
    recording = busservo_record.Recording(robot.joints, ["base"], b"\xff\xff\0\0\0\0\xf4\x01")
    return {
        "BusServo": bus,
        "AsyncBusServo": busservo_async.AsyncBusServo(bus),
        "SimController": sim,
        "Joint": robot.joints["base"],
        "Robot": robot,
        "Sequence": sequence,
        "Player": sequence.play(robot),
        "Panel": busservo_web.Panel(robot, "a password"),
        "Arm": arm,
        "Line": arm.line_to(120, 0, 50),
        "Calibration": busservo_calibrate.Calibration(bus, {"base": 1}),
        "Refused": busservo_web.Refused(409, "why"),
        "Teleop": busservo_teleop.Teleop(
            robot, busservo_motion.Robot(bus, {"base": busservo_motion.Joint(2)})
        ),
        "Recorder": busservo_record.Recorder(robot, limp=False),
        "Recording": recording,
        "Playback": recording.play(busservo_motion.Robot(bus, {"base": robot.joints["base"]})),
    }


# Reading Python source as text.


def statements(text):
    """The logical lines of Python source as (indent, text): comments dropped, a statement's
    lines within brackets joined, a triple-quoted string (a docstring) made ""."""
    out = []
    line = []
    indent = 0
    depth = 0
    start = True
    i = 0
    n = len(text)
    while i < n:
        c = text[i]
        if start:  # a statement's first line: measure its indent
            j = i
            while j < n and text[j] == " ":
                j += 1
            indent = j - i
            i = j
            start = False
        elif c == "\n" or c == "#":
            while c == "#" and i < n and text[i] != "\n":
                i += 1
            i += 1
            if depth:
                line.append(" ")
            else:
                s = "".join(line).strip()
                if s:
                    out.append((indent, s))
                line = []
                start = True
        elif c == '"' or c == "'":
            if text[i : i + 3] == c * 3:
                end = text.find(c * 3, i + 3)
                end = n if end < 0 else end + 3
                line.append('""')
            else:
                end = i + 1
                while end < n and text[end] != c:
                    end += 2 if text[end] == "\\" else 1
                end += 1
                line.append(text[i:end])
            i = end
        else:
            if c in "([{":
                depth += 1
            elif c in ")]}":
                depth -= 1
            line.append(c)
            i += 1
    s = "".join(line).strip()
    if s:
        out.append((indent, s))
    return out


def split(text, sep):
    """text split at each sep outside brackets and strings."""
    parts = []
    depth = 0
    quote = None
    begin = 0
    for i, c in enumerate(text):
        if quote:
            quote = None if c == quote else quote
        elif c == '"' or c == "'":
            quote = c
        elif c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
        elif c == sep and not depth:
            parts.append(text[begin:i])
            begin = i + 1
    parts.append(text[begin:])
    return parts


def identifier(text):
    """The identifier text starts with ("" if none)."""
    i = 0
    while i < len(text) and (text[i] == "_" or text[i].isalpha() or text[i].isdigit()):
        i += 1
    return text[:i]


def signature(s):
    """A def statement's name and ([(parameter, default text or None)], return annotation);
    a parameter "*" stands for any * or ** in it."""
    if s.startswith("async "):
        s = s[6:]
    open_ = s.index("(")
    name = s[4:open_].strip()
    close = open_
    depth = 0
    for close in range(open_, len(s)):  # the matching bracket
        depth += (s[close] in "([{") - (s[close] in ")]}")
        if not depth:
            break
    params = []
    for p in split(s[open_ + 1 : close], ","):
        p = p.strip()
        if p.startswith("*"):
            params.append(("*", None))
        elif p and p != "/":
            head = split(p, "=")
            default = "=".join(head[1:]).strip() if len(head) > 1 else None
            params.append((head[0].split(":")[0].strip(), default))
    tail = s[close + 1 :].strip()
    returns = tail[2:].rstrip(":. ").strip() if tail.startswith("->") else None
    return name, params, returns


def imported(s):
    """The names an import statement binds."""
    if s.startswith("from "):
        s = s[s.index(" import ") + 8 :]
    else:
        s = s[7:]
    names = []
    for part in s.strip("() ").split(","):
        words = part.split()
        if words:
            names.append(words[-1] if "as" in words else words[0].split(".")[0])
    return names


def parse(text):
    """What source or a stub defines at its top level and in its classes' bodies, by name
    ("Class.member" for a member): ("def", params, returns, decorators), ("class",),
    ("var", annotation or None, value text or None), or ("import",)."""
    found = {}
    cls = None  # the class whose body this is, and that body's indent
    body = None
    decorators = []
    for indent, s in statements(text):
        if indent and cls is None and (s.startswith("import ") or s.startswith("from ")):
            for name in imported(s):  # in a try (what CPython lacks: lib/busservo_cpython.py)
                found[name] = ("import",)
            continue
        if not indent:
            cls = None
        elif cls is None or body not in (None, indent):
            continue  # in a function, or an if
        elif body is None:
            body = indent
        prefix = cls + "." if indent else ""
        if s.startswith("@"):
            decorators.append(s[1:])
            continue
        if s.startswith("def ") or s.startswith("async def "):
            name, params, returns = signature(s)
            found[prefix + name] = ("def", params, returns, decorators)
        elif s.startswith("class "):
            name = identifier(s[6:])
            found[prefix + name] = ("class",)
            if not indent:
                cls = name
                body = None
        elif s.startswith("import ") or s.startswith("from "):
            for name in imported(s):
                found[prefix + name] = ("import",)
        else:
            name = identifier(s)
            rest = s[len(name) :].strip()
            if name and rest.startswith(":"):
                parts = rest[1:].split("=", 1)
                value = parts[1].strip() if len(parts) > 1 else None
                found[prefix + name] = ("var", parts[0].strip(), value)
            elif name and rest.startswith("=") and not rest.startswith("=="):
                found[prefix + name] = ("var", None, rest[1:].strip())
        decorators = []
    return found


PARSED = {}


def parsed(path):
    if path not in PARSED:
        with open(path) as f:
            PARSED[path] = parse(f.read())
    return PARSED[path]


def stub(module):
    return parsed("lib/%s.pyi" % module.__name__)


def source(module):
    return parsed("lib/%s.py" % module.__name__)


def kind(entry):
    """What parse() found: a def, a class or a var (a property is a var)."""
    if entry[0] == "def" and "property" in entry[3]:
        return "var"
    return entry[0]


def public(names):
    return set(name for name in names if not name.startswith("_"))


# What the modules have at run time.


def runtime_names(module):
    """A module's public names and their kinds, less what it imports."""
    own = source(module)
    names = {}
    for name in public(dir(module)):
        if own.get(name, ("",))[0] == "import":
            continue
        value = getattr(module, name)
        names[name] = "class" if isinstance(value, type) else "def" if callable(value) else "var"
    return names


def runtime_members(cls, obj):
    """A class's public methods and an instance's public attributes, and their kinds."""
    members = {}
    for name in public(dir(cls)) | public(dir(obj)):
        members[name] = "def" if callable(getattr(obj, name)) else "var"
    return members


def stub_functions(module):
    """The stub's public functions and methods, constructors included: (name, entry)."""
    for name, entry in sorted(stub(module).items()):
        private = [part for part in name.split(".") if part[0] == "_" and part != "__init__"]
        if kind(entry) == "def" and not private:
            yield name, entry


def behind(module, qualified):
    """Where a stub's "name" or "Class.name" is defined: (module, its qualified name there),
    through FORWARDS."""
    if "." in qualified:
        cls, name = qualified.split(".")
        if cls in FORWARDS and name not in dir(getattr(module, cls)):
            module, cls = FORWARDS[cls]
        qualified = cls + "." + name
    return module, qualified


def function(module, qualified):
    """The function behind a stub's "name" or "Class.name"."""
    module, qualified = behind(module, qualified)
    owner = module
    for part in qualified.split("."):
        owner = getattr(owner, part, None)
    return owner


TYPES = {"None": type(None), "bool": bool, "int": int, "dict": dict, "set": set, "list": list}


def type_ok(annotation, value):
    """Whether value is of the annotation's type, as far as a simple one tells: the builtins
    in TYPES and our own classes; any other (Final, Callable, ...) lets any value be."""
    if annotation is None:
        return True
    for option in split(annotation, "|"):
        name = option.split("[")[0].strip()
        if name in TYPES:
            if isinstance(value, TYPES[name]):
                return True
        elif type(value).__name__ == name or not any(hasattr(m, name) for m in MODULES):
            return True
    return False


class _Nothing:
    pass


NOTHING = _Nothing()


def error(f, n, **kw):
    """What calling f with n positional arguments (and kw) raises: its message, or None."""
    try:
        f(*([NOTHING] * n), **kw)
    except Exception as e:
        return str(e)
    return None


def call_problems(f, where, params):
    """How f's arity and parameter names differ from params, as far as its errors tell."""
    if ("*", None) in params:
        return []  # varargs: not told
    n = len(params)
    got = error(f, n + 1)
    if got is not None and "positional arguments but" not in got:
        return []  # terse error messages: MicroPython cannot tell here
    want = "takes %d positional arguments but %d were given" % (n, n + 1)
    if got is None or want not in got:
        got = got or "it takes them"
        return ["%s: with %d arguments: %r, not %r" % (where, n + 1, got, want)]
    problems = []
    required = len([p for p in params if p[1] is None])
    if required:
        got = error(f, 0)
        want = "takes %d positional arguments but 0 were given" % required
        if got is None or want not in got:
            problems.append("%s: with no arguments: %r, not %r" % (where, got, want))
    # If each name is among the first j + 1, the names are these, in this order.
    for j, (name, _) in enumerate(params):
        got = error(f, j + 1, **{name: NOTHING})
        want = "multiple values for argument '%s'" % name
        if got is None or want not in got:
            problems.append("%s: parameter %d is not %r (%r)" % (where, j, name, got))
    return problems


def resolve(text, names, module):
    """The value of a source's default: a literal, const(), a module constant, or a name of
    the module's (such as time.ticks_ms); NOTHING if none of these."""
    for _ in range(5):
        entry = names.get(text)
        if entry and entry[0] == "var" and entry[2]:
            text = entry[2]
        elif text.startswith("const(") and text.endswith(")"):
            text = text[6:-1]
        else:
            break
    try:
        return eval(text, module.__dict__)
    except Exception:
        return NOTHING


class Stubs(unittest.TestCase):
    def test_the_stubs_are_read(self):
        self.assertEqual(stub(busservo)["BusServo.move"][0], "def")
        self.assertEqual(stub(busservo)["CMD_SERVO_MOVE"], ("var", "Final", "3"))
        params = stub(busservo)["BusServo.read_positions"][1]
        self.assertEqual(params, [("self", None), ("ids", None), ("timeout_ms", "None")])
        self.assertEqual(stub(busservo_async)["AsyncBusServo.running"][3], ["property"])
        self.assertIn("ALL_GROUPS", source(busservo_sim))  # imported, and so not its own

    def test_module_names_match(self):
        problems = []
        for module in MODULES:
            path = "lib/%s.pyi" % module.__name__
            have = runtime_names(module)
            said = {}
            for name, entry in stub(module).items():
                if "." not in name and not name.startswith("_") and entry[0] != "import":
                    said[name] = kind(entry)
            for name in sorted(set(have) | set(said)):
                where = "%s.%s" % (module.__name__, name)
                if name not in said:
                    problems.append("%s (a %s) is not in %s" % (where, have[name], path))
                elif name not in have:
                    problems.append("%s is in %s, not in the module" % (where, path))
                elif have[name] != said[name]:
                    problems.append("%s: a %s, the stub says %s" % (where, have[name], said[name]))
        self.assertEqual(problems, [])

    def test_constants_match(self):
        problems = []
        for module in MODULES:
            for name, entry in stub(module).items():
                if entry[0] != "var" or "." in name or name.startswith("_"):
                    continue
                where = "%s.%s" % (module.__name__, name)
                value = getattr(module, name, NOTHING)
                if entry[2] not in (None, "...") and eval(entry[2], {}) != value:
                    problems.append("%s is %r, the stub says %s" % (where, value, entry[2]))
                if not type_ok(entry[1], value):
                    problems.append("%s is %r, the stub says %s" % (where, value, entry[1]))
        self.assertEqual(problems, [])

    def test_class_members_match(self):
        problems = []
        objects = instances()
        unstubbed = set(UNSTUBBED)
        for module in MODULES:
            said = stub(module)
            for cls in sorted(n for n, e in said.items() if e[0] == "class" and n[0] != "_"):
                obj = objects.get(cls)
                if obj is None:
                    problems.append("%s: no instance to look at: add one to instances()" % cls)
                    continue
                have = runtime_members(getattr(module, cls), obj)
                members = {}
                for name, entry in said.items():
                    if name.startswith(cls + ".") and not name.split(".")[1].startswith("_"):
                        members[name.split(".")[1]] = entry
                prefix = "%s.%s." % (module.__name__, cls)
                left_out = set(n[len(prefix) :] for n in UNSTUBBED if n.startswith(prefix))
                for name in sorted(set(have) | set(members) | left_out):
                    where = prefix + name
                    if where in UNSTUBBED:
                        unstubbed.discard(where)
                        if name not in have or name in members:
                            problems.append("%s is in UNSTUBBED: not so" % where)
                    elif name not in members:
                        problems.append("%s (a %s) is not in its stub" % (where, have[name]))
                    elif name not in have:
                        problems.append("%s is in its stub, not in the module" % where)
                    elif have[name] != kind(members[name]):
                        problems.append(
                            "%s: a %s, the stub says %s" % (where, have[name], kind(members[name]))
                        )
                    else:
                        entry = members[name]
                        annotation = entry[1] if entry[0] == "var" else entry[2]
                        if kind(entry) == "var" and not type_ok(annotation, getattr(obj, name)):
                            problems.append(
                                "%s of a new one is %r, the stub says %s"
                                % (where, getattr(obj, name), annotation)
                            )
        for where in sorted(unstubbed):
            problems.append("%s is in UNSTUBBED: no such class" % where)
        self.assertEqual(problems, [])

    def test_signatures_match_the_functions(self):
        problems = []
        for module in MODULES:
            for name, entry in stub_functions(module):
                where = "%s.%s" % (module.__name__, name)
                f = function(module, name)
                if f is None:
                    problems.append("%s is in its stub, not in the module" % where)
                else:
                    problems += call_problems(f, where, entry[1])
        self.assertEqual(problems, [])

    def test_signatures_match_the_source(self):
        # Names, order and defaults as the source spells them: a default the stub gives is
        # the source's value, and the stub gives every default that is a literal.
        problems = []
        for module in MODULES:
            for name, entry in stub_functions(module):
                where = "%s.%s" % (module.__name__, name)
                home, qualified = behind(module, name)
                names = source(home)
                if names.get(qualified, ("",))[0] != "def":
                    problems.append(
                        "%s: no def %s in lib/%s.py" % (where, qualified, home.__name__)
                    )
                    continue
                params = names[qualified][1]
                if [p[0] for p in params] != [p[0] for p in entry[1]]:
                    problems.append("%s: the source has %s" % (where, [p[0] for p in params]))
                    continue
                for (param, default), (_, said) in zip(params, entry[1]):
                    if (default is None) != (said is None):
                        problems.append("%s: %s's default is %s" % (where, param, default))
                    if default is None or said is None:
                        continue
                    value = resolve(default, names, home)
                    literal = value is None or type(value) in (bool, int, float, str)
                    if said == "..." and literal:
                        problems.append("%s: say %s=%r in the stub" % (where, param, value))
                    elif said != "..." and eval(said, {}) != value:
                        problems.append(
                            "%s: %s=%s, the source has %r" % (where, param, said, value)
                        )
        self.assertEqual(problems, [])


if __name__ == "__main__":
    unittest.main()
