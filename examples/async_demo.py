# Moves servos 1 and 2, runs action group 1; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# busservo with asyncio: a control loop keeps its pace while other tasks wait for the
# controller's answers and for an action group to complete.
#   mpremote mip install lib/busservo_async.json   # once: the driver, its asyncio face
#   mpremote run examples/async_demo.py
import asyncio
import time

import busservo
import busservo_board
from busservo_async import AsyncBusServo

# Set True once you have checked that servo 1 can turn to 900 and servo 2 to 100, with nothing
# in their way, and that your robot has room for action group 1.
I_HAVE_CHECKED_MY_ROBOT = False

# board.py's UART, or the simulated controller; the BusServo's asyncio face.
bus = AsyncBusServo(busservo_board.bus())
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check

# The controller's events by name: events() gives their command numbers.
EVENTS = {
    busservo.CMD_ACTION_GROUP_RUN: "ACTION_GROUP_RUN",
    busservo.CMD_ACTION_GROUP_STOP: "ACTION_GROUP_STOP",
    busservo.CMD_ACTION_GROUP_COMPLETE: "ACTION_GROUP_COMPLETE",
}

loops = 0


async def control_loop():
    # Stands for the robot's own work: it must run every 10 ms, whatever else waits.
    global loops
    while True:
        loops += 1
        await asyncio.sleep_ms(10)


async def listen():
    async for cmd in bus.events():
        print("  event:", EVENTS.get(cmd, cmd), "running:", bus.running, "group:", bus.group)


async def main():
    print("servos 1 and 2 are at", sorted((await bus.read_positions([1, 2])).items()))
    print("this moves servo 1 to 900 and servo 2 to 100 over 2 s, then runs action group 1")
    if not I_HAVE_CHECKED_MY_ROBOT:
        print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
        return

    asyncio.create_task(control_loop())
    asyncio.create_task(listen())
    start = time.ticks_ms()
    print("battery: %d mV" % await bus.read_battery())
    bus.move_many([(1, 900), (2, 100)], 2000)
    await asyncio.sleep_ms(1000)
    print("mid-move:", sorted((await bus.read_positions([1, 2])).items()))
    await asyncio.sleep_ms(1000)
    bus.run_group(1)
    how = await bus.wait_group_done(timeout_ms=10000)
    done = "completed" if how == busservo.CMD_ACTION_GROUP_COMPLETE else "stopped"
    print("action group", bus.group, done)
    await asyncio.sleep_ms(20)  # let the listener print the last event
    took = time.ticks_diff(time.ticks_ms(), start)
    print("the control loop ran %d times in %d ms meanwhile" % (loops, took))


asyncio.run(main())
