# A STAND-IN for lib/busservo_motion.py, for developing tests/bench_motion.py only,
# until the real module is merged (then this file goes). The same API, the least of it:
#
#   arm = Robot(bus, {"j1": Joint(1), ...})   # Joint(id): degrees -120..120 -> 0..1000
#   arm.stream({"j1": deg, ...})              # keeps the latest targets only
#   arm.step()                                # one move_many() when the wire is nearly free
#
# step() sends when bus.wire_ms() is at most one frame's time: the frame then waits
# behind at most one other, and the UART never makes the call wait.


class Joint:
    def __init__(self, servo_id):
        self.id = servo_id

    def position(self, deg):
        deg = min(120, max(-120, deg))
        return 500 + int(round(deg * 500 / 120))


class Robot:
    def __init__(self, bus, joints, time_ms=20):
        self.bus = bus
        self.joints = joints
        self.time_ms = time_ms
        self._latest = {}
        self._new = False
        # One move_many frame: 3 bytes a servo and 7 more, 10 bits a byte, at 9600 baud.
        self._frame_ms = (3 * len(joints) + 7) * 10000 // 9600 + 1

    def stream(self, targets):
        self._latest.update(targets)
        self._new = True

    def step(self):
        if not self._new or self.bus.wire_ms() > self._frame_ms:
            return False
        pairs = [(self.joints[n].id, self.joints[n].position(d)) for n, d in self._latest.items()]
        self.bus.move_many(pairs, self.time_ms)
        self._new = False
        return True
