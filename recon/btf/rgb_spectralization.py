"""An RGB BTF spectralized from spot spectra measured at some texels of some direction pairs
(thesis section 10.1: spectral BTFs from RGB BTFs; Eq. 6.9/6.10 over the BTF's texels and
pairs).

The spots: a CSV ``pair,x,y,<nm>,<nm>,...`` (:func:`read_btf_spots`): per spot the pair's index
in the BTF's direction order, the texel's column ``x`` and row ``y`` of the stored texture (after
any ``texels`` reduction of the import) and its spectrum (a reflectance factor: a white
Lambertian reads 1). The camera's response: by name among the shipped cameras or a CSV
(:func:`recon.image_spectralization.camera_response`); the images' decoded, linear values are
taken as that camera's linear values, up to a smooth factor per channel (the light's shape and
level in it, the exposure) fitted to the spots
(:func:`recon.image_spectralization.camera_fit.camera_term`).

Design (:data:`DESIGNS`). The reflectance of a texel changes little in shape between pairs but
much in scale (shading, foreshortening, the specular lobe); a spot measured at one pair says
most of what the texel is at every other pair. ``"joint"`` (the default) reconstructs every pair
at once (Eq. 6.10 over the stacked ``(n_pairs, H, W)`` texels) with the dynamic-range
compression of Eq. 10.2 at :math:`p_{dyn} = 1`: the prior (Eq. 6.3, in its regression form,
:data:`PRIOR`) then holds alike :math:`S_i / \\sum_c V_i^c`, the spectra with their scale divided
out, and the appearance graph
(RGBXY, Eq. 6.5, on those scaled values) links texels of one chromaticity within a pair and, as
the texel coordinates are shared, the same texel across pairs: a spot's spectrum reaches the
texel at every pair, rescaled by its brightness there. ``"per_pair"``, the simpler alternative,
spectralizes each pair's image on its own (Eq. 6.10, :math:`p_{dyn} = 0`) from the spots carried
to it texel by texel, each scaled by the ratio of the texel's camera sums at the two pairs.
``benchmarks/btf_spectra.py`` compares them (BENCHMARKS.md, "Spectral BTFs from RGB BTFs and
spot spectra").

References
----------
- The thesis, Eq. 6.3, 6.5, 6.8, 6.9, 6.10, 10.2 and section 10.1.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from recon.errors import InputError
from recon.image_spectralization.camera_fit import MAX_DEGREE, camera_term
from recon.image_spectralization.run import solve_grid
from recon.image_spectralization.spots import read_spot_table
from recon.spectra import SampledSpectra, WavelengthGrid, resample
from recon.spectralize.solve import DYNAMIC_FLOOR, EnergyWeights, PointSpectra, reconstruct

__all__ = [
    "DESIGNS",
    "ENERGY",
    "MAX_TEXELS",
    "MIN_SPOTS",
    "PRIOR",
    "BTFSpots",
    "SpectralizedBTF",
    "read_btf_spots",
    "check_rgb",
    "check_spots",
    "pair_brightness",
    "spectralize_rgb_btf",
]

DESIGNS = ("joint", "per_pair")
"""The ways of spreading the spots over the BTF (module description)."""
MIN_SPOTS = 3
"""Fewest spots: the gains of the three channels are fitted to them."""
MAX_TEXELS = 4_000_000
"""Most texels over all pairs of one joint solve (about 4 GB of solver memory at 33 bands);
larger BTFs are refused, to be reduced with ``texels``."""
_P_DYN = {"joint": 1.0, "per_pair": 0.0}
ENERGY: dict[str, Any] = {
    "appearance": "rgbxy",
    "neighbours": 3,
    "weights": EnergyWeights(delta=0.0),
}
"""The energy of every design besides the prior and the data (Eq. 6.5, 6.10, 6.11): the RGBXY
appearance space, three neighbours, equal primed weights, no smoothness term."""
PRIOR = "regression"
"""The prior of Eq. 6.3 in every design: the spectra minus the regression from camera values
fitted to the spots (with the flat spectrum of the neutral interface reflection held, unless
``neutral=False``). On the twin's lego (3 x 3 pairs, 32 texels, spots at 1 % of every pair's
texels, a gain per channel, free base) ``"joint"`` reached 2.9 % (Eq. 6.8) with it and 7.6 % with
the plain prior; with all spots at one pair 15 % and 144 %."""


@dataclass(frozen=True, eq=False)
class BTFSpots:
    """``where`` ``(m, 3)`` int (pair, x, y) of the spots and their ``spectra`` (``m`` rows),
    read from ``source``."""

    where: np.ndarray
    spectra: SampledSpectra
    source: str

    def flat_texels(self, shape: tuple[int, int, int]) -> np.ndarray:
        """Row-major indices of the spots in a BTF of ``shape`` ``(n_pairs, H, W)``, refusing
        spots outside it."""
        pairs, height, width = shape
        pair, x, y = self.where.T
        for name, values, size in (("pair", pair, pairs), ("x", x, width), ("y", y, height)):
            outside = (values < 0) | (values >= size)
            if outside.any():
                first = int(np.argmax(outside))
                raise InputError(
                    f"spots {self.source}: {int(outside.sum())} spot(s) with {name} outside "
                    f"0..{size - 1}, the first {name}={values[first]} (row {first + 2}); the BTF "
                    f"has {pairs} pairs of {width} x {height} texels"
                )
        return np.asarray((pair * height + y) * width + x)


def read_btf_spots(path: str | Path) -> BTFSpots:
    """Read the spots CSV ``pair,x,y,<nm>,...`` (module description; lines starting with
    ``#`` are comments).

    Returns
    -------
    BTFSpots

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> path = Path(tempfile.mkdtemp()) / "spots.csv"
    >>> _ = path.write_text("pair,x,y,400,500,600\\n2,3,4,0.1,0.2,0.3\\n")
    >>> read_btf_spots(path).where.tolist()
    [[2, 3, 4]]
    """
    where, spectra = read_spot_table(path, ("pair", "x", "y"), "texel")
    return BTFSpots(where, spectra, str(path))


@dataclass(frozen=True, eq=False)
class SpectralizedBTF:
    """The spectral BTF and how it was made.

    Attributes
    ----------
    cube
        ``(n_pairs, H, W, K)`` float32 reflectance factors (the spots' unit), non-negative.
    grid
        Their wavelengths.
    design
        One of :data:`DESIGNS`.
    gains
        ``(3,)`` the gain per channel fitted to the spots (the mean of the fitted factor,
        :class:`recon.image_spectralization.camera_fit.CameraTerm`).
    fit_residual_pct
        ``(3,)`` relative RMS residual of that fit per channel, %.
    notes
        What was done to the inputs beyond reading them.
    """

    cube: np.ndarray
    grid: WavelengthGrid
    design: str
    gains: np.ndarray
    fit_residual_pct: np.ndarray
    notes: tuple[str, ...]


def _carried_spots(
    rgb: np.ndarray, pixels: np.ndarray, spectra: np.ndarray, pair: int
) -> tuple[np.ndarray, np.ndarray]:
    """The spots carried to ``pair`` (``"per_pair"``): one per texel (the spot at ``pair``
    itself where there is one, else the first), scaled by the texel's camera sum at ``pair``
    over its sum at the spot's own pair (sums raised to the floor of Eq. 10.2,
    :data:`recon.spectralize.solve.DYNAMIC_FLOOR`)."""
    count, height, width, _ = rgb.shape
    sums = rgb.sum(axis=-1).reshape(count, height * width)
    sums = np.maximum(sums, DYNAMIC_FLOOR * max(float(sums.mean()), np.finfo(float).tiny))
    own, texel = np.divmod(pixels, height * width)
    order = np.lexsort((own != pair, texel))  # per texel, the spot at ``pair`` first
    texels, first = np.unique(texel[order], return_index=True)
    chosen = order[first]
    ratio = sums[pair, texels] / sums[own[chosen], texels]
    return pair * height * width + texels, spectra[chosen] * ratio[:, None]


def check_spots(
    spots: BTFSpots, response: SampledSpectra, shape: tuple[int, int, int]
) -> tuple[np.ndarray, WavelengthGrid, list[str]]:
    """The spots' flat texel indices in a BTF of ``shape`` ``(n_pairs, H, W)``, the grid to
    reconstruct on and notes on it (:func:`recon.image_spectralization.run.solve_grid`),
    refusing spots outside the BTF, fewer than :data:`MIN_SPOTS` or spectra that do not cover
    the response: what can be checked before the images are read."""
    pixels = spots.flat_texels(shape)
    if pixels.size < MIN_SPOTS:
        raise InputError(
            f"spots {spots.source}: {pixels.size} spot(s); expected at least {MIN_SPOTS} (a gain "
            "per channel is fitted to them)"
        )
    grid, notes = solve_grid(spots.spectra, response)
    return pixels, grid, notes


def _with_unlit_texels(
    rgb: np.ndarray, pixels: np.ndarray, spectra: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The spots and, as spots of zero reflectance, the texels whose camera values are all
    zero (shadowed, occluded; ``"joint"``): a non-negative spectrum the camera does not see at
    all is zero on the bands it is sensitive to. Left to the solve, such a texel takes the
    metameric black of its neighbours scaled by the floor of Eq. 10.2 (on the twin's lego, with
    spots at one pair, 44 % Eq. 6.8 over the 14 % of texels in shadow)."""
    unlit = np.flatnonzero(np.all(rgb.reshape(-1, 3) <= 0, axis=1))
    unlit = np.setdiff1d(unlit, pixels)
    return (
        np.concatenate([pixels, unlit]),
        np.concatenate([spectra, np.zeros((unlit.size, spectra.shape[1]))]),
    )


def pair_brightness(rgb: np.ndarray) -> np.ndarray:
    """``(n_pairs, 1)`` the mean camera sum of each pair (1 for a black pair). ``"joint"``
    divides each pair by it, spots included, and multiplies the result back: Eq. 10.2 at
    :math:`p_{dyn} = 1` is blind to such a factor except through its floor (a share of the mean
    sum, :data:`recon.spectralize.solve.DYNAMIC_FLOOR`), which would otherwise be set by the
    brightest pairs (a mirror highlight) and flatten every texel of the dark ones."""
    sums = rgb.sum(axis=-1).mean(axis=(1, 2))
    return np.where(sums > 0, sums, 1.0)[:, None]


def check_rgb(rgb: np.ndarray) -> np.ndarray:
    """``rgb`` as float64 ``(n_pairs, H, W, 3)`` camera values, refusing another shape or more
    than :data:`MAX_TEXELS` texels over all pairs."""
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.ndim != 4 or rgb.shape[3] != 3:
        raise InputError(f"rgb: expected (n_pairs, H, W, 3) camera values, got {rgb.shape}")
    if rgb.shape[0] * rgb.shape[1] * rgb.shape[2] > MAX_TEXELS:
        raise InputError(
            f"rgb: {rgb.shape[0]} pairs of {rgb.shape[2]} x {rgb.shape[1]} texels; expected at "
            f"most {MAX_TEXELS} texels over all pairs: resample the texture to fewer texels"
        )
    return rgb


def spectralize_rgb_btf(
    rgb: np.ndarray,
    spots: BTFSpots,
    response: SampledSpectra,
    *,
    design: str = "joint",
    neutral: bool = True,
    camera_degree: int = MAX_DEGREE,
    tol: float = 1e-6,
) -> SpectralizedBTF:
    """Spectralize an RGB BTF from spot spectra (module description; Eq. 6.10, 10.2).

    Parameters
    ----------
    rgb
        ``(n_pairs, H, W, 3)`` linear camera values, pairs in the BTF's direction order.
    spots
        Spot spectra at texels of some pairs (:func:`read_btf_spots`).
    response
        ``(3, K')`` the camera's spectral response, rows R, G, B, any scale.
    design
        One of :data:`DESIGNS`.
    neutral
        Hold the regression prior's base to the dichromatic model: the flat reflectance factor
        of a dielectric's interface reflection maps to itself (``neutral`` of
        :func:`recon.spectralize.solve.build_problem`); False fits the base freely.
    camera_degree
        Highest degree of the camera term's smooth factor per channel
        (:func:`recon.image_spectralization.camera_fit.camera_term`); 0: a gain per channel.
    tol
        Relative residual of the solves (:func:`recon.spectralize.solve.reconstruct`).

    Returns
    -------
    SpectralizedBTF
    """
    rgb = check_rgb(rgb)
    if design not in DESIGNS:
        raise InputError(f"design: expected one of {', '.join(DESIGNS)}, got {design!r}")
    pixels, grid, notes = check_spots(spots, response, rgb.shape[:3])
    spectra = resample(spots.spectra, grid, method="box" if notes else "linear").values
    camera = camera_term(
        response, grid, rgb.reshape(-1, 3)[pixels], spectra, max_degree=camera_degree
    )
    r_cam = camera.matrix
    options: dict[str, Any] = {
        **ENERGY,
        "prior": PRIOR,
        "neutral": np.ones(grid.size) if neutral else None,
        "tol": tol,
    }
    if design == "joint":
        exposure = pair_brightness(rgb)
        pixels, spectra = _with_unlit_texels(rgb, pixels, spectra)
        points = PointSpectra(pixels, spectra / exposure[pixels // (rgb.shape[1] * rgb.shape[2])])
        solved = reconstruct(
            rgb / exposure[:, :, None, None],
            r_cam,
            point_spectra=points,
            p_dyn=_P_DYN[design],
            **options,
        )
        values = solved.spectra * exposure[:, :, None, None]
    else:
        values = np.empty((*rgb.shape[:3], grid.size))
        size = rgb.shape[1] * rgb.shape[2]
        for pair in range(rgb.shape[0]):
            carried, scaled = _carried_spots(rgb, pixels, spectra, pair)
            points = PointSpectra(carried - pair * size, scaled)
            values[pair] = reconstruct(
                rgb[pair], r_cam, point_spectra=points, p_dyn=_P_DYN[design], **options
            ).spectra
    cube = np.clip(values, 0.0, None).astype(np.float32)
    return SpectralizedBTF(cube, grid, design, camera.gains, camera.fit_residual_pct, tuple(notes))
