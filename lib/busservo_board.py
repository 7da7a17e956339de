# busservo_board: the bus and the robot, found the same way by every example.
#
#   import busservo_board
#   bus = busservo_board.bus()               # board.py's UART, or the simulated controller
#   arm = busservo_board.robot(bus, JOINTS)  # the calibration you saved, or these joints
#   arm = busservo_board.robot(bus, busservo_board.joints(dps=30))   # or the examples' arm
#
# bus() is a BusServo on the uart() of your board.py (your port's file from boards/, copied
# to the board as board.py), or, where there is no board.py, on the simulated controller
# (lib/busservo_sim.py), which it says. A board.py that fails to import stops it with its own
# error: only a missing one means the simulator. `simulated` says which it took. With neither
# on the board, an ImportError says what to copy.
#
# robot(bus, joints) is the Robot your calibration saved to busservo_motion.CALIBRATION
# (robot.json, in the folder the program runs from: a board's root), so that every example
# moves your arm within the limits you found; without that file, a Robot of the joints the
# example gives: joints() are the examples' arm (a base, a shoulder, an elbow and a claw).
# A speed the example asks for (joints(dps=30)) holds with the file too: a calibration
# brings limits, never a faster arm.
import errno

import busservo

simulated = False  # True once bus() took the simulated controller


def bus():
    """A BusServo on board.py's uart(), or on the simulated controller without one."""
    global simulated
    try:
        from board import uart  # your board file: boards/<port>.py, copied as board.py
    except ImportError as e:
        if "'board'" not in str(e):
            raise  # board.py is there but fails to import: its error, not the simulator
        try:
            from busservo_sim import uart
        except ImportError as e:
            if "'busservo_sim'" not in str(e):
                raise
            raise ImportError(
                "no board.py, nor the simulator: copy your port's board file as board.py "
                "(mpremote cp boards/esp32.py :board.py), or install the simulator "
                "(mpremote mip install lib/busservo_sim.json)"
            ) from None

        simulated = True
        print("no board.py found: using the simulated controller, nothing real moves")
    port = uart()
    print("talking to", port)
    return busservo.BusServo(port)


def robot(bus, joints):
    """The Robot saved to busservo_motion.CALIBRATION, or with no such file, a Robot of
    joints on bus. A speed cap the joints ask for holds over the file's: each of its joints
    turns at most the least dps of joints (and its own, if the file gives one)."""
    import busservo_motion

    path = busservo_motion.CALIBRATION
    dps = busservo_motion.least_dps(joints)
    try:
        arm = busservo_motion.Robot.load(bus, path, dps)
    except OSError as e:
        if e.args[0] != errno.ENOENT:
            raise
        return busservo_motion.Robot(bus, joints)  # no calibration saved: the example's
    said = ", at most %g degrees/s" % dps if dps else ""
    print("using the calibration in %s: joints %s%s" % (path, ", ".join(arm.names), said))
    return arm


def joints(dps=None):
    """The examples' arm: {name: busservo_motion.Joint} of a base, a shoulder, an elbow and a
    claw on servos 1..4, each turning at most dps degrees a second (None: as fast as asked)."""
    import busservo_motion as bm

    return {
        "base": bm.Joint(1, dps=dps),
        "shoulder": bm.Joint(2, limits=(-90, 90), dps=dps),
        "elbow": bm.Joint(3, limits=(-90, 90), dps=dps),
        "claw": bm.Joint(4, limits=(0, 60), dps=dps),
    }
