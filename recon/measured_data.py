"""Read the measured data that ships with spectwin (package data of ``recon``: ``recon/data``).

Spectra are CSV files whose first column is ``wavelength_nm`` and whose ``#`` lines name the
source; every data folder has a ``SOURCES.md`` naming origin and licence
(``recon/data/spectra/SOURCES.md``, ``recon/data/real/llanos2019/SOURCES.md``).
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np
from scipy import io

from recon.errors import DamagedDataError, InputError, MissingDataError, Remedy
from recon.spectra import SampledSpectra, WavelengthGrid

__all__ = [
    "Llanos2019Multispectral",
    "camera_name",
    "camera_names",
    "data_path",
    "read_camera_sensitivities",
    "read_llanos2019_multispectral",
    "read_spectra_columns",
    "read_spectra_csv",
]


def data_path(relative_path: str | Path = "") -> Path:
    """The path of a file or folder of spectwin's measured data (``recon/data``).

    Parameters
    ----------
    relative_path
        Path inside the data folder, e.g. ``"real/llanos2019"``; empty for the folder itself.

    Raises
    ------
    MissingDataError
        When the file or folder is not part of the installed package.
    """
    path = Path(str(resources.files("recon").joinpath("data"))) / relative_path
    if not path.exists():
        raise MissingDataError(
            f"measured data {relative_path!s} is missing from the installed package (expected "
            f"{path})",
            remedy=Remedy.reinstall,
        )
    return path


def read_spectra_csv(relative_path: str | Path) -> SampledSpectra:
    """Read a spectra CSV of spectwin's data (e.g. ``"spectra/sensors/nikon_d70_rgb.csv"``).

    Parameters
    ----------
    relative_path
        Path inside ``recon/data``, or an absolute path to a CSV file of the same layout.

    Returns
    -------
    SampledSpectra
        Values ``(n_columns, K)`` named by the CSV header, on the file's wavelengths.
    """
    path = Path(relative_path) if Path(relative_path).is_absolute() else data_path(relative_path)
    if not path.is_file():
        raise MissingDataError(f"spectra file {path} does not exist: expected a CSV file")
    lines = [line for line in path.read_text().splitlines() if line and not line.startswith("#")]
    header = [column.strip() for column in lines[0].split(",")]
    if header[0] != "wavelength_nm" or len(header) < 2:
        raise InputError(f"{path}: expected a header 'wavelength_nm,<name>,...', got {lines[0]!r}")
    table = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    return SampledSpectra(WavelengthGrid(table[:, 0]), table[:, 1:].T, tuple(header[1:]))


def read_spectra_columns(
    path: str | Path, columns: tuple[str, ...], *, low_nm: float, high_nm: float
) -> SampledSpectra:
    """Named columns of a spectrometer's CSV export (a ``Wavelength`` column first, one column
    per measured spectrum), kept between ``low_nm`` and ``high_nm``.

    Parameters
    ----------
    path
        The CSV file.
    columns
        The columns to read, in the order of the result's rows.
    low_nm, high_nm
        The wavelength range kept.

    Returns
    -------
    SampledSpectra
        Values ``(len(columns), K)`` named by ``columns``.
    """
    path = Path(path)
    if not path.is_file():
        raise MissingDataError(f"spectra file {path} does not exist: expected a CSV file")
    lines = path.read_text().splitlines()
    header = [column.strip() for column in lines[0].split(",")]
    missing = [name for name in columns if name not in header]
    if header[0] != "Wavelength" or missing:
        raise DamagedDataError(f"{path}: expected a 'Wavelength' column and {missing}")
    table = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    keep = (table[:, 0] >= low_nm) & (table[:, 0] <= high_nm)
    if keep.sum() < 2:
        raise DamagedDataError(f"{path}: fewer than 2 wavelengths in [{low_nm}, {high_nm}] nm")
    values = table[keep][:, [header.index(name) for name in columns]].T
    return SampledSpectra(WavelengthGrid(table[keep, 0]), values, tuple(columns))


_CAMERAS_FOLDER = Path("spectra") / "cameras_rawtoaces"


def camera_names() -> tuple[str, ...]:
    """The names of the 51 cameras whose measured RGB sensitivities ship with spectwin, sorted.

    The data are AcademySoftwareFoundation/rawtoaces-data's (Apache-2.0): DSLR, mirrorless and
    cinema cameras, 380-780 nm in 5 nm steps, relative units (``recon/data/spectra/SOURCES.md``).
    A name is the file's with spaces for underscores, e.g. ``"Canon EOS 5D Mark II"``.
    """
    return tuple(
        sorted(path.stem.replace("_", " ") for path in data_path(_CAMERAS_FOLDER).glob("*.csv"))
    )


def camera_name(name: str) -> str:
    """``name`` as :func:`camera_names` spells it (underscores for spaces are accepted).

    Raises
    ------
    InputError
        For a name that is not one of the cameras, naming the closest ones.
    """
    names = camera_names()
    wanted = str(name).replace("_", " ")
    if wanted not in names:
        close = difflib.get_close_matches(wanted, names, n=3, cutoff=0.5)
        hint = f"; closest: {', '.join(close)}" if close else f"; e.g. {names[0]!r}"
        raise InputError(
            f"camera {name!r}: expected one of the {len(names)} measured cameras{hint}"
        )
    return wanted


def read_camera_sensitivities(name: str) -> SampledSpectra:
    """Measured RGB spectral sensitivities of the camera ``name`` (see :func:`camera_name`).

    Returns
    -------
    SampledSpectra
        ``(3, 81)`` rows R, G, B on 380-780 nm in 5 nm steps, relative units.
    """
    file_name = camera_name(name).replace(" ", "_")
    spectra = read_spectra_csv(_CAMERAS_FOLDER / f"{file_name}.csv")
    if spectra.names != ("R", "G", "B"):
        raise DamagedDataError(
            f"camera {name!r}: expected the columns R, G, B, got {spectra.names}"
        )
    return spectra


_LLANOS2019_FOLDER = Path("real") / "llanos2019" / "multispectral_images"


@dataclass(frozen=True, eq=False)
class Llanos2019Multispectral:
    """A real 7-band image of a ColorChecker and the RGB camera that saw it (Llanos 2019).

    The image is Llanos's ``d2_colorChecker30cm_dHyper.mat``: a Point Grey Flea3 (Sony ICX655
    CCD) photographed the chart under a projector through 7 band-pass filters, and each band
    image is the bilinearly demosaiced Green channel of that capture, i.e. the image of a
    hypothetical monochrome camera with the Green channel's sensitivity, clipped to zero
    (``sensor.mat`` ``channel_mode`` = false). ``sensor.mat``'s ``sensor_map`` holds the Red,
    Green and Blue sensitivities at the 7 bands relative to Green (so the Green row is constant),
    normalized so that an image of ones gives Green = 1 under Llanos's image formation. That
    formation integrates over wavelength with trapezoidal weights on the band grid (25, 50, ...,
    50, 25 nm): :attr:`response` includes them, and ``image @ response`` reproduces the Green
    samples of Llanos's own simulated RAW image ``d2_colorChecker30cm_raw.mat`` (to about
    1e-8).

    Attributes
    ----------
    image
        ``(H, W, 7)`` float64 (342 x 408 x 7), relative radiance, non-negative.
    wavelengths_nm
        ``(7,)`` float64 nominal filter centres, 400 to 700 nm in 50 nm steps.
    sensor_map
        ``(7, 3)`` float64 relative RGB sensitivities per nm at the bands (``sensor_map.T`` of
        the file; columns R, G, B).
    source
        The ``.mat`` file of the image.
    """

    image: np.ndarray
    wavelengths_nm: np.ndarray
    sensor_map: np.ndarray
    source: Path

    @property
    def grid(self) -> WavelengthGrid:
        """The band wavelengths as a ``WavelengthGrid``."""
        return WavelengthGrid(self.wavelengths_nm)

    @property
    def response(self) -> np.ndarray:
        """``(7, 3)`` camera response with ``rgb = image @ response`` (Eq. 6.1, Eq. 7.1).

        ``sensor_map`` times the grid's trapezoidal quadrature weights in nm (the discrete band
        integral of :func:`recon.spectra.band_integrals`).
        """
        return self.sensor_map * self.grid.quadrature_weights()[:, None]


def _load_mat(path: Path, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    if not path.is_file():
        raise MissingDataError(f"Llanos 2019 data file {path} does not exist")
    contents = io.loadmat(path)
    missing = [name for name in names if name not in contents]
    if missing:
        raise DamagedDataError(f"{path}: expected the variables {list(names)}, missing {missing}")
    return {name: contents[name] for name in names}


def read_llanos2019_multispectral() -> Llanos2019Multispectral:
    """Read Llanos's 7-band ColorChecker image and camera sensitivities (spectwin's data).

    Files: ``real/llanos2019/multispectral_images/d2_colorChecker30cm_dHyper.mat``
    (``I_hyper``) and ``sensor.mat`` (``bands``, ``sensor_map``); B. Llanos, University of
    Alberta, 2019, Boost Software License 1.0 (see ``recon/data/real/llanos2019/SOURCES.md``).
    A real multispectral image and the RGB response that goes with it, for the sparse-to-dense
    experiments of thesis chapter 7 on real data.

    Returns
    -------
    Llanos2019Multispectral
        See its description for the meaning and units of the arrays.
    """
    folder = data_path(_LLANOS2019_FOLDER)
    image_path = folder / "d2_colorChecker30cm_dHyper.mat"
    image = np.asarray(_load_mat(image_path, ("I_hyper",))["I_hyper"], dtype=np.float64)
    sensor = _load_mat(folder / "sensor.mat", ("bands", "sensor_map"))
    wavelengths = np.asarray(sensor["bands"], dtype=np.float64).ravel()
    sensor_map = np.ascontiguousarray(np.asarray(sensor["sensor_map"], dtype=np.float64).T)
    bands = wavelengths.size
    if image.ndim != 3 or image.shape[-1] != bands or sensor_map.shape != (bands, 3):
        raise DamagedDataError(
            f"{folder}: expected I_hyper (H, W, K), bands (K,) and sensor_map (3, K), got "
            f"{image.shape}, {wavelengths.shape} and {sensor_map.T.shape}"
        )
    for array in (image, wavelengths, sensor_map):
        array.setflags(write=False)
    return Llanos2019Multispectral(image, wavelengths, sensor_map, image_path)
