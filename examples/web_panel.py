# A browser panel for servos 1..4; real servos only once I_HAVE_CHECKED_MY_ROBOT = True.
# Drive servos 1..4 from a phone: a slider a joint, live positions, the battery, teach and
# play back, and a STOP button (or Esc) that lets every joint go limp. Nothing moves until
# you arm the page; if the page goes quiet for a second (tab closed, Wi-Fi gone), the joints
# hold where they are. Its calibration page calibrates the arm by hand and saves robot.json,
# which this example loads the next time; with an arm's links in it (joints base, shoulder,
# elbow and wrist: docs/panel.md), the page also jogs the arm's tool point in millimetres.
#
# On a board with Wi-Fi (ESP32, Pico W): its board.py gives uart() and, to join your
# network, WIFI = ("network name", "its password"); without WIFI the board starts its own
# access point, "busservo", whose WPA2 key is the panel's password. The board prints the
# address to open and the password. It serves until stopped: run it at the board's REPL,
# where Ctrl-C stops it (and the joints hold). With board.py on the board (docs/panel.md):
#   mpremote mip install lib/busservo_web.json   # once: the driver, motion, the panel, its page
#   mpremote cp examples/web_panel.py :web_panel.py
#   mpremote repl              then type: import web_panel      (Ctrl-] leaves mpremote)
# To serve again: Ctrl-D (a soft reset), then import web_panel. `mpremote run
# examples/web_panel.py` serves too, but a Ctrl-C there stops mpremote, not the board: the
# panel goes on serving and holding the robot until `mpremote soft-reset` (which sends the
# board a Ctrl-C, then resets it). Copied as main.py it serves from power-up.
# On the unix port, against the simulated controller, at http://127.0.0.1:8080 (and on your
# PC's other addresses: it listens on every interface, as a board does):
#   sh boards/unix.sh examples/web_panel.py [--port N] [--password P]
#
# The password: the one given, else the one in web_panel.txt, else a new random one, kept
# in web_panel.txt (on the board's filesystem, or in the folder this runs from).
import asyncio
import errno
import os
import sys

import busservo_board
import busservo_web

# Set True once servos 1..4 can turn freely: the page moves them as far as each joint's
# limits below, and its STOP lets them go limp (hold the arm: limp, it falls).
I_HAVE_CHECKED_MY_ROBOT = False
DPS: int | None = 30  # on a real robot no joint turns faster (degrees a second)

try:  # board.py's (network name, password) to join; None: an access point
    from board import WIFI  # type: ignore[attr-defined]
except ImportError:  # no board.py (busservo_board.bus() says so), or no WIFI in it
    WIFI = None

UNIX = sys.platform in ("linux", "darwin")
# Sent to a board's REPL by `mpremote run`, which passes no Ctrl-C on: a soft reset stops it.
SENT = globals().get("__file__") == "<stdin>"
COMMAND_LINE = UNIX and __name__ == "__main__" and not SENT  # sh boards/unix.sh: --port N
PASSWORD_FILE = "web_panel.txt"


def option(name, default):
    """--name VALUE or --name=VALUE from the command line (the unix port), else default."""
    args = sys.argv
    for i, arg in enumerate(args):
        if arg == name:
            if i + 1 < len(args):
                return args[i + 1]
            print("%s wants a value: %s %s" % (name, name, "N" if name == "--port" else "P"))
            raise SystemExit(2)
        if arg.startswith(name + "="):
            return arg[len(name) + 1 :]
    return default


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
    # WPA2 with the panel's password, said outright: on an ESP32 a key alone leaves the
    # access point open (its default); a Pico W's is WPA2 already.
    wpa2 = getattr(network.WLAN, "SEC_WPA2", None)
    if wpa2 is None:
        ap.config(ssid="busservo", key=key)
    else:
        ap.config(ssid="busservo", key=key, security=wpa2)
    ap.active(True)
    print("started the access point busservo; its key is the password below")
    return ap.ifconfig()[0]


def main():
    try:
        port = int(option("--port", 8080 if UNIX else 80))
    except ValueError:
        port = -1
    if not 0 < port < 65536:
        print("--port wants a number from 1 to 65535, got %r" % option("--port", None))
        raise SystemExit(2)
    key = password()
    if len(key) < 8:
        print("--password wants 8 or more characters, got %d" % len(key))
        raise SystemExit(2)
    bus = busservo_board.bus()  # board.py's UART, or the simulated controller
    simulated = busservo_board.simulated  # nothing real to check, nor to hurt: full speed
    dps = None if simulated else DPS
    # Your calibration (robot.json, if you saved one), or these joints.
    robot = busservo_board.robot(bus, busservo_board.joints(dps=dps))
    ids = [robot.joints[name].servo_id for name in robot.names]
    print("the servos are at", bus.read_positions(ids))
    print("this serves a web page whose sliders move them, and whose STOP lets them go limp")
    if not (I_HAVE_CHECKED_MY_ROBOT or simulated):
        print("nothing moved: check, then set I_HAVE_CHECKED_MY_ROBOT = True (top of this file)")
        raise SystemExit
    address = "127.0.0.1" if UNIX else connect(key)
    robot.where()  # where the joints start (a joint with a dps limit needs it)
    try:
        asyncio.run(serve(robot, key, port, address))
    except OSError as e:
        if e.errno != errno.EADDRINUSE:
            raise
        if COMMAND_LINE:
            print("port %d is in use (another panel?): give another with --port N" % port)
        else:  # a board: most likely a panel that still serves
            print(
                "port %d is in use (another panel?): a soft reset frees it (Ctrl-D at the "
                "board's REPL, or mpremote soft-reset)" % port
            )
        raise SystemExit(1)
    finally:
        robot.hold()


async def serve(robot, key, port, address):
    """busservo_web.serve(), saying where to go once it is listening."""
    failed = []

    async def run():
        try:
            await busservo_web.serve(robot, key, port)
        except OSError as e:  # the port in use, most likely: main() says so
            failed.append(e)

    server = asyncio.create_task(run())
    await asyncio.sleep_ms(200)
    if not failed:
        print(
            "open http://%s%s/ and log in with the password %s"
            % (address, "" if port == 80 else ":%d" % port, key)
        )
        if SENT:
            print("(mpremote soft-reset stops the panel: a Ctrl-C stops only mpremote)")
        else:
            print("(Ctrl-C stops the panel)")
    await server
    if failed:
        raise failed[0]


main()
