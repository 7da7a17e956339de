# For firmware with busservo frozen in: add to your board's manifest
#     include("path/to/busservo/manifest.py")
# or, with the simulated controller, the asyncio interface and the motion layer too,
#     include("path/to/busservo/manifest.py", sim=True, asyncio=True, motion=True)
# arm=True freezes the arm in millimetres (busservo_arm) and calibration=True the calibration by
# hand (busservo_calibrate), record=True continuous recording and playback (busservo_record),
# teleop=True a leader arm driving a follower (busservo_teleop), each with the motion layer
# they stand on.
# web=True freezes the web panel (busservo_web) too; it needs its page copied to the board's
# /lib: mpremote cp lib/busservo_web.html.gz :/lib/ (its jog needs arm=True, its calibration
# page calibration=True, its recording record=True and its teleop teleop=True)
# No metadata(): included, it would become the whole firmware's (and a second library's would
# fail with "Duplicate call to metadata()"). busservo.__version__ says the driver's version.
options.defaults(
    sim=False,
    asyncio=False,
    motion=False,
    web=False,
    arm=False,
    calibration=False,
    record=False,
    teleop=False,
)

module("busservo.py", base_path="lib")
module("busservo_board.py", base_path="lib")  # how the examples find board.py
if options.sim:
    module("busservo_sim.py", base_path="lib")
if options.asyncio:
    module("busservo_async.py", base_path="lib")
if (
    options.motion
    or options.web
    or options.arm
    or options.calibration
    or options.record
    or options.teleop
):
    module("busservo_motion.py", base_path="lib")
if options.web:
    module("busservo_web.py", base_path="lib")
    module("busservo_web_sliders.py", base_path="lib")  # its parts
    module("busservo_web_teach.py", base_path="lib")
    module("busservo_web_jog.py", base_path="lib")
    module("busservo_web_calibrate.py", base_path="lib")
    module("busservo_web_record.py", base_path="lib")
if options.arm:
    module("busservo_arm.py", base_path="lib")
if options.calibration:
    module("busservo_calibrate.py", base_path="lib")
if options.record:
    module("busservo_record.py", base_path="lib")
if options.teleop:
    module("busservo_teleop.py", base_path="lib")
