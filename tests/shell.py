# Shell commands from tests on the unix port, which has os.system() and no subprocess.
import os
import sys
import time

MICROPYTHON = ".venv/bin/micropython"
MPREMOTE = ".venv/bin/mpremote"
PYTHON = os.getcwd() + "/.venv/bin/python"  # CPython (tests start in the repository's root)


def scratch(name):
    """A fresh path in $TMPDIR (else /tmp) for this run."""
    tmp = os.getenv("TMPDIR") or "/tmp"
    return "%s/busservo-%s-%s" % (tmp, name, "".join("%02x" % b for b in os.urandom(4)))


def free_port():
    """A TCP port on 127.0.0.1 that nothing listens on: the one the OS gives a bind to port 0
    (asked from CPython: MicroPython's sockets do not say which port they were given), so that
    two runs of the tests at once never serve on the same port."""
    ok, out = sh(
        PYTHON + " -c 'import socket; s = socket.socket(); "
        's.bind(("127.0.0.1", 0)); print(s.getsockname()[1])\''
    )
    if not ok:
        raise OSError("no free port: " + out)
    return int(out)


def sh(command):
    """Run command with sh; return (True if it exited 0, what it printed)."""
    out = scratch("out")
    status = os.system("(%s) >%s 2>&1" % (command, out))
    with open(out) as f:
        text = f.read()
    os.remove(out)
    return status == 0, text


def sh_all(commands):
    """Run the commands at once, each with sh as sh() does: [(ok, what it printed)] in their
    order. For commands that spend their time waiting (an example's moves, on real time)."""
    base = scratch("all")
    os.mkdir(base)
    for i, command in enumerate(commands):
        each = "%s/%d" % (base, i)
        os.system("( (%s) >%s.out 2>&1; echo $? >%s.rc ) </dev/null &" % (command, each, each))
    done = []
    for i in range(len(commands)):
        each = "%s/%d" % (base, i)
        status = wait_for(each + ".rc", 10 * 60 * 1000, "\n")
        with open(each + ".out") as f:
            done.append((status is not None and status.strip() == "0", f.read()))
    os.system("rm -rf " + base)
    return done


def start(command, log):
    """Start command in the background, its output to log; return its pid."""
    ok, pid = sh("%s >%s 2>&1 & echo $!" % (command, log))
    return int(pid)


def stop(pid):
    os.system("kill %d 2>/dev/null" % pid)


def wait_for(path, ms=10000, text=None):
    """Wait until path exists, or with text, until the file holds text; then
    return True, or with text, the file's content. None if it does not come."""
    start = time.ticks_ms()
    while time.ticks_diff(time.ticks_ms(), start) < ms:
        try:
            if text is None:
                os.stat(path)  # not open(): path may be a pty
                return True
            with open(path) as f:
                content = f.read()
            if text in content:
                return content
        except OSError:
            pass
        time.sleep_ms(20)
    return None


def fresh_import(name, **stand_ins):
    """Import module name afresh, with stand-ins in sys.modules for the modules named
    (machine=..., termios=...); sys.modules is as it was afterwards."""
    saved = {key: sys.modules.get(key) for key in list(stand_ins) + [name]}
    for key, module in stand_ins.items():
        sys.modules[key] = module
    sys.modules.pop(name, None)
    try:
        return __import__(name)
    finally:
        for key, module in saved.items():
            if module is None:
                sys.modules.pop(key, None)
            else:
                sys.modules[key] = module
