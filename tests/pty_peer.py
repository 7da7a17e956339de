# A controller on a pty that answers at once, as a simulator a user writes does (or a
# controller at another speed, or a socat loopback to one): no line, no pacing. CPython (the
# unix port opens no pty):
#
#   .venv/bin/python tests/pty_peer.py LINK [SECONDS]
#
# makes LINK a symlink to the pty, answers the battery (7500 mV) and positions (every servo
# at 500) the moment a request's last byte is in, and ends after SECONDS (20) or when killed.
import os
import sys
import time
import tty


def main(link, seconds=20.0):
    master, slave = os.openpty()
    tty.setraw(slave)
    os.symlink(os.ttyname(slave), link)
    end = time.monotonic() + seconds
    got = bytearray()
    try:
        while time.monotonic() < end:
            try:
                got += os.read(master, 256)
            except BlockingIOError:
                pass
            while len(got) >= 4:
                if got[0] != 0x55 or got[1] != 0x55:
                    del got[0]
                    continue
                size = got[2] + 2
                if len(got) < size:
                    break
                frame, got[:size] = bytes(got[:size]), b""
                if frame[3] == 0x0F:
                    os.write(master, bytes((0x55, 0x55, 0x04, 0x0F, 0x4C, 0x1D)))
                elif frame[3] == 0x15:
                    reply = bytearray((0x55, 0x55, 3 * frame[4] + 3, 0x15, frame[4]))
                    for servo_id in frame[5:]:
                        reply += bytes((servo_id, 0xF4, 0x01))
                    os.write(master, reply)
    finally:
        os.remove(link)


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else 20.0)
