"""A dome run's capture store as its processing reads it: images, frames and joint groups.

A ``dome-run`` store (layout: :mod:`hwbridge.dome_layout`) holds per stage position an alignment
frame of every camera, then per LED every RGB camera's HDR set and the spectral camera's
scheduled bands. An *image* of the run is one stage position and LED, ``(view_id, light_id)``,
seen by every RGB camera; the images are counted in capture order (the LED counter of the band
schedule, over the stage positions).

Groups (thesis 10.1.2, 10.4.2): the images of one cycle of the band schedule hold every band
once (the noisiest twice), so the images are reconstructed jointly cycle by cycle
(:func:`joint_groups`); a last cycle that misses bands joins the one before.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hwbridge.dome_layout import SPECTRAL_CAMERA
from hwbridge.schema import DomeRigAttrs, recorded
from hwbridge.store import CaptureStore
from recon.calibration.dome_capture import dome_rig
from recon.errors import InputError

__all__ = ["DomeRun", "joint_groups", "open_dome_run"]

_FIELDS = ("kind", "view_id", "light_id", "exposure_s", "band_nm")


@dataclass(frozen=True)
class DomeRun:
    """What processing needs of a dome run besides its frames.

    Attributes
    ----------
    capture_path
        The run's capture store.
    rig
        Its ``rig`` attribute (a run's: ``material``, ``sample_size_m`` and
        ``stage_positions`` are set).
    rgb_cameras
        The RGB cameras, in the store's order.
    images
        ``(view_id, light_id)`` of every image, in capture order.
    index
        Per camera its index fields (:data:`hwbridge.dome_layout` names).
    """

    capture_path: Path
    rig: DomeRigAttrs
    rgb_cameras: tuple[str, ...]
    images: tuple[tuple[int, int], ...]
    index: dict[str, dict[str, np.ndarray]]

    @property
    def material(self) -> str:
        return str(self.rig.material)

    @property
    def sample_size_m(self) -> float:
        return float(recorded(self.rig.sample_size_m, f"{self.capture_path}: rig.sample_size_m"))

    @property
    def bands_nm(self) -> np.ndarray:
        return np.asarray(self.rig.bands_nm, np.float64)

    @property
    def views(self) -> list[int]:
        """The stage positions, in capture order."""
        return list(dict.fromkeys(view for view, _ in self.images))

    def slots(self, camera: str, kind: str, view: int, light: int | None = None) -> np.ndarray:
        """Frame slots of ``camera`` of ``kind`` at stage position ``view`` (and LED ``light``),
        in capture order."""
        index = self.index[camera]
        mask = (index["kind"] == kind) & (index["view_id"] == view)
        if light is not None:
            mask &= index["light_id"] == light
        return np.flatnonzero(mask)

    def image_bands(self, image: int) -> list[int]:
        """Indices into :attr:`bands_nm` of the spectral frames of image ``image``."""
        view, light = self.images[image]
        taken = self.index[SPECTRAL_CAMERA]["band_nm"][
            self.slots(SPECTRAL_CAMERA, "sample", view, light)
        ]
        return [int(np.argmin(np.abs(self.bands_nm - band))) for band in taken]


def joint_groups(
    bands_per_image: Sequence[Sequence[int]], cycle: int, n_bands: int
) -> list[list[int]]:
    """Images in groups of ``cycle`` consecutive ones (module docstring); a last group without
    every one of ``n_bands`` bands joins the one before.

    Examples
    --------
    >>> joint_groups([[0], [1], [0], [1], [0]], 2, 2)
    [[0, 1], [2, 3, 4]]
    """
    count = len(bands_per_image)
    if cycle < 1 or count == 0:
        raise InputError(f"cycle, images: expected at least one each, got {cycle}, {count}")
    groups = [list(range(start, min(start + cycle, count))) for start in range(0, count, cycle)]
    last = {band for image in groups[-1] for band in bands_per_image[image]}
    if len(groups) > 1 and len(last) < n_bands:
        merged = groups.pop()
        groups[-1] += merged
    return groups


def open_dome_run(capture: str | Path | CaptureStore) -> DomeRun:
    """Read a dome run's attributes and index; refuse a store that is not one, naming what it
    lacks, before any frame is read."""
    store = capture if isinstance(capture, CaptureStore) else CaptureStore.open(capture)
    rig = dome_rig(store, "dome-run")
    cameras = list(rig.geometry.cameras)
    if SPECTRAL_CAMERA not in cameras or len(cameras) < 2:
        raise InputError(
            f"{store.path}: expected RGB cameras and the {SPECTRAL_CAMERA!r} camera, got {cameras}"
        )
    index = {camera: store.index(camera, _FIELDS) for camera in cameras}
    spectral = index[SPECTRAL_CAMERA]
    samples = spectral["kind"] == "sample"
    images = tuple(
        dict.fromkeys(
            zip(
                spectral["view_id"][samples].tolist(),
                spectral["light_id"][samples].tolist(),
                strict=True,
            )
        )
    )
    return DomeRun(
        capture_path=store.path.resolve(),
        rig=rig,
        rgb_cameras=tuple(camera for camera in cameras if camera != SPECTRAL_CAMERA),
        images=images,
        index=index,
    )
