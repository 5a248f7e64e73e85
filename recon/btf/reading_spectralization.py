"""An RGB BTF spectralized from one spectrophotometer reading at 45/0 (thesis section 10.1:
spectral BTFs from RGB BTFs; Eq. 6.9, 6.3, 10.2).

The reading: a CSV ``wavelength_nm,reflectance`` (:func:`read_reading_csv`, the layout of
spectwin's spectra and of spectrometers' exports): one reflectance factor spectrum (a white
Lambertian reads 1) measured by a 45/0 instrument (light at 45 degrees from the normal, view
along it) over its measuring spot. That spot is an area of the sample, not one texel: a
rectangle of the stored texture (:class:`MeasuringSpot`, by default all of it). The reading
belongs to the BTF's pair nearest 45/0 (:func:`reading_pair`; within :data:`TOLERANCE_DEG`).

What it constrains (Eq. 6.9, a device integral): the mean spectrum over the measuring spot at
that pair, :math:`\\frac{1}{|A|} \\sum_{i \\in A} S_{i,l} = r_l` in every band :math:`l`. The
energy is that of the ``"joint"`` design of :mod:`recon.btf.rgb_spectralization` (every pair at
once, Eq. 10.2 at :math:`p_{dyn} = 1`, the RGBXY appearance graph) with this term as its data and
the prior of Eq. 6.3 in its regression form on a map :math:`W` made from the reading
(:func:`reading_regression`): a texel's spectrum is the reading with each part of the spectrum
scaled by how the channel that sees it compares with the spot's mean,

.. math:: B_{i,l} = r_l \\sum_c w_c(l)\\, V_i^c / \\bar V^c, \\qquad
          w_c(l) = \\hat R_c(l) / \\sum_{c'} \\hat R_{c'}(l),

with :math:`\\hat R_c` the camera's response of channel :math:`c` scaled to unit sum and
:math:`\\bar V` the mean camera values over the measuring spot at the reading's pair. Then
:math:`\\bar V W = r`: the map alone meets the reading, and a BTF of one colour whose brightness
varies is recovered exactly at every texel of every pair. Where colours differ, the prior holds
the departures from the map alike between neighbours, the camera term (Eq. 6.2) gives each texel
its camera values and the reading holds the mean. The camera's gains are fitted to the reading
(:func:`recon.image_spectralization.camera_fit.camera_term`, degree 0): three gains to one
spectrum, exactly.
``benchmarks/btf_spectra.py`` compares it with Jakob 2019 upsampling (BENCHMARKS.md, "Spectral
BTFs from RGB BTFs and spot spectra").

References
----------
- The thesis, Eq. 6.2, 6.3, 6.8, 6.9, 6.10, 10.2 and sections 6.1, 10.1.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import sparse

from recon.btf.rgb_spectralization import (
    ENERGY,
    SpectralizedBTF,
    check_rgb,
    pair_brightness,
)
from recon.errors import InputError
from recon.image_spectralization.camera_fit import camera_term
from recon.image_spectralization.run import solve_grid
from recon.image_spectralization.wavelength_table import read_wavelength_table
from recon.spectra import SampledSpectra, resample
from recon.spectralize.solve import DeviceIntegrals, reconstruct

__all__ = [
    "DESIGN",
    "GEOMETRY_DEG",
    "MAX_REFLECTANCE",
    "TOLERANCE_DEG",
    "MeasuringSpot",
    "Reading45",
    "is_reading_csv",
    "read_reading_csv",
    "reading_pair",
    "reading_regression",
    "spectralize_from_reading",
]

DESIGN = "reading_45_0"
"""The design's name in :class:`recon.btf.rgb_spectralization.SpectralizedBTF`."""
GEOMETRY_DEG = (45.0, 0.0)
"""Polar angles of the instrument's light and view (degrees from the sample's normal)."""
TOLERANCE_DEG = 15.0
"""Largest :math:`\\sqrt{(\\theta_l - 45)^2 + \\theta_v^2}` (degrees) of the pair a reading is
given to; the azimuths are free (45/0 instruments light from a ring or any one side)."""
MAX_REFLECTANCE = 1.5
"""Largest reflectance factor accepted in a reading (fluorescent or glossy samples exceed 1)."""
_COLUMN = "reflectance"


@dataclass(frozen=True, eq=False)
class Reading45:
    """One reflectance factor ``spectrum`` (one row) measured at 45/0, read from ``source``."""

    spectrum: SampledSpectra
    source: str


def is_reading_csv(path: str | Path) -> bool:
    """Whether the CSV at ``path`` is a reading (its first line that is not a comment starts
    with ``wavelength_nm``) rather than a spots table."""
    path = Path(path)
    if not path.is_file():
        return False
    try:
        with path.open() as handle:
            first = next(
                (line for line in handle if line.strip() and not line.lstrip().startswith("#")),
                "",
            )
    except UnicodeDecodeError:
        return False
    return first.split(",")[0].strip() == "wavelength_nm"


def read_reading_csv(path: str | Path) -> Reading45:
    """Read a reading ``wavelength_nm,reflectance`` (module description), refusing values
    outside 0..:data:`MAX_REFLECTANCE`.

    Returns
    -------
    Reading45

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> path = Path(tempfile.mkdtemp()) / "reading.csv"
    >>> _ = path.write_text("wavelength_nm,reflectance\\n400,0.2\\n700,0.6\\n")
    >>> read_reading_csv(path).spectrum.values.tolist()
    [[0.2, 0.6]]
    """
    spectrum = read_wavelength_table(path, (_COLUMN,), "reading")
    values = spectrum.values[0]
    outside = (values < 0) | (values > MAX_REFLECTANCE)
    if outside.any():
        first = int(np.argmax(outside))
        raise InputError(
            f"reading {path}: reflectance {values[first]:g} at "
            f"{spectrum.grid.wavelengths_nm[first]:g} nm; expected reflectance factors in "
            f"0..{MAX_REFLECTANCE:g} (a white Lambertian reads 1)"
        )
    return Reading45(spectrum, str(path))


@dataclass(frozen=True)
class MeasuringSpot:
    """The instrument's measuring spot on the stored texture: the rectangle of ``width`` x
    ``height`` texels from column ``x``, row ``y`` (the top-left texel is 0, 0)."""

    x: int
    y: int
    width: int
    height: int

    def texels(self, shape: tuple[int, int]) -> np.ndarray:
        """Row-major indices of its texels in a texture of ``shape`` ``(H, W)``, refusing a
        rectangle that is empty or reaches outside the texture."""
        height, width = shape
        if (
            self.width < 1
            or self.height < 1
            or self.x < 0
            or self.y < 0
            or self.x + self.width > width
            or self.y + self.height > height
        ):
            raise InputError(
                f"measuring spot x={self.x}, y={self.y}, width={self.width}, "
                f"height={self.height}: expected a non-empty rectangle inside the {width} x "
                f"{height} texels of the stored texture"
            )
        rows, columns = np.mgrid[self.y : self.y + self.height, self.x : self.x + self.width]
        return (rows * width + columns).ravel()


def reading_pair(light_dirs: np.ndarray, view_dirs: np.ndarray) -> tuple[int, float]:
    """The pair nearest 45/0 (:data:`GEOMETRY_DEG`) and its distance in degrees
    (:data:`TOLERANCE_DEG`), the first of equally near ones (to a micro-degree).

    Parameters
    ----------
    light_dirs, view_dirs
        ``(n_pairs, 3)`` unit vectors, the sample's normal along +z.

    Raises
    ------
    InputError
        When no pair lies within :data:`TOLERANCE_DEG` of 45/0.
    """
    light = np.degrees(np.arccos(np.clip(np.asarray(light_dirs)[:, 2], -1.0, 1.0)))
    view = np.degrees(np.arccos(np.clip(np.asarray(view_dirs)[:, 2], -1.0, 1.0)))
    # To a micro-degree: the first of equal ones, and 30/0 within 15 degrees.
    distance = np.round(np.hypot(light - GEOMETRY_DEG[0], view - GEOMETRY_DEG[1]), 6)
    pair = int(np.argmin(distance))
    if distance[pair] > TOLERANCE_DEG:
        raise InputError(
            f"reading: no direction pair near 45/0; the nearest, pair {pair} (light at "
            f"{light[pair]:.1f}, view at {view[pair]:.1f} degrees from the normal), is "
            f"{distance[pair]:.1f} degrees away; expected one within {TOLERANCE_DEG:g}"
        )
    return pair, float(distance[pair])


def reading_regression(r_cam: np.ndarray, reading: np.ndarray, mean_rgb: np.ndarray) -> np.ndarray:
    """The map :math:`W` ``(3, K)`` from camera values to spectra made from the reading
    (module description): :math:`W_{c,l} = r_l w_c(l) / \\bar V^c`.

    Parameters
    ----------
    r_cam
        ``(K, 3)`` the camera term (any gain per channel: each channel is scaled to unit sum).
    reading
        ``(K,)`` the reading :math:`r`.
    mean_rgb
        ``(3,)`` the mean camera values :math:`\\bar V` over the measuring spot, positive.

    Examples
    --------
    >>> import numpy as np
    >>> r_cam = np.array([[1.0, 0, 0], [0.5, 0.5, 0], [0, 0, 1]])
    >>> W = reading_regression(r_cam, np.array([0.2, 0.4, 0.6]), np.array([1.0, 2.0, 3.0]))
    >>> (np.array([1.0, 2.0, 3.0]) @ W).tolist()
    [0.2, 0.4, 0.6]
    """
    unit = r_cam / r_cam.sum(axis=0)
    total = unit.sum(axis=1, keepdims=True)
    shares = np.divide(unit, total, out=np.full_like(unit, 1 / 3), where=total > 0)
    return np.asarray((reading[:, None] * shares / mean_rgb[None, :]).T)


def spectralize_from_reading(
    rgb: np.ndarray,
    reading: Reading45,
    response: SampledSpectra,
    *,
    pair: int,
    spot: MeasuringSpot | None = None,
    tol: float = 1e-6,
) -> SpectralizedBTF:
    """Spectralize an RGB BTF from one 45/0 reading (module description; Eq. 6.9, 6.10, 10.2).

    Parameters
    ----------
    rgb
        ``(n_pairs, H, W, 3)`` linear camera values, pairs in the BTF's direction order.
    reading
        The reading (:func:`read_reading_csv`).
    response
        ``(3, K')`` the camera's spectral response, rows R, G, B, any scale.
    pair
        The pair the reading belongs to (:func:`reading_pair`).
    spot
        The measuring spot; None: the whole texture.
    tol
        Relative residual of the solve (:func:`recon.spectralize.solve.reconstruct`).

    Returns
    -------
    SpectralizedBTF
        ``design`` :data:`DESIGN`; ``gains`` fitted to the reading (``fit_residual_pct`` zero:
        three gains meet one spectrum exactly).
    """
    rgb = check_rgb(rgb)
    count, height, width, _ = rgb.shape
    if not 0 <= pair < count:
        raise InputError(f"pair: expected 0..{count - 1} (the BTF's pairs), got {pair}")
    texels = (spot or MeasuringSpot(0, 0, width, height)).texels((height, width))
    grid, notes = solve_grid(reading.spectrum, response)
    values = resample(reading.spectrum, grid, method="box" if notes else "linear").values[0]
    mean_rgb = rgb[pair].reshape(-1, 3)[texels].mean(axis=0)
    if np.any(mean_rgb <= 0):
        raise InputError(
            f"rgb: the measuring spot is black in {'RGB'[int(np.argmin(mean_rgb))]} at pair "
            f"{pair}, the reading's; expected the sample lit there"
        )
    camera = camera_term(response, grid, mean_rgb[None], values[None], max_degree=0)
    r_cam = camera.matrix
    exposure = pair_brightness(rgb)
    average = np.zeros(count * height * width)
    average[pair * height * width + texels] = 1.0 / texels.size
    integrals = sparse.kron(sparse.csr_matrix(average), sparse.identity(grid.size), "csr")
    solved = reconstruct(
        rgb / exposure[:, :, None, None],
        r_cam,
        device_integrals=DeviceIntegrals(integrals, values / exposure[pair]),
        p_dyn=1.0,
        prior="regression",
        regression=reading_regression(r_cam, values, mean_rgb),
        tol=tol,
        **ENERGY,
    )
    cube = np.clip(solved.spectra * exposure[:, :, None, None], 0.0, None).astype(np.float32)
    return SpectralizedBTF(cube, grid, DESIGN, camera.gains, camera.fit_residual_pct, tuple(notes))
