#!/usr/bin/env python3
# The simulated controller (lib/busservo_sim.py, on the MicroPython unix port) behind a pty,
# so that any program can talk to it as to a controller on a USB-serial adapter:
#
#   sh boards/unix.sh --sim-pty [--link PATH]
#
# prints the pty's path (and makes PATH a link to it), then serves until stopped. This file
# is CPython: the unix port cannot open a pty itself (it has no openpty and no ffi here).
#
# --link PATH never deletes what it did not make: it replaces only a symlink that is dangling
# or points to a pty (/dev/pts/...), as an earlier run leaves behind if it is killed; anything
# else at PATH is refused (exit status 1). On the way out it removes the link only if it still
# points to this run's pty.
#
# Ctrl-C (SIGINT) stops it quietly with exit status 130, as a shell expects of an interrupted
# command; SIGTERM (kill) with 0, as before; a hang-up (SIGHUP) with 129.
import argparse
import os
import signal
import subprocess
import sys
import tty


def refuse(message):
    print("boards/simpty.py: " + message, file=sys.stderr)
    sys.exit(1)


def what_is_at(link):
    """None if link may be replaced: nothing is there, or a symlink that is dangling or points
    to a pty. Otherwise what is there, in words."""
    if not os.path.lexists(link):
        return None
    if not os.path.islink(link):
        return "a directory" if os.path.isdir(link) else "a file"
    target = os.readlink(link)
    if not os.path.exists(link) or target.startswith("/dev/pts/"):
        return None
    return "a link to " + target


def check_link(link):
    there = what_is_at(link)
    if there is not None:
        refuse(
            "--link %s: it is %s, which this did not make; not replacing it "
            "(remove it, or choose another path)" % (link, there)
        )


def make_link(link, pty):
    check_link(link)
    try:
        if os.path.lexists(link):
            os.remove(link)  # a dangling link, or one to a pty
        os.symlink(pty, link)  # fails if anything has taken the path meanwhile
    except OSError as e:
        refuse("--link %s: cannot make it a link to %s: %s" % (link, pty, e.strerror))


def remove_link(link, pty):
    try:
        if os.readlink(link) == pty:
            os.remove(link)
    except OSError:
        pass  # gone, or no longer a link: not this run's to remove


def stop(signum, frame):
    sys.exit(0 if signum == signal.SIGTERM else 128 + signum)


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--link", help="also make this path a symlink to the pty")
    parser.add_argument("--micropython", default="micropython", help="the unix port to run")
    args = parser.parse_args()
    if args.link:
        check_link(args.link)  # before anything is made

    path = sim = None
    try:
        signal.signal(signal.SIGTERM, stop)
        signal.signal(signal.SIGHUP, stop)
        master, slave = os.openpty()
        tty.setraw(slave)  # bytes go through untouched until the driver sets its own mode
        path = os.ttyname(slave)
        if args.link:
            make_link(args.link, path)
        # In a session of its own: a Ctrl-C at the terminal reaches this process alone, which
        # stops the simulator quietly (rather than it printing its own KeyboardInterrupt).
        sim = subprocess.Popen(
            [args.micropython, "-m", "busservo_sim"],
            stdin=master,
            stdout=master,
            close_fds=True,
            start_new_session=True,
        )
        print("busservo simulator on %s (Ctrl-C stops it)" % path, flush=True)
        # The slave stays open here, so the pty lives while drivers come and go.
        status = sim.wait()
        return status if status >= 0 else 128 - status
    except KeyboardInterrupt:
        return 130
    finally:
        for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            signal.signal(signum, signal.SIG_IGN)  # a second Ctrl-C cannot cut the clean-up
        if sim is not None:
            sim.terminate()
            sim.wait()
        if args.link and path:
            remove_link(args.link, path)


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # a Ctrl-C before main() is under way: nothing to clean up
        sys.exit(130)
