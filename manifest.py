# For firmware with busservo frozen in: add to your board's manifest
#     include("path/to/busservo/manifest.py")
# or, with the simulated controller too,
#     include("path/to/busservo/manifest.py", sim=True)
metadata(
    description="Driver for the serial Bus Servo Controller (LOBOT/Hiwonder, 0x55 0x55 frames).",
    version="0.1.0",
)
options.defaults(sim=False)

module("busservo.py", base_path="lib")
if options.sim:
    module("busservo_sim.py", base_path="lib")
