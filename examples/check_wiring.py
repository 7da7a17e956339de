# Moves nothing: asks the controller for its battery voltage and, if it stays silent, says why.
# Run it first, once the wires are on: a working link answers in about 10.4 ms (10 bytes of
# wire at 9600 baud: the 4-byte question and the 6-byte answer). When the controller (or a
# servo it reads) does not answer, it ends with an OSError, exit status 1, so that a script can
# tell: through `mpremote run` too, which reports a board's sys.exit() as status 0.
#   mpremote mip install package.json   # once: the driver
#   mpremote run examples/check_wiring.py
import errno
import time

import busservo_board

READ_SERVOS = 0  # set 6, say, to read servos 1..6 too, once the controller answers

bus = busservo_board.bus()  # board.py's UART, or the simulated controller

# Why a controller stays silent, the most likely first: (the cause, how to check it).
CAUSES = (
    ("TX and RX swapped", "your TX goes to its RX, your RX to its TX (a swap harms nothing)"),
    ("no common ground", "a wire joins your board's GND to the controller's GND"),
    ("the controller is unpowered", "battery charged, power switch on, its LED lit"),
    ("the wrong baud rate", "board.py's UART(...) says 9600 baud, 8 bits, no parity, 1 stop"),
    ("the wrong UART pins in board.py", "its tx= and rx= are the pins your wires are on"),
    (
        "a 5 V controller TX on a 3.3 V RX pin",
        "measure its TX at rest: 5 V needs a divider (1k, then 2k to GND) or a level shifter",
    ),
)

mv = None  # no answer yet
start = time.ticks_us()
try:
    mv = bus.read_battery()
except OSError as e:
    if e.args[0] != errno.ETIMEDOUT:  # silence; anything else is another fault: show it
        raise
took = time.ticks_diff(time.ticks_us(), start)

fault: OSError | None = None  # what ends it with exit status 1, if anything
if mv is not None:
    print("battery: %.2f V" % (mv / 1000))
    print("round trip: %.1f ms (about 10.4 ms on a wire at 9600 baud)" % (took / 1000))
    print("noise: %d bytes that were no frame" % bus.noise)
    if READ_SERVOS:
        read = bus.read_positions(range(1, READ_SERVOS + 1))
        print("positions:", sorted(read.items()))
        silent = [i for i in sorted(read) if read[i] is None]
        if silent:
            print("servos %s do not answer: their power, the bus cable, their ids" % silent)
            fault = OSError(errno.ENODEV, "servos %s do not answer" % silent)
else:
    print("no answer from the controller within 100 ms. The likely causes, in order:")
    for n, (cause, check) in enumerate(CAUSES, 1):
        print("%d. %s\n   check: %s" % (n, cause, check))
    fault = OSError(errno.ETIMEDOUT, "no answer from the controller: the likely causes are above")
if bus.noise:
    print("%d bytes came that made no frame: something talks, but garbled." % bus.noise)
    print("That points to the baud rate (9600 8N1), the logic level, or the ground.")
if fault:
    raise fault  # for a script or a CI: the link does not work yet
