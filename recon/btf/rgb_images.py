"""The images of a measured RGB BTF, one per direction pair, as the import reads them.

Every source of an RGB BTF (a folder with a direction table, :mod:`recon.btf.rgb_import`; the
Bonn archives and files, :mod:`recon.btf.bonn_formats`) is read into an :class:`RGBImageSet`:
the direction pairs' angles and a function that decodes one pair's image to linear RGB, so
that an import holds one image in memory at a time.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from recon.directions import direction
from recon.errors import InputError

__all__ = ["RGBImageSet"]


@dataclass(frozen=True)
class RGBImageSet:
    """The images of an RGB BTF, read one pair at a time.

    Attributes
    ----------
    angles_deg
        ``(N, 4)``: light polar angle, light azimuth, view polar angle, view azimuth of each
        pair, in degrees (:func:`recon.directions.direction`).
    names
        What each pair's image is called in its source (a file name, an archive entry), for
        messages.
    read
        ``read(pair)``: the pair's ``(H, W, 3)`` linear RGB image (row 0 at the top).
    encoding
        How the source stored the values: ``"sRGB"`` (8- or 16-bit, decoded by ``read``) or
        ``"linear"`` (floating point).
    layout
        The source's format (``"image folder"``, ``"UBO2003"``, ``"ATRIUM HDR"``,
        ``"UBO2014"``).
    source
        The folder or file read.
    """

    angles_deg: np.ndarray
    names: tuple[str, ...]
    read: Callable[[int], np.ndarray]
    encoding: str
    layout: str
    source: Path

    def __post_init__(self) -> None:
        polar = self.angles_deg[:, [0, 2]]
        outside = np.flatnonzero(~np.all((polar >= 0) & (polar < 90), axis=1))
        if outside.size:
            first = outside[0]
            raise InputError(
                f"{self.source}: {self.names[first]} has polar angles "
                f"{polar[first, 0]:g}, {polar[first, 1]:g} deg; expected 0 to below 90 (above "
                "the sample)"
            )

    @property
    def n_pairs(self) -> int:
        """The number of direction pairs (images)."""
        return len(self.names)

    def light_dirs(self) -> np.ndarray:
        """``(N, 3)`` the pairs' light directions."""
        return direction(self.angles_deg[:, 0], self.angles_deg[:, 1])

    def view_dirs(self) -> np.ndarray:
        """``(N, 3)`` the pairs' view directions."""
        return direction(self.angles_deg[:, 2], self.angles_deg[:, 3])
