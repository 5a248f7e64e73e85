"""Exceptions of the hardware bridge (``hwbridge`` imports neither ``recon`` nor ``twin``)."""


class BridgeInputError(ValueError):
    """A request the device cannot take (e.g. a wavelength outside its range)."""


class DriverNotInstalled(BridgeInputError):
    """A real device whose driver library is not installed: the message names the extra of
    ``spectwin`` that brings it (``pip install 'spectwin[rotation-stage]'``)."""


class StoreDamagedError(RuntimeError):
    """A store whose data or metadata is missing or corrupt on disk (a chunk deleted, truncated
    or altered, a ``zarr.json`` gone): the message names the path and what is wrong."""


class DeviceError(RuntimeError):
    """A device answered something unexpected or reported an error."""


class DeviceTimeout(DeviceError):
    """A device did not answer in time."""


class DeviceDisconnected(DeviceError):
    """A device dropped off the bus; it may come back after staging it again."""


class StoreBusy(RuntimeError):
    """Another writer holds the store's lock (:mod:`hwbridge.lock`); the message names it."""


class SessionInterrupted(Exception):
    """A capture stopped on SIGINT or SIGTERM between two frames (:mod:`hwbridge.session`).

    Attributes
    ----------
    store
        The store's path.
    done, total
        Plan steps in the store (written and flagged done) and in the plan.
    """

    def __init__(self, store: object, done: int, total: int):
        super().__init__(f"{store}: interrupted after {done} of {total} frames")
        self.store, self.done, self.total = store, done, total
