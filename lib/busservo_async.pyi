"""busservo_async: busservo for asyncio, so that waiting for the controller never stalls the
other tasks of a robot.

    import asyncio, busservo_async
    bus = busservo_async.AsyncBusServo(uart)      # a UART, or a busservo.BusServo

    bus.move(1, 800, 1000)                        # commands only write: no await
    mv = await bus.read_battery()                 # queries await their reply
    bus.run_group(8)
    how = await bus.wait_group_done()             # CMD_ACTION_GROUP_COMPLETE or _STOP
    async for cmd in bus.events():                # every frame, as poll() gives them
        ...

There is no background task: nothing to start or stop. A query runs the driver's own query
(BusServo.ask()) a step every poll_ms, so the driver alone decides which reply answers it.
Queries are serialised: one request is on the bus at a time, and a second task's query waits
for the first one's reply (or timeout) before it asks. A timeout raises OSError(ETIMEDOUT),
as the blocking API does. Use this object's poll() and events(), not the BusServo's poll() or
blocking queries, so that no frame goes past the waiting tasks.
"""

from typing import AsyncIterator, Collection, Sequence

from busservo import _UART, BusServo

class AsyncBusServo:
    """A BusServo for asyncio tasks. Commands and state are the BusServo's (forwarded to
    `bus`); queries, poll(), events() and wait_group_done() are this object's own."""

    bus: BusServo
    """The BusServo this object drives."""
    poll_ms: int
    """How often (ms) a waiting task looks at the UART: at 9600 baud a byte takes about
    1 ms."""
    lost: int
    """Frames not held for events() and poll() because `queue` were waiting already
    (bus.lost counts the driver's own)."""

    def __init__(self, bus: BusServo | _UART, poll_ms: int = 5, queue: int = 32) -> None:
        """bus: a busservo.BusServo, or a UART to make one on (BusServo(uart), 9600 baud).
        Up to `queue` frames are held for events() and poll(); more are counted in lost."""
    # Queries.
    async def read_battery(self, timeout_ms: int = 100) -> int:
        """Battery voltage in mV. Other tasks run while it waits. Raises OSError(ETIMEDOUT)
        if no reply comes within timeout_ms (0..60000) of the request leaving the wire; a
        bad timeout_ms raises ValueError or TypeError before anything is written."""
    async def read_positions(
        self, ids: Sequence[int], timeout_ms: int | None = None
    ) -> dict[int, int | None]:
        """{servo_id: position} for 1..84 servos (None: the servo did not answer); the default
        timeout is 100 ms plus 10 ms per servo. Other tasks run while it waits. Raises
        OSError(ETIMEDOUT) if no reply comes; bad ids or timeout_ms raise ValueError or
        TypeError before anything is written."""
    def run_group(self, group: int, times: int = 1) -> None:
        """As BusServo.run_group(): run action group `group` (0..255) `times` (0..65535)
        times; 0 = forever. wait_group_done() then waits for this group's end."""
    async def wait_group_done(self, timeout_ms: int | None = None) -> int:
        """Wait for the action group the last run_group() started to end (or, with none
        started, the running one): CMD_ACTION_GROUP_COMPLETE if it ran its course,
        CMD_ACTION_GROUP_STOP if it was stopped. timeout_ms=None waits as long as it takes;
        past timeout_ms it raises OSError(ETIMEDOUT). If it ended already (while another
        task awaited, say), this returns at once. A timeout_ms that is not None or an
        int >= 0 raises ValueError or TypeError."""
    # Frames.
    def poll(self) -> int | None:
        """As BusServo.poll(): the oldest frame's command, or None. Never blocks."""
    def events(self) -> AsyncIterator[int]:
        """`async for cmd in bus.events():` every frame's command, in order."""
    # The BusServo's commands and state, forwarded to `bus`.
    def move(self, servo_id: int, position: int, time_ms: int) -> None:
        """As BusServo.move(): servo servo_id (0..255) to position (0..65535) within time_ms
        (0..65535). Only writes: no await."""
    def move_many(
        self, servos: Collection[tuple[int, int]] | dict[int, int], time_ms: int
    ) -> None:
        """As BusServo.move_many(): 1..83 servos, given as (id, position) pairs or a dict
        {id: position}, together within time_ms. Only writes: no await."""
    def stop_group(self) -> None:
        """As BusServo.stop_group(): stop the running action group, if any."""
    def set_group_speed(self, group: int, percent: int) -> None:
        """As BusServo.set_group_speed(): run `group` (ALL_GROUPS for all) at percent %."""
    def unload(self, ids: Collection[int]) -> None:
        """As BusServo.unload(): let 1..252 servos go limp."""
    def request_battery(self) -> None:
        """As BusServo.request_battery(): the reply comes through poll() and events()."""
    def request_positions(self, ids: Sequence[int]) -> None:
        """As BusServo.request_positions(): the reply comes through poll() and events()."""
    def wire_ms(self) -> int:
        """As BusServo.wire_ms(): ms of written bytes still ahead on the wire (0: idle)."""
    @property
    def running(self) -> bool:
        """BusServo.running: an action group runs (RUN seen, no STOP or COMPLETE since)."""
    @property
    def group(self) -> int | None:
        """BusServo.group: the action group of the last RUN or COMPLETE."""
    @property
    def times(self) -> int:
        """BusServo.times: how many times the group of the last RUN or COMPLETE runs."""
    @property
    def battery(self) -> int | None:
        """BusServo.battery: the battery's voltage in mV, as last read, or None."""
    @property
    def positions(self) -> dict[int, int | None]:
        """BusServo.positions: {servo_id: position}, as last read."""
    @property
    def noise(self) -> int:
        """BusServo.noise: bytes read that were no frame of the controller's."""
    @property
    def early(self) -> int:
        """BusServo.early: replies taken that came sooner than the wire at its baudrate
        allows (a peer faster than that)."""
