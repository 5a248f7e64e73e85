"""Read Llanos's (2019) real exposure series of a ColorChecker behind band-pass filters.

The capture ships with spectwin in ``recon/data/real/llanos2019`` (B. Llanos, University of
Alberta, 2019, Boost Software License 1.0; see ``SOURCES.md`` and ``captured_images/about.txt``
there): a
Point Grey Flea3 FL3-GE-50S5C (Sony ICX655 CCD, GBRG Bayer mosaic, raw 12-bit) photographed an
X-Rite ColorChecker Classic lit by a projector through 7 band-pass filters (nominally 400 to 700 nm
in 50 nm steps; the spectrometer places their peaks at 398, 438, 498, 544, 595, 640 and 692 nm), at
7 exposure times from 25 ms to 3916 ms, and took dark frames at the same 7 exposure times (2 each).
The frames stored there are reduced copies made by the author's ``DemoDataPreprocessing.m``:
bilinear demosaicing, bilinear resizing to 1/6 (408 x 342), re-mosaicing and conversion to 8 bit
(``im2uint8``). So the values are local averages of the camera's raw response, quantized to 8 bit,
and the black level sits at 0 (the dark frames average 0.001 to 0.006). The file names match the
replay mapping ``hwbridge/mappings/llanos2019.yaml``.

``spectral_data/spectra_averaged.csv`` holds an ASD spectrometer's measurements (350-2500 nm,
1 nm steps): the filters' transmissions (relative to the unfiltered projector light) and the 24
patches' reflectances (relative to a Spectralon tile), the patches in reading order (left to
right, top to bottom), which is also the order of the labels 1-24 of
``colorChecker_labels/d2_colorChecker30cm_550nm_labels.png``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import tifffile
from skimage import io as skimage_io

from hwbridge.store import CaptureStore
from recon.calibration.capture_io import select_frames
from recon.errors import DamagedDataError, InputError, MissingDataError
from recon.measured_data import data_path, read_spectra_columns
from recon.spectra import SampledSpectra

__all__ = [
    "LLANOS2019_PATCH_NAMES",
    "Llanos2019ChartCapture",
    "chart_capture_from_store",
    "read_llanos2019_chart_capture",
    "read_llanos2019_chart_spectra",
]

_FOLDER = Path("real") / "llanos2019"
_CHART = re.compile(r"d2_colorChecker30cm_(?P<band_nm>\d+)nm_(?P<exposure_ms>\d+)ms_.*\.tif")
_DARK = re.compile(r"d2_dark_(?P<exposure_ms>\d+)ms_.*\.tif")
_FILTER_COLUMNS = ("400 nm", "442 nm", "500 nm", "550 nm", "600 nm", "650 nm", "700 nm")

LLANOS2019_PATCH_NAMES: tuple[str, ...] = (
    "dark skin",
    "light skin",
    "blue sky",
    "foliage",
    "blue flower",
    "bluish green",
    "orange",
    "purplish blue",
    "moderate red",
    "purple",
    "yellow green",
    "orange yellow",
    "blue",
    "green",
    "red",
    "yellow",
    "magenta",
    "cyan",
    "white 9.5 (.05 D)",
    "neutral 8 (.23 D)",
    "neutral 6.5 (.44 D)",
    "neutral 5 (.70 D)",
    "neutral 3.5 (1.05 D)",
    "black 2 (1.5 D)",
)
"""Column names of the 24 patches in ``spectra_averaged.csv``, in label order 1-24."""


@dataclass(frozen=True, eq=False)
class Llanos2019ChartCapture:
    """The ColorChecker exposure series and dark frames of Llanos (2019), as stored.

    Attributes
    ----------
    frames
        ``(n_exposures, n_bands, H, W)`` uint8 raw Bayer frames (7 x 7 x 342 x 408), exposures
        increasing, bands increasing.
    exposure_s
        ``(n_exposures,)`` exposure times in seconds (0.025 to 3.916).
    band_nm
        ``(n_bands,)`` nominal filter wavelengths (400 to 700 nm).
    dark_frames
        ``(n_dark, H, W)`` uint8 dark frames.
    dark_exposure_s
        ``(n_dark,)`` their exposure times in seconds.
    patch_labels
        ``(H, W)`` uint8: 0 off the chart's patches, 1-24 the patches in reading order (labels
        drawn on the 550 nm image; the other bands are shifted by chromatic aberration by at
        most a pixel or two, so erode the masks before averaging).
    bayer_pattern
        ``"gbrg"``: the colour of the 2 x 2 tile read row by row.
    """

    frames: np.ndarray
    exposure_s: np.ndarray
    band_nm: np.ndarray
    dark_frames: np.ndarray
    dark_exposure_s: np.ndarray
    patch_labels: np.ndarray
    bayer_pattern: str = "gbrg"

    @property
    def bit_depth(self) -> int:
        """8: the stored copies are 8-bit."""
        return 8

    def channel_index(self) -> np.ndarray:
        """``(H, W)`` int: the colour of each pixel's filter, 0 = R, 1 = G, 2 = B."""
        codes = np.array(["rgb".index(letter) for letter in self.bayer_pattern]).reshape(2, 2)
        height, width = self.patch_labels.shape
        return np.tile(codes, (height // 2 + 1, width // 2 + 1))[:height, :width]


def _match(folder: Path, pattern: re.Pattern[str]) -> list[tuple[Path, dict[str, str]]]:
    if not folder.is_dir():
        raise MissingDataError(f"Llanos 2019 capture folder {folder} does not exist")
    found = []
    for path in sorted(folder.iterdir()):
        match = pattern.fullmatch(path.name)
        if match:
            found.append((path, match.groupdict()))
    if not found:
        raise MissingDataError(f"{folder}: no file matches {pattern.pattern}")
    return found


def read_llanos2019_chart_capture() -> Llanos2019ChartCapture:
    """Read the ColorChecker series, dark frames and patch labels of Llanos (2019).

    Files: ``real/llanos2019/captured_images/images_filtered_light/color_checker/
    d2_colorChecker30cm_<band>nm_<t>ms_*.tif`` (one frame per band and exposure),
    ``captured_images/dark_frames/d2_dark_<t>ms_*.tif`` and
    ``colorChecker_labels/d2_colorChecker30cm_550nm_labels.png`` in spectwin's data.

    Returns
    -------
    Llanos2019ChartCapture
        See its description.
    """
    root = data_path(_FOLDER)
    chart = _match(root / "captured_images" / "images_filtered_light" / "color_checker", _CHART)
    keys = [(int(groups["exposure_ms"]), int(groups["band_nm"])) for _, groups in chart]
    exposures_ms = sorted({key[0] for key in keys})
    bands = sorted({key[1] for key in keys})
    if len(set(keys)) != len(keys) or len(keys) != len(exposures_ms) * len(bands):
        raise DamagedDataError(
            f"{root}: expected one chart frame per band and exposure time, got {len(keys)} frames "
            f"for {len(bands)} bands and {len(exposures_ms)} exposure times"
        )
    images = {key: tifffile.imread(path) for key, (path, _) in zip(keys, chart, strict=True)}
    frames = np.stack([np.stack([images[(t, b)] for b in bands]) for t in exposures_ms])
    dark = _match(root / "captured_images" / "dark_frames", _DARK)
    dark_frames = np.stack([tifffile.imread(path) for path, _ in dark])
    dark_exposure_s = np.array([int(groups["exposure_ms"]) / 1000 for _, groups in dark])
    return _assemble(
        frames,
        np.array(exposures_ms, dtype=np.float64) / 1000,
        np.array(bands, dtype=np.float64),
        dark_frames,
        dark_exposure_s,
        str(root),
    )


def _assemble(
    frames: np.ndarray,
    exposure_s: np.ndarray,
    band_nm: np.ndarray,
    dark_frames: np.ndarray,
    dark_exposure_s: np.ndarray,
    source: str,
) -> Llanos2019ChartCapture:
    """Add the patch labels, check that everything fits together and freeze the arrays."""
    label_path = data_path(_FOLDER) / "colorChecker_labels" / "d2_colorChecker30cm_550nm_labels.png"
    if not label_path.is_file():
        raise MissingDataError(f"Llanos 2019 patch labels {label_path} do not exist")
    labels = np.asarray(skimage_io.imread(label_path))
    if (
        frames.dtype != np.uint8
        or dark_frames.shape[1:] != frames.shape[2:]
        or labels.shape != frames.shape[2:]
        or labels.max() != len(LLANOS2019_PATCH_NAMES)
    ):
        raise DamagedDataError(
            f"{source}: expected uint8 frames, dark frames and 24 patch labels of one shape, got "
            f"{frames.dtype} {frames.shape[2:]}, {dark_frames.shape[1:]} and {labels.shape} with "
            f"{labels.max()} labels"
        )
    labels = labels.astype(np.uint8)
    for array in (frames, dark_frames, labels):
        array.setflags(write=False)
    return Llanos2019ChartCapture(
        frames=frames,
        exposure_s=exposure_s,
        band_nm=band_nm,
        dark_frames=dark_frames,
        dark_exposure_s=dark_exposure_s,
        patch_labels=labels,
    )


def _as_uint8(frames: np.ndarray, source: str) -> np.ndarray:
    if frames.min() < 0 or frames.max() > 255 or np.any(frames != np.round(frames)):
        raise InputError(f"{source}: expected 8-bit frames (integers 0-255)")
    return frames.astype(np.uint8)


def chart_capture_from_store(
    store: str | Path | CaptureStore, camera: str = "flea3"
) -> Llanos2019ChartCapture:
    """The same series read from a capture store, e.g. the replay of ``hwbridge.replay.ingest``
    with the ``llanos2019`` mapping: calibration then reads real frames exactly as it reads
    simulated ones (``recon.calibration.capture_io.select_frames``).

    Parameters
    ----------
    store
        A complete capture store (or its path) with ``chart`` frames at every band and exposure
        time and ``dark`` frames.
    camera
        The camera's name in the store.

    Returns
    -------
    Llanos2019ChartCapture
    """
    chart = select_frames(store, camera, kind="chart")
    bands = np.unique(chart.band_nm)
    exposures = np.unique(chart.exposure_s)
    if len(chart.frames) != bands.size * exposures.size:
        raise InputError(
            f"{camera}: expected one chart frame per band and exposure time, got "
            f"{len(chart.frames)} for {bands.size} bands and {exposures.size} exposure times"
        )
    order = np.lexsort((chart.band_nm, chart.exposure_s))
    frames = chart.frames[order].reshape(exposures.size, bands.size, *chart.frames.shape[1:])
    dark = select_frames(store, camera, kind="dark")
    source = str(store.path if isinstance(store, CaptureStore) else store)
    return _assemble(
        _as_uint8(frames, source),
        exposures,
        bands,
        _as_uint8(dark.frames, source),
        dark.exposure_s,
        source,
    )


def read_llanos2019_chart_spectra(
    low_nm: float = 380.0, high_nm: float = 780.0
) -> tuple[SampledSpectra, SampledSpectra]:
    """The filters' transmissions and the patches' reflectances measured by the spectrometer.

    Parameters
    ----------
    low_nm, high_nm
        The wavelength range kept (1 nm steps); the camera's IR-cut filter and the projector
        make light outside the visible range irrelevant.

    Returns
    -------
    filters : SampledSpectra
        ``(7, K)`` relative transmissions (the filtered over the unfiltered projector light),
        named ``"400 nm"``, ``"442 nm"``, ... as in the file (the second filter is sold as
        450 nm).
    patches : SampledSpectra
        ``(24, K)`` reflectances relative to a Spectralon tile, named as
        :data:`LLANOS2019_PATCH_NAMES` (label order).
    """
    path = data_path(_FOLDER) / "spectral_data" / "spectra_averaged.csv"
    filters = read_spectra_columns(path, _FILTER_COLUMNS, low_nm=low_nm, high_nm=high_nm)
    patches = read_spectra_columns(path, LLANOS2019_PATCH_NAMES, low_nm=low_nm, high_nm=high_nm)
    return filters, patches
