#!/usr/bin/env python3
# A stand-in board for the tests: the MicroPython unix port's REPL behind a pty, in a folder
# that is its filesystem, answering mpremote as a board on USB does where the unix port alone
# does not (CPython: the unix port cannot open a pty):
#
#   .venv/bin/python tests/board_pty.py LINK FOLDER
#
# makes LINK a link to the pty, runs .venv/bin/micropython in FOLDER with MICROPYPATH
# ".frozen:FOLDER/lib" (a board's sys.path: its root, then /lib, where mip installs), and relays
# the bytes both ways until killed. What it adds to the unix port, as a board's firmware does it
# (MicroPython's shared/runtime/pyexec.c and a port's main loop):
#
# - Ctrl-C (0x03) from the computer interrupts a running program (KeyboardInterrupt), as a
#   board's UART does, rather than waiting in its input as a byte. The unix port reads
#   Ctrl-C only as the signal a terminal sends: it gets SIGINT instead, while its handler is
#   set (only while a program runs; at its prompt the byte goes through, as a board's does).
# - A soft reset: where the unix port ends (Ctrl-D at the raw REPL's empty line, or
#   sys.exit()), a board clears its heap and starts again. This starts the unix port again,
#   after "MPY: soft reboot", in the raw REPL if it was in it; a program ended by sys.exit()
#   first gets the two 0x04 a board's raw REPL sends at its end (mpremote's exit status 0).
import os
import pty
import select
import signal
import sys
import time
import tty

MICROPYTHON = os.path.join(os.path.dirname(os.path.abspath(__file__)), "../.venv/bin/micropython")


def start(folder):
    """The unix port in folder, on a pty of its own: (pid, the pty's fd)."""
    pid, fd = pty.fork()
    if pid == 0:
        os.chdir(folder)
        tty.setraw(0)  # as a board's UART: no echo, no line editing, bytes as they are
        os.environ["MICROPYPATH"] = ".frozen:" + os.path.join(folder, "lib")
        os.execv(MICROPYTHON, [MICROPYTHON])
    return pid, fd


def catches_sigint(pid):
    """True while the unix port has a handler for SIGINT: while a program runs."""
    try:
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith("SigCgt:"):
                    return bool(int(line.split()[1], 16) & (1 << (signal.SIGINT - 1)))
    except OSError:
        pass
    return False


def main(link, folder):
    host, board_side = os.openpty()
    tty.setraw(board_side)
    if os.path.lexists(link):
        os.remove(link)
    os.symlink(os.ttyname(board_side), link)
    pid, fd = start(folder)
    raw = False  # in the raw REPL (Ctrl-A), as mpremote puts it
    running = False  # a raw REPL command sent (Ctrl-D), its end (0x04 then ">") not yet seen
    tail = b""
    try:
        while True:
            ready, _, _ = select.select([host, fd], [], [])
            if host in ready:
                data = os.read(host, 4096)
                out = bytearray()
                for b in data:
                    if b == 3 and catches_sigint(pid):
                        os.kill(pid, signal.SIGINT)  # the board's interrupt character
                        continue
                    if b == 1:
                        raw = True
                    elif b == 2:
                        raw = False
                    elif b == 4 and raw:
                        running = True
                    out.append(b)
                if out:
                    os.write(fd, bytes(out))
            if fd in ready:
                try:
                    data = os.read(fd, 4096)
                except OSError:
                    data = b""
                if data:
                    os.write(host, data)
                    tail = (tail + data)[-2:]
                    if tail == b"\x04>":
                        running = False
                    continue
                # The unix port ended: a board soft-resets.
                os.waitpid(pid, 0)
                os.close(fd)
                if running:
                    os.write(host, b"\x04\x04")  # a board's raw REPL says a program ended
                os.write(host, b"MPY: soft reboot\r\n")
                pid, fd = start(folder)
                running = False
                tail = b""
                if raw:
                    time.sleep(0.2)  # its banner first, which a board in the raw REPL omits
                    os.write(fd, b"\x01")
    finally:
        os.kill(pid, signal.SIGKILL)
        if os.path.islink(link):
            os.remove(link)


if __name__ == "__main__":
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    main(sys.argv[1], os.path.abspath(sys.argv[2]))
