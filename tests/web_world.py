# The web panel on the wire-faithful world, live: lib/busservo_web.py serving the
# robot of examples/web_panel.py, whose controller is the simulated one at the far
# end of an rp2's UART and a 9600-baud line (tests/wire.py), on real time. The
# browser tests (tests/browser.py) and the benchmark (tests/bench_web.py) use it.
#
#   sh boards/unix.sh tests/web_world.py --port 8080 --password secret-pw --probe 8081
#
# --probe N also serves, on port N, what only the controller knows: each servo's
# position and which are limp, as JSON (GET anything). It prints "serving" once
# both listen. GET /turn/ID/POSITION (more pairs may follow) on it turns those servos by
# hand first, if they are limp. --calibration PATH: the robot of that file, and the
# panel's calibration file (an arm's links, and where its calibration page saves). --leader:
# the program gives the panel a leader arm (the same joints on servos 11..14, on the same
# bus), which the page turns on and off (its teleop).
import asyncio
import json
import sys

import busservo
import busservo_board
import busservo_motion as bm
import busservo_web
import wire

sys.path.append("examples")


def robot(world):
    """The arm of examples/web_panel.py, on world's UART and clock."""
    busservo.time = bm.time = world.clock
    return bm.Robot(busservo.BusServo(world.uart), busservo_board.joints())


class Moves:
    """A world's on_frame: counts the CMD_SERVO_MOVE frames the controller took and
    keeps the last MOVES of them, so that a probe costs the same after hours; and counts
    the positions requests (reads)."""

    MOVES = 20

    def __init__(self):
        self.count = 0
        self.reads = 0
        self._last = [None] * self.MOVES

    def __call__(self, us, frame):
        if frame[3] == busservo.CMD_SERVO_MOVE:
            self._last[self.count % self.MOVES] = frame
            self.count += 1
        elif frame[3] == busservo.CMD_MULT_SERVO_POS_READ:
            self.reads += 1

    def last(self):
        """The last MOVES moves, oldest first, as [time_ms, {id: position}]."""
        n = self.count
        frames = [self._last[i % self.MOVES] for i in range(max(0, n - self.MOVES), n)]
        return [
            [f[5] | f[6] << 8, {f[i]: f[i + 1] | f[i + 2] << 8 for i in range(7, len(f), 3)}]
            for f in frames
        ]


def live(port="rp2"):
    """A world on real time: its clock, UART, line and controller; its on_frame
    counts the moves (Moves)."""
    world = wire.World(port, clock=wire.RealClock(), call_us=0, cost_us=0)
    world.on_frame = Moves()
    return world


def controller(world):
    """What the controller knows: {"at": {id: position}, "limp": [ids], "moved": how many
    CMD_SERVO_MOVE it took, "moves": the last 20 of them as [time_ms, {id: position}],
    "reads": how many positions requests it took}."""
    sim = world.sim
    moves = world.on_frame
    return {
        "at": {i: sim.position(i) for i in (1, 2, 3, 4)},
        "limp": sorted(sim.limp),
        "moved": moves.count,
        "moves": moves.last(),
        "reads": moves.reads,
    }


async def http(port, method, path, body=None, token=None, raw=None):
    """One request to 127.0.0.1:port: (status, parsed JSON or the raw bytes). body is
    sent as JSON; raw, if given, is sent as the body as it is."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        data = raw if raw is not None else b"" if body is None else json.dumps(body).encode()
        head = "%s %s HTTP/1.0\r\nHost: 127.0.0.1\r\n" % (method, path)
        if token:
            head += "Authorization: Bearer %s\r\n" % token
        if data or method == "POST":
            head += "Content-Type: application/json\r\nContent-Length: %d\r\n" % len(data)
        await writer.awrite(head.encode() + b"\r\n" + data)
        reply = b""
        while True:
            try:
                part = await reader.read(1024)
            except OSError:  # reset: the server closed with our body unread
                break
            if not part:
                break
            reply += part
    finally:
        await writer.aclose()
    head, _, content = reply.partition(b"\r\n\r\n")
    status = int(head.split()[1]) if head else 0
    try:
        return status, json.loads(content)
    except ValueError:
        return status, content


async def login(port, password="secret-pw"):
    status, reply = await http(port, "POST", "/api/login", {"password": password})
    assert status == 200, (status, reply)
    return reply["token"]


async def probe(world, port):
    async def answer(reader, writer):
        try:
            line = await reader.readline()
            while (await reader.readline()).strip():
                pass  # the request's lines, read: closing with them unread would reset
            turn = line.split()[1].split(b"/") if line.startswith(b"GET /turn/") else ()
            for i in range(2, len(turn) - 1, 2):  # GET /turn/ID/POSITION/...: hands
                world.sim.turn(int(turn[i]), int(turn[i + 1]))
            body = json.dumps(controller(world)).encode()
            await writer.awrite(
                b"HTTP/1.0 200 OK\r\nContent-Type: application/json\r\n\r\n" + body
            )
        finally:
            await writer.aclose()

    return await asyncio.start_server(answer, "127.0.0.1", port)


def leader(bus):
    """A leader arm on bus: the joints of robot(), on servos 11..14."""
    joints = busservo_board.joints()
    return bm.Robot(
        bus, {n: bm.Joint(j.servo_id + 10, limits=j.limits) for n, j in joints.items()}
    )


async def main(port, password, probe_port, path, lead=False):
    world = live()
    arm = robot(world)
    if path:  # a calibration file: its joints (and links: an arm to jog)
        arm = bm.Robot.load(arm.bus, path)
    if probe_port:
        await probe(world, probe_port)
    options = {"leader": leader(arm.bus)} if lead else {}
    server = asyncio.create_task(
        busservo_web.serve(arm, password, port, path=path or "robot.json", **options)
    )
    await asyncio.sleep_ms(100)
    print("serving", port, flush=True) if hasattr(print, "flush") else print("serving", port)
    await server


if __name__ == "__main__":
    args = sys.argv[1:]

    def option(name, default):
        return args[args.index(name) + 1] if name in args else default

    asyncio.run(
        main(
            int(option("--port", 8080)),
            option("--password", "secret-pw"),
            int(option("--probe", 0)),
            option("--calibration", None),
            "--leader" in args,
        )
    )
