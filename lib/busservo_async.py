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
# How it works. Whichever task is waiting reads the frames that have come (no
# background task: nothing to start or stop), every poll_ms, and hands each to
# whoever wants it: a query takes its own reply; wait_group_done() sees the end
# of a group; every other frame, the group's end included, is held for events()
# and poll(), up to `queue` of them (more are counted in `lost`, not hidden).
#
# Queries are serialised: one request is on the bus at a time, and a second
# task's query waits for the first one's reply (or timeout) before it asks.
# The protocol numbers no requests, so this is how a reply is known to be the
# answer to the request just made. A timeout raises OSError(ETIMEDOUT), as the
# blocking API does. Use this object's poll() and events(), not the BusServo's
# poll() or blocking queries, so that no frame goes past the waiting tasks.
import asyncio
import errno
import time

import busservo
from busservo import (
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_STOP,
    CMD_GET_BATTERY_VOLTAGE,
    CMD_MULT_SERVO_POS_READ,
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
        self._waiters = []  # [commands wanted, takes the frame?, what came]
        self._ended = None  # how the last group ended, since the last run_group()
        self._asking = asyncio.Lock()  # one query on the bus at a time

    def __getattr__(self, name):
        # The commands (they only write, so they never block) and the state
        # (running, group, times, battery, positions) are the BusServo's.
        return getattr(self.bus, name)

    # Queries.

    async def read_battery(self, timeout_ms=100):
        """Battery voltage in mV."""
        async with self._asking:
            self._dispatch()  # what came before answers no request of ours
            self.bus.request_battery()
            await self._wait((CMD_GET_BATTERY_VOLTAGE,), True, timeout_ms)
            return self.bus.battery

    async def read_positions(self, ids, timeout_ms=None):
        """{servo_id: position} for 1..84 servos; the default timeout is 100 ms
        plus 10 ms per servo."""
        async with self._asking:
            self._dispatch()
            self.bus.request_positions(ids)  # checks ids
            if timeout_ms is None:
                timeout_ms = 100 + 10 * len(ids)
            return await self._wait((CMD_MULT_SERVO_POS_READ,), True, timeout_ms)

    def run_group(self, group, times=1):
        """As BusServo.run_group()."""
        self.bus.run_group(group, times)
        self._ended = None  # this one has not ended yet

    async def wait_group_done(self, timeout_ms=None):
        """Wait for the running action group (or the one just started) to end:
        CMD_ACTION_GROUP_COMPLETE if it ran its course, CMD_ACTION_GROUP_STOP if
        it was stopped. timeout_ms=None waits as long as it takes. If it ended
        already (while another task awaited, say), this returns at once."""
        self._dispatch()
        if self._ended is not None and not self.bus.running:
            return self._ended
        wanted = (CMD_ACTION_GROUP_COMPLETE, CMD_ACTION_GROUP_STOP)
        return await self._wait(wanted, False, timeout_ms)

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

    async def _wait(self, wanted, takes, timeout_ms):
        if timeout_ms is not None:
            busservo._check("timeout_ms", timeout_ms, 0, 0x1FFFFFFF)
        waiter = [wanted, takes, None]
        self._waiters.append(waiter)
        start = time.ticks_ms()
        try:
            while True:
                self._dispatch()
                if waiter[2] is not None:
                    return waiter[2]
                if (
                    timeout_ms is not None
                    and time.ticks_diff(time.ticks_ms(), start) >= timeout_ms
                ):
                    raise OSError(errno.ETIMEDOUT)
                await asyncio.sleep_ms(self.poll_ms)
        finally:
            self._waiters.remove(waiter)

    def _dispatch(self):
        # Hand every frame that has come to whoever waits for it, oldest first.
        bus = self.bus
        while True:
            cmd = bus.poll()
            if cmd is None:
                return
            if cmd == CMD_ACTION_GROUP_COMPLETE or cmd == CMD_ACTION_GROUP_STOP:
                self._ended = cmd
            for waiter in self._waiters:
                if waiter[2] is None and cmd in waiter[0]:
                    waiter[2] = cmd
                    if waiter[1]:  # a query's reply: the query takes it
                        if cmd == CMD_MULT_SERVO_POS_READ:
                            waiter[2] = self._reply_positions()
                        break
            else:  # nobody took it: hold it for events() and poll()
                if len(self._held) < self._queue:
                    self._held.append(cmd)
                else:
                    self.lost += 1

    def _reply_positions(self):
        # The reply just decoded still lies in the driver's receive buffer. (The
        # twin of the loop in BusServo.read_positions(): a shared method there
        # would take busservo.py's RAM past its 8 KB target.)
        rx = self.bus._rx
        f = self.bus._f
        return {rx[i]: rx[i + 1] | rx[i + 2] << 8 for i in range(f + 5, f + 5 + 3 * rx[f + 4], 3)}
