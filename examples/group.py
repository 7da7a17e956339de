# Runs action group 1, then 2 until stopped; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# The action groups are the ones downloaded to the controller beforehand; this waits for their
# events with poll(), which never blocks.
#   mpremote mip install package.json   # once: the driver
#   mpremote run examples/group.py
import time

import busservo
import busservo_board

# Set True once you know what action groups 1 and 2 do and your robot has room to do it.
I_HAVE_CHECKED_MY_ROBOT = False

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check

# The controller's events by name: poll() returns their command numbers.
EVENTS = {
    busservo.CMD_ACTION_GROUP_RUN: "ACTION_GROUP_RUN",
    busservo.CMD_ACTION_GROUP_STOP: "ACTION_GROUP_STOP",
    busservo.CMD_ACTION_GROUP_COMPLETE: "ACTION_GROUP_COMPLETE",
}

print("servos 1..6 are at", sorted(bus.read_positions([1, 2, 3, 4, 5, 6]).items()))
print("this runs action group 1 once, then group 2 over and over, and stops it after 0.5 s")
if not I_HAVE_CHECKED_MY_ROBOT:
    print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
    raise SystemExit


def wait_for(want, timeout_ms=10000):
    start = time.ticks_ms()
    while time.ticks_diff(time.ticks_ms(), start) < timeout_ms:
        cmd = bus.poll()  # never blocks: do the rest of your loop here
        if cmd is not None:
            name = EVENTS.get(cmd, cmd)
            print(name, "running:", bus.running, "group:", bus.group, "times:", bus.times)
        if cmd == want:
            return
        time.sleep_ms(5)
    print("gave up waiting")


try:
    bus.run_group(1)
    wait_for(busservo.CMD_ACTION_GROUP_COMPLETE)
    bus.run_group(2, 0)  # 0: forever
    wait_for(busservo.CMD_ACTION_GROUP_RUN)
    time.sleep_ms(500)
finally:  # also on Ctrl-C: a group that runs for ever must not outlive the example
    bus.stop_group()
wait_for(busservo.CMD_ACTION_GROUP_STOP)
