# busservo_async: busservo for asyncio, so that waiting for the controller never
# stalls the other tasks of a robot.
#
#   import asyncio, busservo_async
#   bus = busservo_async.AsyncBusServo(uart)      # a UART, or a busservo.BusServo
#
#   bus.move(1, 800, 1000)                        # commands only write: no await
#   mv = await bus.read_battery()                 # queries await their reply
#   bus.run_group(8)
#   how = await bus.wait_group_done()             # CMD_ACTION_GROUP_COMPLETE or _STOP
#   async for cmd in bus.events():                # every frame, as poll() gives them
#       ...
#
# How it works. There is no background task: nothing to start or stop. A query
# runs the driver's own query (BusServo.ask(), a generator) a step every
# poll_ms, so the driver alone decides which reply answers it: one that
# matches (a position reply must carry the ids asked), never a late reply to
# an earlier query, cancelled or timed out (the next query lets it come, as an
# event, before it asks). Whichever task waits reads the frames that have come
# and hands each to whoever wants it: wait_group_done() sees the end of its
# group; every frame is held for events() and poll(), up to `queue` of them
# (more are counted in `lost`, not hidden).
#
# Queries are serialised: one request is on the bus at a time, and a second
# task's query waits for the first one's reply (or timeout) before it asks.
# A timeout raises OSError(ETIMEDOUT), as the blocking API does. Use this
# object's poll() and events(), not the BusServo's poll() or blocking queries,
# so that no frame goes past the waiting tasks.
import asyncio
import errno
import time

try:
    import micropython  # noqa: F401 (on a board; CPython has none)
except ImportError:  # CPython, on a computer: busservo_cpython gives what it lacks
    from busservo_cpython import asyncio, time

import busservo
from busservo import (
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_RUN,
    CMD_ACTION_GROUP_STOP,
)


class AsyncBusServo:
    def __init__(self, bus, poll_ms=5, queue=32):
        if not isinstance(bus, busservo.BusServo):
            bus = busservo.BusServo(bus)  # it was a UART
        self.bus = bus
        self.poll_ms = poll_ms  # at 9600 baud a byte takes about 1 ms
        self.lost = 0  # frames not held because `queue` were waiting already
        self._queue = queue
        self._held = []  # commands for events() and poll(), oldest first
        self._waiters = []  # wait_group_done()'s: [commands wanted, what came]
        # The group run_group() started: None (none), False (asked, its RUN not
        # seen yet: an end that comes now is an earlier group's), True (running),
        # or how it ended.
        self._run = None
        self._group = None  # (group, times) of the run run_group() started
        self._asking = asyncio.Lock()  # one query on the bus at a time

    def __getattr__(self, name):
        # The commands (they only write, so they never block) and the state
        # (running, group, times, battery, positions, noise, wire_ms()) are the
        # BusServo's.
        return getattr(self.bus, name)

    # Queries.

    async def read_battery(self, timeout_ms=100):
        """Battery voltage in mV."""
        async with self._asking:
            await self._ask(None, timeout_ms)
            return self.bus.battery

    async def read_positions(self, ids, timeout_ms=None):
        """{servo_id: position} for 1..84 servos; the default timeout is 100 ms
        plus 10 ms per servo."""
        async with self._asking:
            await self._ask(ids, timeout_ms)
            positions = self.bus.positions
            return {servo_id: positions[servo_id] for servo_id in ids}

    async def _ask(self, ids, timeout_ms):
        # The driver's query (ask(): it checks its arguments first), a step every poll_ms;
        # under _asking, held by the caller until it has read the answer.
        for _ in self.bus.ask(ids, timeout_ms):
            await asyncio.sleep_ms(self.poll_ms)

    def run_group(self, group, times=1):
        """As BusServo.run_group()."""
        self._dispatch()  # frames already in are earlier runs'
        self.bus.run_group(group, times)
        self._run = False  # an end before its RUN comes back is an earlier group's
        self._group = (group, times)  # its RUN comes back with both, as sent

    async def wait_group_done(self, timeout_ms=None):
        """Wait for the action group the last run_group() started to end (or,
        with none started, the running one): CMD_ACTION_GROUP_COMPLETE if it ran
        its course, CMD_ACTION_GROUP_STOP if it was stopped. timeout_ms=None
        waits as long as it takes. If it ended already (while another task
        awaited, say), this returns at once."""
        if timeout_ms is not None and (type(timeout_ms) is not int or timeout_ms < 0):
            raise (ValueError if type(timeout_ms) is int else TypeError)(
                "timeout_ms must be None or an int >= 0, got %r" % (timeout_ms,)
            )
        self._dispatch()
        if self._run is not None and self._run is not False and self._run is not True:
            return self._run
        wanted = (CMD_ACTION_GROUP_COMPLETE, CMD_ACTION_GROUP_STOP)
        return await self._wait(wanted, timeout_ms)

    # Frames.

    def poll(self):
        """As BusServo.poll(): the oldest frame's command, or None. Never blocks."""
        self._dispatch()
        return self._held.pop(0) if self._held else None

    def events(self):
        """`async for cmd in bus.events():` every frame's command, in order."""
        return self

    def __aiter__(self):
        return self

    async def __anext__(self):
        while True:
            cmd = self.poll()
            if cmd is not None:
                return cmd
            await asyncio.sleep_ms(self.poll_ms)

    async def _wait(self, wanted, timeout_ms):
        waiter = [wanted, None]
        self._waiters.append(waiter)
        start = time.ticks_ms()
        try:
            while True:
                self._dispatch()
                if waiter[1] is not None:
                    return waiter[1]
                if (
                    timeout_ms is not None
                    and time.ticks_diff(time.ticks_ms(), start) >= timeout_ms
                ):
                    raise OSError(errno.ETIMEDOUT, "the group did not end in time")
                await asyncio.sleep_ms(self.poll_ms)
        finally:
            self._waiters.remove(waiter)

    def _dispatch(self):
        # Hand every frame that has come to whoever waits for it, oldest first.
        # While a query runs, it alone decodes (so that its reply cannot become
        # an event); the frames it holds back come here once it is done.
        if self._asking.locked():
            return
        bus = self.bus
        while True:
            cmd = bus.poll()
            if cmd is None:
                return
            end = cmd == CMD_ACTION_GROUP_COMPLETE or cmd == CMD_ACTION_GROUP_STOP
            ours = (bus.group, bus.times) == self._group  # the frame's group and times
            if cmd == CMD_ACTION_GROUP_RUN and self._run is False and ours:
                self._run = True  # the group run_group() started has started
            elif end and (
                self._run is True
                # its RUN lost on the line: its COMPLETE still names it
                or self._run is False
                and cmd == CMD_ACTION_GROUP_COMPLETE
                and ours
            ):
                self._run = cmd
            for waiter in self._waiters:
                # A group's end, unless it is an earlier group's. It is still
                # held below: wait_group_done() looks, it does not take.
                if waiter[1] is None and cmd in waiter[0] and self._run is not False:
                    waiter[1] = cmd
            if len(self._held) < self._queue:
                self._held.append(cmd)
            else:
                self.lost += 1
