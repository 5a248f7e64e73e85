"""Wire emulators of real devices, registered as pyserial URL handlers.

``serial.serial_for_url("varispec://")`` opens an emulated VariSpec LCTF, ``"apt://"`` a Thorlabs
APT rotation stage, ``"dmxusbpro://"`` an Enttec DMX USB Pro with the dome's LED decoders: the
real drivers talk to them byte for byte. :mod:`hwbridge.emulators.pty_link` serves an emulator on
a pseudo-terminal instead. Importing this package registers the handlers.
"""

import serial

if "hwbridge.emulators" not in serial.protocol_handler_packages:
    serial.protocol_handler_packages.append("hwbridge.emulators")
