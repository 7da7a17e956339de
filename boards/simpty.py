#!/usr/bin/env python3
# The simulated controller (lib/busservo_sim.py, on the MicroPython unix port) behind a pty,
# so that any program can talk to it as to a controller on a USB-serial adapter:
#
#   sh boards/unix.sh --sim-pty [--link PATH]
#
# prints the pty's path (and makes PATH a link to it), then serves until stopped. This file
# is CPython: the unix port cannot open a pty itself (it has no openpty and no ffi here).
import argparse
import os
import signal
import subprocess
import sys
import tty


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--link", help="also make this path a symlink to the pty")
    parser.add_argument("--micropython", default="micropython", help="the unix port to run")
    args = parser.parse_args()

    master, slave = os.openpty()
    tty.setraw(slave)  # bytes go through untouched until the driver sets its own mode
    path = os.ttyname(slave)
    if args.link:
        if os.path.lexists(args.link):
            os.remove(args.link)
        os.symlink(path, args.link)
    sim = subprocess.Popen(
        [args.micropython, "-m", "busservo_sim"], stdin=master, stdout=master, close_fds=True
    )
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    print("busservo simulator on %s (Ctrl-C stops it)" % path, flush=True)
    try:
        sim.wait()  # the slave stays open here, so the pty lives while drivers come and go
    except KeyboardInterrupt:
        pass
    finally:
        sim.terminate()
        if args.link and os.path.islink(args.link):
            os.remove(args.link)
    return sim.wait()


if __name__ == "__main__":
    sys.exit(main())
