# The web panel as a board runs it, for tests/bench_web.py's heap figures: run on a unix port
# built for 32 bits (a board's object sizes) with -X heapsize=N, from a folder that holds the
# panel installed as mip installs it, and nothing else of this repository.
#
#   MICROPYPATH=.frozen:FOLDER micropython32 -X heapsize=64K tests/bench_web_board.py PORT
#
# The robot of examples/web_panel.py on a stand-in for the UART: a controller that takes
# moves and answers position and battery queries a 9600-baud line's time later (as small as
# a board's UART: the figure is the panel's). With "arm FILE" after PORT, the joints that
# FILE holds (an arm's, written by tests/bench_web.py: Robot.save() with links) instead, FILE
# the panel's calibration file: it jogs, and calibrates. It prints "serving" once it
# listens; with "watch" after PORT, it also prints "held N" each time the RAM in use,
# collected every 20 ms, is more than ever before.
import asyncio
import gc
import sys
import time

import busservo
import busservo_motion as bm
import busservo_web


class Line:
    # any/readinto/write, as busservo wants them; whole frames are written at a time.
    def __init__(self):
        self.out = b""  # what the controller has said
        self.due = 0  # ticks_ms when it has come down the line
        self.free = 0  # ticks_ms when what was written is in
        self.at = {}  # id: position

    def any(self):
        return len(self.out) if time.ticks_diff(time.ticks_ms(), self.due) >= 0 else 0

    def readinto(self, buf, n=None):
        n = min(self.any(), len(buf) if n is None else n)
        for i in range(n):
            buf[i] = self.out[i]
        self.out = self.out[n:]
        return n or None

    def write(self, buf, off=None, n=None):
        if n is None:
            off, n = 0, len(buf) if off is None else off
        now = time.ticks_ms()
        if time.ticks_diff(self.free, now) < 0:
            self.free = now
        self.free = time.ticks_add(self.free, n * 1042 // 1000 + 1)
        cmd = buf[off + 3]
        if cmd == busservo.CMD_SERVO_MOVE:
            for i in range(off + 7, off + n, 3):
                self.at[buf[i]] = buf[i + 1] | buf[i + 2] << 8
        elif cmd == busservo.CMD_MULT_SERVO_POS_READ:
            k = buf[off + 4]
            reply = bytearray((0x55, 0x55, 3 * k + 3, cmd, k))
            for i in range(off + 5, off + 5 + k):
                p = self.at.get(buf[i], 500)
                reply += bytes((buf[i], p & 0xFF, p >> 8))
            self.say(reply)
        elif cmd == busservo.CMD_GET_BATTERY_VOLTAGE:
            self.say(b"\x55\x55\x04\x0f\x4c\x1d")  # 7500 mV
        return n

    def say(self, reply):
        self.out += reply
        self.due = time.ticks_add(self.free, len(reply) * 1042 // 1000 + 1)


async def watch():
    most = 0
    while True:
        gc.collect()
        if gc.mem_alloc() > most:
            most = gc.mem_alloc()
            print("held", most)
        await asyncio.sleep_ms(20)


async def main(port, watching, path):
    robot = path and bm.Robot.load(busservo.BusServo(Line()), path)
    robot = robot or bm.Robot(
        busservo.BusServo(Line()),
        {
            "base": bm.Joint(1),
            "shoulder": bm.Joint(2, limits=(-90, 90)),
            "elbow": bm.Joint(3, limits=(-90, 90)),
            "claw": bm.Joint(4, limits=(0, 60)),
        },
    )
    if watching:
        asyncio.create_task(watch())
    server = asyncio.create_task(busservo_web.serve(robot, "bench-pw-32", port, path=path))
    await asyncio.sleep_ms(50)
    print("serving")
    await server


arm = "arm" in sys.argv and sys.argv[sys.argv.index("arm") + 1]
asyncio.run(main(int(sys.argv[1]), "watch" in sys.argv[2:], arm))
