"""busservo: MicroPython driver for the serial Bus Servo Controller (LOBOT/Hiwonder-style
boards, frames that start 0x55 0x55, 9600 baud).

One small module speaks the whole protocol: it moves servos, runs action groups, reads
positions and the battery. It never allocates in a control loop's hot path, and its poll()
never blocks.

    import busservo
    from machine import UART

    bus = busservo.BusServo(UART(2, 9600, tx=17, rx=16))   # or any object with any/readinto/write
    bus.move(1, 800, 1000)          # servo 1 to position 800 within 1000 ms
    bus.read_battery()              # 7500 (mV); raises OSError(ETIMEDOUT) with no reply

Every frame on the wire, in both directions, is 0x55 0x55 Length Cmd Prm 1 ... Prm N, with
Length = N + 2; 16-bit values travel low byte first. There is no checksum and no request
number.
"""

from typing import Collection, Final, Iterator, Protocol, Sequence

CMD_SERVO_MOVE: Final = 3
"""The command of move() and move_many()."""
CMD_ACTION_GROUP_RUN: Final = 6
"""An action group has started (from run_group()); poll() returns it."""
CMD_ACTION_GROUP_STOP: Final = 7
"""An action group was stopped (by stop_group(), or by a RUN of another); poll() returns it."""
CMD_ACTION_GROUP_COMPLETE: Final = 8
"""An action group has run its course; poll() returns it."""
CMD_ACTION_GROUP_SPEED: Final = 11
"""The command of set_group_speed()."""
CMD_GET_BATTERY_VOLTAGE: Final = 15
"""The battery's voltage: the command of request_battery(), and of its reply."""
CMD_MULT_SERVO_UNLOAD: Final = 20
"""The command of unload()."""
CMD_MULT_SERVO_POS_READ: Final = 21
"""Servo positions: the command of request_positions(), and of its reply."""
ALL_GROUPS: Final = 0xFF
"""set_group_speed(ALL_GROUPS, percent): every downloaded action group."""

class _UART(Protocol):
    """What BusServo needs of a UART: machine.UART has it, so has busservo_sim.SimController.
    (Not a name of the module: for type checkers only.)"""

    def any(self) -> int:
        """How many bytes are waiting to be read."""
    def readinto(self, buf: bytearray, n: int, /) -> int | None:
        """Read at most n bytes into buf: how many came, or None (or 0) for none."""
    def write(self, buf: bytearray, off: int = ..., n: int = ..., /) -> int | None:
        """The stream protocol's write(buf), write(buf, n) and write(buf, off, n): how many
        bytes the UART took (it may take only part), or None if it took none."""

class BusServo:
    """The Bus Servo Controller on a UART.

    Commands (move, move_many, run_group, stop_group, set_group_speed, unload,
    request_battery, request_positions) check every argument first: bad input raises
    ValueError or TypeError naming the argument, its range and what came, and nothing is
    written. Ranges are what the wire carries: ids and groups 0..255; positions, times,
    repeat counts and percentages 0..65535; 1..83 servos a move, 1..252 ids an unload, 1..84
    a position read; timeouts 0..60000 ms.

    Every frame leaves whole, or the call raises: the driver writes what the UART did not
    take as the wire makes room, so a call waits for the wire as long as it must. If the
    UART takes nothing for the wire time plus 50 ms (a stuck or unplugged UART), the call
    raises OSError(EIO); if part of the frame had gone, the next command first sends the
    rest of it.

    One context at a time may call it: your main loop, or asyncio tasks through
    busservo_async. Never a hard interrupt handler.
    """

    running: bool
    """An action group runs: RUN seen, no STOP or COMPLETE since."""
    group: int | None
    """The action group of the last RUN or COMPLETE (None before any)."""
    times: int
    """How many times the group of the last RUN or COMPLETE runs (0: forever)."""
    battery: int | None
    """The battery's voltage in mV, as last read, or None."""
    positions: dict[int, int | None]
    """{servo_id: position}, as last read, updated in place. Signed: a servo near 0 may
    report a few units below it. None: the servo did not answer (the controller read 65535,
    as it does for a servo unpowered or not on the bus; a servo truly at -1 reads so too)."""
    noise: int
    """Bytes read that were no frame of the controller's: a count for diagnosis."""
    lost: int
    """Frames dropped because more than 32 came in during one query without a poll(): never
    expected at 9600 baud, but counted rather than hidden."""
    early: int
    """Replies taken for answers that came sooner than the wire at baudrate allows: 0 with a
    controller at the speed baudrate says. Growing: the peer is faster (a controller set to
    another speed, one on USB HID, a fake or simulator that answers at once). Nothing is
    wrong with that; the driver only cannot tell a late reply from a fast one then."""

    def __init__(self, uart: _UART, baudrate: int = 9600) -> None:
        """The controller on uart: machine.UART(..., 9600), or any object with any(),
        readinto(buf, n) and the stream protocol's write(buf), write(buf, n) and
        write(buf, off, n), such as busservo_sim.SimController().

        baudrate (1200..1000000) is the UART's: a byte takes 10 bits (1.04 ms at 9600
        baud), so the driver knows when what it wrote will have left the wire. It does not
        set the UART's rate. Raises ValueError or TypeError for a bad baudrate, and
        TypeError for a uart without any(), readinto() and write() (a path, say:
        boards/unix.py's uart(path) opens one on the unix port).

        Two attributes of uart, both optional, say how its bytes come (a computer's ports
        have them; a board's UART has neither): latency_ms, how much later than the wire a
        byte may reach the program (an int in 0..60000: a USB-serial chip's hand-overs and a
        busy computer's delay; None: at any pace, a pty), which the driver's timing counts;
        and wait(ms), which waits in the OS until bytes come or ms pass, and which a blocking
        query calls between its looks at the UART, so that it costs no CPU. Raises
        ValueError or TypeError naming uart.latency_ms for any other latency_ms."""
    # Commands. Each checks all its arguments before it writes anything.
    def move(self, servo_id: int, position: int, time_ms: int) -> None:
        """CMD_SERVO_MOVE: move one servo to position within time_ms.

        servo_id 0..255, position 0..65535, time_ms 0..65535. Raises ValueError or TypeError
        (nothing is written) for a bad argument, and OSError(EIO) if the UART takes
        nothing."""
    def move_many(
        self, servos: Collection[tuple[int, int]] | dict[int, int], time_ms: int
    ) -> None:
        """CMD_SERVO_MOVE: move 1..83 servos, given as (id, position) pairs or a dict
        {id: position}, together within time_ms.

        ids 0..255, positions 0..65535, time_ms 0..65535. Raises ValueError or TypeError
        (nothing is written) for a bad argument, and OSError(EIO) if the UART takes
        nothing."""
    def run_group(self, group: int, times: int = 1) -> None:
        """CMD_ACTION_GROUP_RUN: run action group `group` `times` times; 0 = forever.

        group 0..255, times 0..65535. The controller answers with CMD_ACTION_GROUP_RUN, then
        CMD_ACTION_GROUP_COMPLETE (or _STOP), which poll() returns. Raises ValueError or
        TypeError for a bad argument, and OSError(EIO) if the UART takes nothing."""
    def stop_group(self) -> None:
        """CMD_ACTION_GROUP_STOP: stop the running action group, if any.

        Raises OSError(EIO) if the UART takes nothing."""
    def set_group_speed(self, group: int, percent: int) -> None:
        """CMD_ACTION_GROUP_SPEED: run `group` (ALL_GROUPS for all) at percent %.
        The controller forgets this at power-off.

        group 0..255, percent 0..65535. Raises ValueError or TypeError for a bad argument,
        and OSError(EIO) if the UART takes nothing."""
    def unload(self, ids: Collection[int]) -> None:
        """CMD_MULT_SERVO_UNLOAD: let 1..252 servos go limp (the next move gives them their
        holding torque back).

        ids 0..255. Raises ValueError or TypeError for bad ids, and OSError(EIO) if the UART
        takes nothing."""
    def request_battery(self) -> None:
        """CMD_GET_BATTERY_VOLTAGE: ask for the voltage; the reply comes through poll()
        (CMD_GET_BATTERY_VOLTAGE, then battery holds it). For loops that cannot wait at all.

        Raises OSError(EIO) if the UART takes nothing."""
    def request_positions(self, ids: Sequence[int]) -> None:
        """CMD_MULT_SERVO_POS_READ: ask for 1..84 positions (the reply must fit in a Length
        byte); the reply comes through poll() (CMD_MULT_SERVO_POS_READ, then positions holds
        them). For loops that cannot wait at all.

        ids 0..255. Raises ValueError or TypeError for bad ids, and OSError(EIO) if the UART
        takes nothing."""
    # The wire.
    def wire_ms(self) -> int:
        """How many ms of what was written are still ahead on the wire (0 when idle). A
        query's timeout counts from when its request has left it; a control loop that sends
        only when wire_ms() is small never waits for the UART."""
    # Queries.
    def read_battery(self, timeout_ms: int = 100) -> int:
        """Battery voltage in mV. Raises OSError(ETIMEDOUT) if no reply comes within
        timeout_ms (0..60000) of the request leaving the wire (and uart.latency_ms more).
        Its words say what came meanwhile: "no reply" when nothing did, "no reply: 6 bytes
        came, 6 of them noise" when bytes did (another baud rate, another program).

        Replies to earlier requests of its kind (request_battery(), a query that timed out)
        come first, as events: it lets them come, for as long as it would wait for its own
        reply and 100 ms more, before it asks (for those a query gave up on already, within
        the last second: while replies keep coming). A reply that comes sooner than the
        wire allows (this request still on the wire, or the reply's own bytes not yet come)
        answers it when nothing else can: no request of its kind was given up on (a peer
        faster than baudrate: counted in early). While one was, such a reply is taken for
        that one's late reply, unless this query's own never comes: then it was this
        query's (one query waits out its timeout). A late one that lands just when the
        answer could is taken for it, once. Frames that come in meanwhile are applied to the
        state at once and returned by the next poll() calls. Raises ValueError or TypeError
        for a bad timeout_ms (before anything is written), and OSError(EIO) if the UART
        takes nothing. OSError's errno is errno.ETIMEDOUT on CPython too."""
    def read_positions(
        self, ids: Sequence[int], timeout_ms: int | None = None
    ) -> dict[int, int | None]:
        """{servo_id: position} for 1..84 servos; positions are signed (a servo near 0 may
        say -3), None for a servo that did not answer (unpowered, not on the bus). Raises
        OSError(ETIMEDOUT) if no reply comes; the default timeout is 100 ms plus 10 ms per
        servo (timeout_ms 0..60000), counted from when the request has left the wire. Only a
        reply that carries exactly these ids, in this order, answers it.

        Raises ValueError or TypeError for bad ids or timeout_ms, and OSError(EIO) if the
        UART takes nothing."""
    def ask(
        self, ids: Sequence[int] | None = None, timeout_ms: int | None = None, again: bool = False
    ) -> Iterator[bool | None]:
        """A query step by step, for a scheduler such as busservo_async: a generator that
        asks for the battery (ids None) or for the positions of ids, yields while it waits,
        and ends once the reply has come (then battery or positions hold it). It raises as
        read_battery() does.

        With again, it asks again and again, for a loop that reads for ever: it yields None
        while it waits, then True once the reply has come, or False once none came in time
        (it does not raise), and its next step asks anew. Made once, it takes no heap a read.

        timeout_ms=None is 100 ms for the battery, 100 ms plus 10 ms per servo for
        positions."""
    # Frames from the controller.
    def poll(self) -> int | None:
        """Return the command byte of the oldest frame not returned yet, after applying it
        to the state, or None. Never blocks; one frame per call.

        With nothing waiting it costs one uart.any() and little more. It reads what the UART
        holds (up to about 1 KB a call) before it says None. A positions reply comes only
        to a request: one that no request in flight asked for (none, or not that many ids)
        is noise."""
