# A browser panel for servos 1..4; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# Drive servos 1..4 from a phone: a slider a joint, live positions, the battery, teach and
# play back, and a STOP button (or Esc) that lets every joint go limp. Nothing moves until
# you arm the page; if the page goes quiet for a second (tab closed, Wi-Fi gone), the joints
# hold where they are.
#
# On a board with Wi-Fi (ESP32, Pico W): its board.py gives uart() and, to join your
# network, WIFI = ("network name", "its password"); without WIFI the board starts its own
# access point, "busservo", whose WPA2 key is the panel's password. The board prints the
# address to open and the password. Install the panel first (README: the web panel).
#   mpremote run examples/web_panel.py
# On the unix port, against the simulated controller, at http://127.0.0.1:8080:
#   sh boards/unix.sh examples/web_panel.py [--port N] [--password P]
#
# The password: the one given, else the one in web_panel.txt, else a new random one, kept
# in web_panel.txt (on the board's filesystem, or in the folder this runs from).
import asyncio
import os
import sys

import busservo
import busservo_motion as bm
import busservo_web

# Set True once servos 1..4 can turn freely: the page moves them as far as each joint's
# limits below, and its STOP lets them go limp (hold the arm: limp, it falls).
I_HAVE_CHECKED_MY_ROBOT = False
DPS: int | None = 30  # on a real robot no joint turns faster (degrees a second)

WIFI = None  # from board.py: (network name, password) to join, or None: an access point
try:
    from board import uart  # your board file: boards/<port>.py, copied as board.py

    try:
        from board import WIFI  # type: ignore[attr-defined, no-redef]
    except ImportError:
        pass
    SIMULATED = False
except ImportError as e:
    if "'board'" not in str(e):
        raise  # board.py is there but fails to import: its error, not the simulator
    from busservo_sim import uart

    print("no board.py found: using the simulated controller, nothing real moves")
    SIMULATED = I_HAVE_CHECKED_MY_ROBOT = True  # nothing real to check
    DPS = None  # nor to hurt: full speed

UNIX = sys.platform in ("linux", "darwin")
PASSWORD_FILE = "web_panel.txt"


def option(name, default):
    """--name VALUE from the command line (the unix port), else default."""
    args = sys.argv
    return args[args.index(name) + 1] if name in args[:-1] else default


def password():
    """The panel's password: given, kept from an earlier run, or new (and then kept)."""
    given = option("--password", None)
    if given:
        return given
    try:
        with open(PASSWORD_FILE) as f:
            kept = f.read().strip()
        if len(kept) >= 8:
            return kept
    except OSError:
        pass
    letters = "abcdefghjkmnpqrstuvwxyz23456789"  # none that look alike
    new = "".join(letters[b % len(letters)] for b in os.urandom(12))
    with open(PASSWORD_FILE, "w") as f:
        f.write(new + "\n")
    return new


def connect(key):
    """Join board.py's WIFI network, or start an access point; return the board's address."""
    import time

    import network  # boards with Wi-Fi only

    wifi = WIFI
    if wifi:
        station = network.WLAN(network.STA_IF)
        station.active(True)
        station.connect(*wifi)
        print("joining", wifi[0], end="")
        for _ in range(40):
            if station.isconnected():
                break
            print(end=".")
            time.sleep_ms(500)
        print()
        if not station.isconnected():
            raise OSError("could not join %r: check WIFI in board.py" % wifi[0])
        return station.ifconfig()[0]
    ap = network.WLAN(network.AP_IF)
    ap.config(ssid="busservo", key=key)  # WPA2 with the panel's password
    ap.active(True)
    print("started the access point busservo; its key is the password below")
    return ap.ifconfig()[0]


def main():
    port = int(option("--port", 8080 if UNIX else 80))
    key = password()
    serial = uart()
    print("talking to", serial)
    bus = busservo.BusServo(serial)
    print("the servos are at", bus.read_positions([1, 2, 3, 4]))
    print("this serves a web page whose sliders move them, and whose STOP lets them go limp")
    if not I_HAVE_CHECKED_MY_ROBOT:
        print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
        raise SystemExit
    address = "127.0.0.1" if UNIX else connect(key)
    robot = bm.Robot(
        bus,
        {
            "base": bm.Joint(1, dps=DPS),
            "shoulder": bm.Joint(2, limits=(-90, 90), dps=DPS),
            "elbow": bm.Joint(3, limits=(-90, 90), dps=DPS),
            "claw": bm.Joint(4, limits=(0, 60), dps=DPS),
        },
    )
    robot.where()  # where the joints start (a joint with a dps limit needs it)
    print(
        "open http://%s%s/ and log in with the password %s"
        % (address, "" if port == 80 else ":%d" % port, key)
    )
    print("(Ctrl-C stops the panel)")
    try:
        asyncio.run(busservo_web.serve(robot, key, port))
    finally:
        robot.hold()


main()
