"""The exceptions of spectwin: one tree, rooted in :class:`SpectwinError`.

It lives here, at the bottom of ``hwbridge``, because ``hwbridge`` imports neither ``recon`` nor
``twin`` and both import ``hwbridge``; :mod:`recon.errors` gives ``recon`` the same classes.

::

    SpectwinError
    ├── InputError            bad input: a file, a setting, a name, a request a device cannot take
    │   └── DriverNotInstalled
    ├── DataError             data a run needs turned out unusable
    │   ├── DamagedDataError  corrupt or inconsistent (a chunk altered, a shape that disagrees)
    │   └── MissingDataError  absent (a file or folder that is not there)
    ├── DeviceError           a device answered something unexpected
    │   ├── DeviceTimeout
    │   └── DeviceDisconnected
    ├── StoreBusy             another writer holds the store
    └── SessionInterrupted    a capture stopped on a signal

A message says what is wrong and what was expected. What the user can do about it is the
exception's :attr:`SpectwinError.remedy`, a :class:`Remedy`, which each front end words in its own
terms. :class:`InputError` is also a ``ValueError``, as Python's own refusals of a bad argument
are: every device, simulated or real, refuses a request outside its range with one.
"""

from __future__ import annotations

import enum

__all__ = [
    "DamagedDataError",
    "DataError",
    "DeviceDisconnected",
    "DeviceError",
    "DeviceTimeout",
    "DriverNotInstalled",
    "InputError",
    "MissingDataError",
    "Remedy",
    "SessionInterrupted",
    "SpectwinError",
    "StoreBusy",
]


class Remedy(enum.Enum):
    """What the user can do about an error; the message itself says only what is wrong.

    Attributes
    ----------
    resume
        Continue the stopped work: its done steps are kept.
    resume_or_rename
        The store exists: continue it, or write to another name.
    finish_processing
        The BTF store is incomplete: process its pending pairs.
    reprocess_pairs
        Pairs of the BTF store are damaged: process them again (resuming flags them pending).
    process
        A BTF store is expected: processing a capture makes one.
    export_btf
        An export of a BTF store (spectral EXR slices and their index) is expected.
    calibrate
        A calibration file is expected: calibrating a calibration capture writes one.
    calibrate_texels
        Calibrate with the texture size of the run.
    calibrate_leds
        Calibrate under the LEDs of the run.
    capture_gonio_calibration, capture_gonio_run, capture_dome_calibration, capture_dome_run
        A capture of that program is expected.
    reinstall
        The installed package lacks its data: install it again.
    install_rotation_stage
        Install the optional dependencies of the rotation stage's driver.
    """

    resume = "resume"
    resume_or_rename = "resume-or-rename"
    finish_processing = "finish-processing"
    reprocess_pairs = "reprocess-pairs"
    process = "process"
    export_btf = "export-btf"
    calibrate = "calibrate"
    calibrate_texels = "calibrate-texels"
    calibrate_leds = "calibrate-leds"
    capture_gonio_calibration = "capture-gonio-calibration"
    capture_gonio_run = "capture-gonio-run"
    capture_dome_calibration = "capture-dome-calibration"
    capture_dome_run = "capture-dome-run"
    reinstall = "reinstall"
    install_rotation_stage = "install-rotation-stage"


class SpectwinError(Exception):
    """The root of spectwin's exceptions: the message names what was wrong and what was expected.

    Parameters
    ----------
    *args
        The message (as for ``Exception``).
    remedy
        What the user can do about it, if anything; else the class's.

    Attributes
    ----------
    remedy
        A :class:`Remedy` or ``None``.
    """

    remedy: Remedy | None = None

    def __init__(self, *args: object, remedy: Remedy | None = None):
        super().__init__(*args)
        if remedy is not None:
            self.remedy = remedy


class InputError(SpectwinError, ValueError):
    """Input that is malformed or does not fit: a file, a setting, a name, a request a device
    cannot take (e.g. a wavelength outside its range). The message names the field and what was
    expected."""


class DriverNotInstalled(InputError):
    """A real device whose driver library is not installed: the message names the library and
    the optional dependencies that bring it."""


class DataError(SpectwinError):
    """Data that a run needs turned out unusable."""


class DamagedDataError(DataError):
    """Data that is corrupt or inconsistent: a store's chunk deleted, truncated or altered, a
    ``zarr.json`` gone, a file whose contents disagree with each other or with what reads them.
    The message names the path and what is wrong."""


class MissingDataError(DataError):
    """Data that is not there: a data file or folder that does not exist."""


class DeviceError(SpectwinError):
    """A device answered something unexpected or reported an error. A capture stopped by one
    keeps the frames it wrote and resumes from the next."""

    remedy = Remedy.resume


class DeviceTimeout(DeviceError):
    """A device did not answer in time."""


class DeviceDisconnected(DeviceError):
    """A device dropped off the bus; it may come back after staging it again."""


class StoreBusy(SpectwinError):
    """Another writer holds the store's lock (:mod:`hwbridge.lock`); the message names it. Once
    that writer has stopped, the store's work resumes."""

    remedy = Remedy.resume


class SessionInterrupted(SpectwinError):
    """A capture stopped on SIGINT or SIGTERM between two frames (:mod:`hwbridge.session`).

    Attributes
    ----------
    store
        The store's path.
    done, total
        Plan steps in the store (written and flagged done) and in the plan.
    """

    remedy = Remedy.resume

    def __init__(self, store: object, done: int, total: int):
        super().__init__(f"{store}: interrupted after {done} of {total} frames")
        self.store, self.done, self.total = store, done, total
