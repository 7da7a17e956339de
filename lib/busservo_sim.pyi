"""busservo_sim: a simulated Bus Servo Controller, for trying busservo with no controller
wired (at a board's REPL, or on the unix port).

    import busservo, busservo_sim
    sim = busservo_sim.SimController()
    bus = busservo.BusServo(sim)    # sim has machine.UART's any/read/readinto/write

It decodes what the driver writes and answers as the protocol says:
- servos move linearly from where they are to their target over time_ms, so a position read
  mid-move gives the value in between (servos start at CENTER, 500);
- a servo turns 0..LIMIT (1000) only: a target beyond it stops at LIMIT, as a real servo
  stops at its limit, and counts one `clamped` (the ids in `pwm` are PWM servos of an LSC
  board instead, up to PWM_LIMIT, 2500 us);
- action groups (`groups`, {group: ms per run}) run `times` times or forever, sending RUN as
  they start, COMPLETE as they end, STOP when stopped (by a STOP command, or by a RUN of
  another group);
- ACTION_GROUP_SPEED scales a group's durations (ALL_GROUPS: every group); power_cycle()
  forgets it, as the controller does at power-off;
- unload lets servos go limp where they are (`limp`) until they are moved, and
  turn(servo_id, position) is a person's hand: it turns a limp servo there at once (True); a
  servo under power holds where it is (False);
- a servo in `missing` does not answer: a position read gives 65535 for it, as a controller
  does for a servo unpowered or not on the bus (the driver reads it as None);
- the battery reads `battery` mV;
- a malformed frame counts one `beeps` (the controller's "beep beep");
- it is at the far end of a 9600-baud line (10 bits a byte): a frame written to it is in once
  its last byte would have arrived, and what it says comes out a byte every 1.04 ms behind
  what it said before, so a reply comes no sooner than on a real wire (baudrate=None: no
  line, every byte at once, for a test world that models the line itself).
Setting `silent` makes it answer nothing at all, as a controller with its TX unplugged; so
does the frame 55 55 03 F0 01 (F0 00 undoes it), which a real controller would beep at.
"""

from typing import Callable, Final, Mapping, Protocol

SIM_SILENT: Final = 0xF0
"""The simulator's own command: Prm 1 = 1 silent, 0 talking."""
GROUPS: dict[int, int]
"""The default action groups, {group: ms per run}: {0: 1000, 1: 500, 2: 2000, 8: 1500}."""
CENTER: Final = 500
"""Where a servo starts."""
LIMIT: Final = 1000
PWM_LIMIT: Final = 2500
"""The far end of a servo's range, 0..1000: a move beyond it stops there."""

class SimController:
    """The simulated controller. It is a UART to the driver: busservo.BusServo(SimController())."""

    groups: dict[int, int]
    """The action groups it knows, {group: ms per run}; a RUN of another one beeps."""
    battery: int
    """What a battery query reads, in mV."""
    silent: bool
    """True: it answers nothing at all, as a controller with its TX unplugged."""
    beeps: int
    """Malformed frames seen (the controller's "beep beep")."""
    clamped: int
    """Move targets beyond LIMIT, each stopped at LIMIT (a servo turns 0..1000 only), or for
    a PWM servo beyond PWM_LIMIT."""
    pwm: set[int]
    """The ids of PWM servos (an LSC board's, 500..2500 us): they turn up to PWM_LIMIT."""
    limp: set[int]
    """The servos unloaded (limp) since they last moved."""
    missing: set[int]
    """The ids of servos that do not answer: a position read gives 65535 for each."""

    def __init__(
        self,
        groups: Mapping[int, int] | None = None,
        battery: int = 7500,
        ticks_ms: Callable[[], int] = ...,
        baudrate: int | None = 9600,
    ) -> None:
        """groups: {group: ms per run} (None: GROUPS); battery in mV. Time comes from
        time.ticks_ms(), or from the ticks_ms function given, which a test can step.
        baudrate: the line's, which paces what goes in and out (None: no line)."""
    def power_cycle(self) -> None:
        """Power off and on: groups stop (silently) and speeds are forgotten."""
    def position(self, servo_id: int) -> int:
        """Where servo_id is now."""
    def turn(self, servo_id: int, position: int) -> bool:
        """Turn servo_id by hand to position (0..LIMIT; a PWM servo's, 0..PWM_LIMIT), as a
        person does, for tests of calibration and teaching: a limp servo (in `limp`) is there
        at once, and stays limp: True. A servo under power holds where it is: False. A
        position out of range raises ValueError. (A PWM servo turns here too; a real one has
        no wire to tell the controller where a hand put it.)"""
    def speed(self, group: int) -> int:
        """The group's speed in percent."""
    @property
    def running(self) -> int | None:
        """The group running now, or None."""
    # machine.UART's methods, as the driver sees them.
    def any(self) -> int:
        """How many bytes of what it answered have come down the line and are not read yet."""
    def readinto(self, buf: bytearray | memoryview, nbytes: int | None = None) -> int | None:
        """Read at most nbytes (default len(buf)) into buf: how many, or None for none."""
    def read(self, nbytes: int | None = None) -> bytes | None:
        """At most nbytes of what it answered (default all), or None for none."""
    def write(
        self, buf: bytes | bytearray, off: int | None = None, nbytes: int | None = None
    ) -> int:
        """The stream protocol's forms: write(buf), write(buf, n), write(buf, off, n). Takes
        it all and answers what it completes; returns how many bytes it took."""

class _StreamIn(Protocol):
    def readinto(self, buf: bytearray, n: int, /) -> int | None: ...

class _StreamOut(Protocol):
    def write(self, buf: bytes, /) -> int | None: ...

def uart() -> SimController:
    """A board file's uart(), for when there is no board: the simulated controller."""

def serve(stream_in: _StreamIn, stream_out: _StreamOut) -> None:
    """Be the controller on a byte stream: what stream_in brings is written to a
    SimController, what it answers goes to stream_out. Runs until stream_in ends. stream_in
    must be a stream select.poll() can wait on (sys.stdin.buffer, say)."""
