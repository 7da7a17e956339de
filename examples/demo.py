# busservo's tour: move six servos, watch them mid-move and at rest, run an
# action group and wait for it to complete, read the battery.
#
#   sh boards/unix.sh examples/demo.py     # unix port, simulated controller
#   mpremote run examples/demo.py          # a board, with board.py and a controller
import time

import busservo

try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py
except ImportError:
    from busservo_sim import uart  # no board file: the simulated controller

SERVOS = (1, 2, 3, 4, 5, 6)
GROUP = 1  # an action group downloaded to the controller
START = time.ticks_ms()


def say(text):
    ms = time.ticks_diff(time.ticks_ms(), START)
    print("[%3d.%03d s] %s" % (ms // 1000, ms % 1000, text))


def show(positions):
    for servo_id in sorted(positions):
        position = positions[servo_id]
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
    port = uart()
    bus = busservo.BusServo(port)
    say("busservo demo, talking to %s" % type(port).__name__)
    say("battery: %.2f V" % (bus.read_battery() / 1000))

    bus.move_many([(i, 500) for i in SERVOS], 0)
    targets = [(i, 150 * i) for i in SERVOS]
    bus.move_many(targets, 1500)
    say("moving servos %s to %s over 1.5 s" % (SERVOS, [p for _, p in targets]))
    time.sleep_ms(600)
    say("mid-move:")
    show(bus.read_positions(SERVOS))
    time.sleep_ms(1000)
    say("at rest:")
    show(bus.read_positions(SERVOS))

    say("running action group %d once" % GROUP)
    bus.run_group(GROUP)
    wait_for(bus, busservo.CMD_ACTION_GROUP_COMPLETE, 10000)

    say("twice as fast, twice over")
    bus.set_group_speed(GROUP, 200)
    bus.run_group(GROUP, 2)
    wait_for(bus, busservo.CMD_ACTION_GROUP_COMPLETE, 10000)
    bus.set_group_speed(GROUP, 100)

    bus.unload(SERVOS)
    say("servos unloaded: they turn freely by hand now")


main()
