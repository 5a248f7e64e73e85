"""Exceptions of the hardware bridge (``hwbridge`` imports neither ``recon`` nor ``twin``)."""


class BridgeInputError(ValueError):
    """A request the device cannot take (e.g. a wavelength outside its range)."""


class StoreDamagedError(RuntimeError):
    """A store whose data or metadata is missing or corrupt on disk (a chunk deleted, truncated
    or altered, a ``zarr.json`` gone): the message names the path and what is wrong."""


class DeviceError(RuntimeError):
    """A device answered something unexpected or reported an error."""


class DeviceTimeout(DeviceError):
    """A device did not answer in time."""


class DeviceDisconnected(DeviceError):
    """A device dropped off the bus; it may come back after staging it again."""
