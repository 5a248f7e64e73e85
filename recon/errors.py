"""The exceptions of spectwin, for ``recon``: the tree of :mod:`hwbridge.errors`, whose root is
:class:`SpectwinError` (``hwbridge`` imports no ``recon``, so the tree lives there)."""

from hwbridge.errors import (
    DamagedDataError,
    DataError,
    InputError,
    MissingDataError,
    Remedy,
    SpectwinError,
)

__all__ = [
    "DamagedDataError",
    "DataError",
    "InputError",
    "MissingDataError",
    "Remedy",
    "SpectwinError",
]
