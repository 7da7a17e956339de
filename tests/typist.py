#!/usr/bin/env python3
# A person at a terminal, for tests: runs a command on a pty of its own (as a terminal would,
# so a program that wants a console, such as `mpremote repl`, gets one), waits for each text
# it is told to expect, then types what follows it. CPython: the unix port cannot open a pty.
#
#   .venv/bin/python tests/typist.py SECONDS EXPECT TYPE [EXPECT TYPE ...] -- COMMAND ...
#
# TYPE may hold \r (Enter), \x1d (Ctrl-]) and other escapes, as a Python string does. It
# prints all the command printed, and exits with the command's status; with 124 if a text it
# waited for did not come within SECONDS (of the one before), saying which.
import os
import pty
import select
import sys
import time


def read(fd, seen, seconds):
    """Add to seen what fd says within seconds: False if nothing came, or it has ended."""
    ready, _, _ = select.select([fd], [], [], seconds)
    if not ready:
        return False
    try:
        data = os.read(fd, 4096)
    except OSError:  # the command has ended: its pty is closed
        return False
    seen += data
    return bool(data)


def main(argv):
    split = argv.index("--")
    seconds = float(argv[0])
    pairs = argv[1:split]
    steps = [(pairs[i].encode(), pairs[i + 1]) for i in range(0, len(pairs), 2)]
    pid, fd = pty.fork()
    if pid == 0:
        os.execvp(argv[split + 1], argv[split + 1 :])
    seen = bytearray()
    at = 0  # how far the texts expected so far were found
    try:
        for expect, keys in steps:
            deadline = time.monotonic() + seconds
            while seen.find(expect, at) < 0:
                left = deadline - time.monotonic()
                if left <= 0 or not read(fd, seen, left):
                    os.kill(pid, 9)
                    os.waitpid(pid, 0)
                    seen += b"\ntests/typist.py: %r did not come within %g s\n" % (expect, seconds)
                    return 124
            at = seen.find(expect, at) + len(expect)
            os.write(fd, keys.encode().decode("unicode_escape").encode("latin-1"))
        while read(fd, seen, seconds):  # what it prints until it ends
            pass
        deadline = time.monotonic() + seconds
        done, status = os.waitpid(pid, os.WNOHANG)
        while not done and time.monotonic() < deadline:
            time.sleep(0.05)
            done, status = os.waitpid(pid, os.WNOHANG)
        if not done:
            os.kill(pid, 9)
            os.waitpid(pid, 0)
            seen += b"\ntests/typist.py: it did not end within %g s\n" % seconds
            return 124
        return os.waitstatus_to_exitcode(status)
    finally:
        sys.stdout.buffer.write(seen)
        sys.stdout.flush()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
