"""Drivers of real devices. Each speaks its device's wire protocol through pyserial (or the
vendor's SDK) and is tested against the wire emulators of ``hwbridge.emulators``."""
