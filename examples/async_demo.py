# busservo with asyncio: a control loop keeps its pace while other tasks wait
# for the controller's answers and for an action group to complete.
#   mpremote run examples/async_demo.py
import asyncio
import time

from busservo import CMD_ACTION_GROUP_COMPLETE
from busservo_async import AsyncBusServo

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

bus = AsyncBusServo(uart())
loops = 0


async def control_loop():
    # Stands for the robot's own work: it must run every 10 ms, whatever else waits.
    global loops
    while True:
        loops += 1
        await asyncio.sleep_ms(10)


async def listen():
    async for cmd in bus.events():
        print("  event: command", cmd, "running:", bus.running, "group:", bus.group)


async def main():
    asyncio.create_task(control_loop())
    asyncio.create_task(listen())
    start = time.ticks_ms()
    print("battery: %d mV" % await bus.read_battery())
    bus.move_many([(1, 900), (2, 100)], 1000)
    await asyncio.sleep_ms(500)
    print("mid-move:", await bus.read_positions([1, 2]))
    bus.run_group(1)
    how = await bus.wait_group_done(timeout_ms=10000)
    print(
        "action group", bus.group, "completed" if how == CMD_ACTION_GROUP_COMPLETE else "stopped"
    )
    await asyncio.sleep_ms(20)  # let the listener print the last event
    took = time.ticks_diff(time.ticks_ms(), start)
    print("the control loop ran %d times in %d ms meanwhile" % (loops, took))


asyncio.run(main())
