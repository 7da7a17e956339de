# Nudges servos 1..6, runs action group 1; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# busservo's tour: read the battery and where six servos are, move each a little and back,
# watch them mid-move and at rest, run an action group and wait for it to complete.
#
#   sh boards/unix.sh examples/demo.py     # unix port, simulated controller
#   mpremote mip install package.json      # once: the driver
#   mpremote run examples/demo.py          # a board, with board.py and a controller
import time

import busservo
import busservo_board

# Set True once you have checked that servos 1..6 can each turn a little (100 of their 1000)
# toward the middle of their range (down, from the middle), and that your robot has room for
# action group 1.
I_HAVE_CHECKED_MY_ROBOT = False

bus = busservo_board.bus()  # board.py's UART, or the simulated controller
if busservo_board.simulated:
    I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check

SERVOS = (1, 2, 3, 4, 5, 6)
GROUP = 1  # an action group downloaded to the controller
START = time.ticks_ms()


def say(text):
    ms = time.ticks_diff(time.ticks_ms(), START)
    print("[%3d.%03d s] %s" % (ms // 1000, ms % 1000, text))


def show(positions):
    for servo_id in sorted(positions):
        position = positions[servo_id]
        if position is None:
            print("             servo %d does not answer" % servo_id)
            continue
        filled = min(max(position, 0), 1000) // 50  # 0..1000 in 20 steps
        print(
            "             servo %d %s%s %4d"
            % (servo_id, "█" * filled, "·" * (20 - filled), position)
        )


def wait_for(bus, want, timeout_ms):
    # poll() never blocks: a control loop would do its other work in here.
    start = time.ticks_ms()
    while time.ticks_diff(time.ticks_ms(), start) < timeout_ms:
        cmd = bus.poll()
        if cmd == busservo.CMD_ACTION_GROUP_RUN:
            times = (
                "forever" if bus.times == 0 else "%d time%s" % (bus.times, "s"[bus.times == 1 :])
            )
            say("action group %d started, to run %s" % (bus.group, times))
        elif cmd == busservo.CMD_ACTION_GROUP_COMPLETE:
            say("action group %d completed" % bus.group)
        elif cmd == busservo.CMD_ACTION_GROUP_STOP:
            say("action group stopped")
        if cmd == want:
            return True
        time.sleep_ms(1)
    say("no answer within %d ms" % timeout_ms)
    return False


def main():
    say("battery: %.2f V" % (bus.read_battery() / 1000))
    read = bus.read_positions(SERVOS)
    say("the servos are at:")
    show(read)
    # Only the servos that answer move (None: unpowered, or not on the bus).
    here = {i: p for i, p in read.items() if p is not None}
    if not here:
        say("no servo answers: check the servos' power and the bus cable")
        return
    # 100 toward the middle (down, from 500 on): never toward an end of the range (0..1000).
    nudged = {i: p + 100 if p < 500 else p - 100 for i, p in here.items()}
    back = {i: max(p, 0) for i, p in here.items()}  # a servo at 0 may read -3
    say(
        "this moves each by 100 toward the middle, 500 (down from there), over 2 s, back over "
        "2 s, then runs group %d" % GROUP
    )
    if not I_HAVE_CHECKED_MY_ROBOT:
        say("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
        return

    bus.move_many(nudged, 2000)
    time.sleep_ms(1000)
    say("mid-move:")
    show(bus.read_positions(SERVOS))
    time.sleep_ms(1100)
    say("at rest:")
    show(bus.read_positions(SERVOS))
    bus.move_many(back, 2000)
    time.sleep_ms(2000)
    say("back where they were")

    say("running action group %d once" % GROUP)
    bus.run_group(GROUP)
    wait_for(bus, busservo.CMD_ACTION_GROUP_COMPLETE, 10000)
    say("done: the servos hold where they are (examples/unload.py lets them go limp)")


main()
