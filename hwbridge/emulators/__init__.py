"""Wire emulators of real devices, registered as pyserial URL handlers.

``serial.serial_for_url("varispec://")`` opens an emulated VariSpec: the real driver talks to it
byte for byte. Importing this package registers the handlers.
"""

import serial

if "hwbridge.emulators" not in serial.protocol_handler_packages:
    serial.protocol_handler_packages.append("hwbridge.emulators")
