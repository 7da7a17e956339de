# busservo_async on the unix port's asyncio, against the fake UART with replies
# that arrive over time.
import asyncio
import errno
import time
import unittest

from busservo import (
    CMD_ACTION_GROUP_COMPLETE,
    CMD_ACTION_GROUP_RUN,
    CMD_ACTION_GROUP_STOP,
    CMD_GET_BATTERY_VOLTAGE,
)
from busservo_async import AsyncBusServo
from fakeuart import FakeUART
from test_frames import (
    ALL_500,
    BATTERY_7500,
    COMPLETE_8_ONCE,
    POSITIONS_ALL_500,
    RUN_2_FOREVER,
    RUN_8_ONCE,
    STOP,
)
from test_queries import BATTERY_7400, GET_BATTERY, READ_1_TO_6


def run(coroutine):
    return asyncio.run(coroutine)


async def timed_out(awaitable):
    try:
        await awaitable
    except OSError as e:
        return e.args[0] == errno.ETIMEDOUT
    return False


class Async(unittest.TestCase):
    def setUp(self):
        self.uart = FakeUART()
        self.bus = AsyncBusServo(self.uart, poll_ms=1)

    def test_queries(self):
        self.uart.reply(GET_BATTERY, BATTERY_7500, delay_ms=20)
        self.uart.reply(READ_1_TO_6, POSITIONS_ALL_500, delay_ms=20)

        async def main():
            return await self.bus.read_battery(), await self.bus.read_positions(range(1, 7))

        self.assertEqual(run(main()), (7500, ALL_500))
        self.assertEqual(self.uart.written(), GET_BATTERY + READ_1_TO_6)
        self.assertEqual((self.bus.battery, self.bus.positions), (7500, ALL_500))

    def test_commands_and_state_are_the_bus_servos(self):
        self.bus.run_group(8)
        self.assertEqual(self.uart.written(), RUN_8_ONCE)
        self.uart.feed(RUN_8_ONCE)
        self.assertEqual(self.bus.poll(), CMD_ACTION_GROUP_RUN)
        self.assertEqual((self.bus.running, self.bus.group, self.bus.times), (True, 8, 1))
        with self.assertRaises(ValueError):
            self.bus.move(300, 0, 0)

    def test_a_query_does_not_block_the_loop(self):
        self.uart.reply(GET_BATTERY, BATTERY_7500, delay_ms=60)
        ticks = [0]

        async def ticker():
            while True:
                ticks[0] += 1
                await asyncio.sleep_ms(1)

        async def main():
            task = asyncio.create_task(ticker())
            await asyncio.sleep_ms(0)
            volts = await self.bus.read_battery()
            task.cancel()
            return volts

        self.assertEqual(run(main()), 7500)
        self.assertTrue(ticks[0] >= 10, "the ticker ran %d times in 60 ms" % ticks[0])

    def test_a_missing_reply_times_out(self):
        async def main():
            return await timed_out(self.bus.read_battery(timeout_ms=30)), await timed_out(
                self.bus.read_positions([1], timeout_ms=10)
            )

        start = time.ticks_ms()
        self.assertEqual(run(main()), (True, True))
        self.assertTrue(time.ticks_diff(time.ticks_ms(), start) >= 40)

    def test_concurrent_queries_are_serialised_and_get_their_own_replies(self):
        self.uart.reply(GET_BATTERY, [BATTERY_7500, BATTERY_7400], delay_ms=15)
        self.uart.reply(READ_1_TO_6, POSITIONS_ALL_500, delay_ms=15)
        order = []

        async def one(name, query):
            result = await query
            order.append((name, len(self.uart.written())))
            return result

        async def main():
            return await asyncio.gather(
                one("battery 1", self.bus.read_battery()),
                one("positions", self.bus.read_positions(range(1, 7))),
                one("battery 2", self.bus.read_battery()),
            )

        self.assertEqual(run(main()), [7500, ALL_500, 7400])
        # Each asked only after the query before it had its answer.
        self.assertEqual(order, [("battery 1", 4), ("positions", 15), ("battery 2", 19)])
        self.assertEqual(self.uart.written(), GET_BATTERY + READ_1_TO_6 + GET_BATTERY)

    def test_wait_group_done(self):
        self.uart.feed_later(RUN_8_ONCE, 10)
        self.uart.feed_later(COMPLETE_8_ONCE, 40)

        async def main():
            self.bus.run_group(8)
            done = await self.bus.wait_group_done(timeout_ms=2000)
            self.bus.run_group(2, 0)
            self.uart.feed_later(RUN_2_FOREVER, 5)
            self.uart.feed_later(STOP, 20)
            stopped = await self.bus.wait_group_done(timeout_ms=2000)
            self.bus.run_group(3)
            nothing = await timed_out(self.bus.wait_group_done(timeout_ms=20))
            return done, stopped, nothing

        self.assertEqual(run(main()), (CMD_ACTION_GROUP_COMPLETE, CMD_ACTION_GROUP_STOP, True))
        # wait_group_done() looks, it does not take: the frames are all still there.
        self.assertEqual(
            [self.bus.poll() for _ in range(5)],
            [
                CMD_ACTION_GROUP_RUN,
                CMD_ACTION_GROUP_COMPLETE,
                CMD_ACTION_GROUP_RUN,
                CMD_ACTION_GROUP_STOP,
                None,
            ],
        )

    def test_a_group_that_ended_during_another_query(self):
        self.uart.reply(GET_BATTERY, BATTERY_7500, delay_ms=40)
        self.uart.feed_later(RUN_8_ONCE, 5)
        self.uart.feed_later(COMPLETE_8_ONCE, 20)

        async def main():
            self.bus.run_group(8)
            await self.bus.read_battery()  # the group runs and completes meanwhile
            return await self.bus.wait_group_done(timeout_ms=0)

        self.assertEqual(run(main()), CMD_ACTION_GROUP_COMPLETE)

    def test_events_yield_every_frame_none_lost(self):
        self.uart.reply(GET_BATTERY, BATTERY_7500, delay_ms=20)  # in about 31 ms
        self.uart.feed_later(RUN_8_ONCE, 5)  # during the query, before its reply

        async def listen(got):
            async for cmd in self.bus.events():
                got.append(cmd)
                if cmd == CMD_GET_BATTERY_VOLTAGE:
                    return

        async def main():
            got = []
            listener = asyncio.create_task(listen(got))
            volts = await self.bus.read_battery()  # its reply is the query's, not an event
            self.uart.feed_later(COMPLETE_8_ONCE, 30)  # after the query, however long it took
            await self.bus.wait_group_done(timeout_ms=2000)
            self.bus.request_battery()  # this reply is an event
            self.uart.feed(BATTERY_7400)
            await listener
            return volts, got

        volts, got = run(main())
        self.assertEqual(volts, 7500)
        self.assertEqual(got, [CMD_ACTION_GROUP_RUN, CMD_ACTION_GROUP_COMPLETE, 15])
        self.assertEqual(self.bus.battery, 7400)

    def test_frames_waiting_before_a_query_are_events(self):
        self.uart.feed(STOP + BATTERY_7400)  # a stale reply, before we asked
        self.uart.reply(GET_BATTERY, BATTERY_7500, delay_ms=5)
        self.assertEqual(run(self.bus.read_battery()), 7500)
        self.assertEqual([self.bus.poll(), self.bus.poll(), self.bus.poll()], [7, 15, None])

    def test_more_frames_than_the_queue_holds_are_counted(self):
        bus = AsyncBusServo(self.uart, poll_ms=1, queue=4)
        self.uart.feed(STOP * 6)
        self.assertEqual([bus.poll() for _ in range(5)], [7, 7, 7, 7, None])
        self.assertEqual(bus.lost, 2)

    def test_a_timeout_has_its_errno_on_every_python(self):
        # As test_queries' test of that name, for the queries and wait_group_done().
        for call in (
            lambda: self.bus.read_battery(timeout_ms=10),
            lambda: self.bus.read_positions([1], timeout_ms=10),
            lambda: self.bus.wait_group_done(timeout_ms=10),
        ):
            try:
                run(call())
            except OSError as e:
                self.assertEqual(e.errno, errno.ETIMEDOUT)
            else:
                self.fail("no timeout")

    def test_bad_timeouts_are_refused(self):
        with self.assertRaises(ValueError):
            run(self.bus.read_battery(timeout_ms=-1))
        with self.assertRaises(TypeError):
            run(self.bus.wait_group_done(timeout_ms=1.5))


class APeerFasterThanTheWire(unittest.TestCase):
    # As test_queries' class of that name: a reply sooner than 9600 baud allows answers.
    def test_queries(self):
        uart = FakeUART(at_once=True)
        uart.reply(GET_BATTERY, BATTERY_7500)
        uart.reply(READ_1_TO_6, POSITIONS_ALL_500)
        bus = AsyncBusServo(uart, poll_ms=1)

        async def main():
            return await bus.read_battery(), await bus.read_positions(range(1, 7))

        self.assertEqual(run(main()), (7500, ALL_500))
        self.assertEqual(run(main()), (7500, ALL_500))
        self.assertEqual(bus.early, 4)


if __name__ == "__main__":
    unittest.main()
