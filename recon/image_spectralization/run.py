"""A user's RGB image spectralized from spot spectra (thesis Eq. 6.10), with the error of every
spot predicted while it was held out (Eq. 6.8).

Steps:

1. The grid: the spots' wavelengths within the response's range (a grid finer than
   :data:`FINEST_STEP_NM` with more than :data:`MAX_BANDS` bands is averaged onto a regular
   grid of that step). The spots must cover at least :data:`MIN_COVERAGE` of every channel's
   response: what the camera sees where no spot was measured would be left to guesswork.
2. The camera term :math:`R_{cam}` (Eq. 6.2, ``(K, 3)``): the response's band integrals on the
   grid, times a smooth factor per channel fitted to the spots
   (:func:`recon.image_spectralization.camera_fit.camera_term`), since the exposure, the
   light over the spots and the response's units are unknown. The relative residual of that
   fit says how well the spots and the image agree.
3. The appearance space and the prior (Eq. 6.3): chosen together by
   :func:`recon.spectralize.choose_appearance` with :data:`FOLDS` folds (RGBXY and the space
   learned from the spots, :mod:`recon.spectralize.learned_appearance`; both priors of each
   fold in one Kronecker solve), or one space given (``appearance``) and only the prior
   chosen, or with ``fast=True`` the thesis's RGBXY space and prior (``"spectra"``) without
   cross-validation. An image of more than :data:`CROSS_VALIDATION_PIXELS` pixels is
   cross-validated in a central window of about that many at full resolution
   (:mod:`recon.image_spectralization.window`), its spots held out; the chosen space's graph
   is then found for the whole image.
4. The solve of Eq. 6.10 (three neighbours, equal primed weights of Eq. 6.11, no smoothness
   term: the settings of the chapter 7 experiments, :mod:`recon.experiments.sparse`) on the
   chosen space's graph, started from the chosen prior's reconstruction of the last fold where
   the whole image was cross-validated (fewer iterations; the same solution within the
   solver's tolerance). In the RGBXY space an image of at least 100 000 pixels is solved
   hierarchically (:mod:`recon.spectralize.hierarchy`): on a lattice of a quarter of the
   pixels and the spots, the others from their nearest solved samples in appearance space,
   which was both faster and closer to the truth than solving every pixel there; the folds of
   step 3 then solve RGBXY on the lattice too, so that its held-out errors are those of the
   reconstruction used. Negative values are clipped to zero.
5. With the cross-validation, the blend with Murakami 2007's kriged estimate
   (:mod:`recon.image_spectralization.kriging_blend`): the kriging weight with which the
   held-out spots are predicted best, 0 (no blend) where the kriged estimate does not help;
   off with ``kriging=False``. It is chosen before the solve of step 4, which a weight of 1
   (the kriged estimate alone) leaves out.

References
----------
- The thesis, Eq. 6.2, 6.3, 6.8, 6.10 and 6.11; chapter 7 (the settings).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from recon.baselines.murakami2007 import default_correlation_length
from recon.errors import InputError
from recon.image_spectralization.camera_fit import MAX_DEGREE, camera_term
from recon.image_spectralization.kriging_blend import (
    blend_with_kriging,
    choose_kriging_weight,
    kriged_estimate,
)
from recon.image_spectralization.spots import SpotSpectra
from recon.image_spectralization.window import CROSS_VALIDATION_PIXELS, cross_validation_window
from recon.spectra import SampledSpectra, WavelengthGrid, resample
from recon.spectralize import hierarchy
from recon.spectralize.appearance import NeighbourGraph
from recon.spectralize.appearance_choice import SPACES, choose_appearance
from recon.spectralize.hierarchy import SAMPLE_STRIDE
from recon.spectralize.learned_appearance import LEARNED_SPACES, fitted_on
from recon.spectralize.solve import EnergyWeights, PointSpectra, graph_for

__all__ = [
    "APPEARANCES",
    "FOLDS",
    "MAX_KRIGED_PIXELS",
    "MIN_COVERAGE",
    "ImageSpectralization",
    "solve_grid",
    "spectralize_image",
]

FOLDS = 3
"""Folds of the cross-validation that chooses the prior and measures every spot's error. Two
folds would save a third of its solves but picked the worse prior on 2 of the 13 cases of
``benchmarks/spectralize_real.py`` (seed 0) where three and five folds picked the better one
(BENCHMARKS.md, "Spectralizing a user's image")."""
MIN_SPOTS = 2 * FOLDS
"""Fewest spots: two per fold."""
MAX_KRIGED_PIXELS = 12_000
"""Most spots blended with the kriged estimate: its system is ``m x m`` (1.2 GB at 12 000);
with more the spectralization is kept alone, with a note. (A ``--mask`` area is one spot.)"""
MIN_COVERAGE = 0.95
"""Share of every channel's response (its integral over wavelength) that the spots' range must
hold."""
MAX_BANDS = 81
FINEST_STEP_NM = 5.0
FAST_PRIOR = "spectra"
"""The prior of ``fast=True``: the thesis's, the spectra themselves held alike (Eq. 6.3)."""
FAST_APPEARANCE = "rgbxy"
"""The appearance space of ``fast=True``: the thesis's RGBXY (Eq. 6.5)."""
APPEARANCES = ("auto", *SPACES)
"""What ``appearance`` may be: ``"auto"`` (chosen by the cross-validation) or one space."""
_ENERGY: dict[str, Any] = {
    "weights": EnergyWeights(delta=0.0),
    "neighbours": 3,
}


@dataclass(frozen=True, eq=False)
class ImageSpectralization:
    """The spectral image and how it was made.

    Attributes
    ----------
    cube
        ``(H, W, K)`` float32 spectra in the spots' unit, non-negative.
    grid
        Their wavelengths.
    prior
        The prior used (``"spectra"`` or ``"regression"``).
    appearance
        The appearance space used (``"rgbxy"`` or ``"learned"``).
    appearance_errors
        Per appearance space tried, the held-out error (Eq. 6.8, %) of its better prior; empty
        without cross-validation or with one space given.
    cross_validated
        Whether the prior was chosen by cross-validation (False: ``fast``).
    kriging_weight
        The kriged estimate's weight in the blend with it (0: no blend).
    held_out_errors
        Per prior, and for the blend with the kriged estimate (``"kriging"`` alone,
        ``"blend"``), the mean error (Eq. 6.8, %) of the spots predicted while held out; empty
        without cross-validation.
    spot_errors
        ``(m,)`` the held-out error (Eq. 6.8, %) of every spot with the prior (and blend)
        used, in the order of the spots, NaN for spots outside the cross-validation's window;
        None without cross-validation.
    gains
        ``(3,)`` the gain per channel fitted to the spots (the mean of the fitted factor,
        :class:`recon.image_spectralization.camera_fit.CameraTerm`).
    fit_residual_pct
        ``(3,)`` relative RMS residual of that fit per channel, %.
    timings_s
        Seconds of the steps taken: the cross-validation, the appearance graph, the solve and
        the kriged estimate (its weight's choice and the blend).
    notes
        What was done to the inputs beyond reading them.
    """

    cube: np.ndarray
    grid: WavelengthGrid
    prior: str
    appearance: str
    appearance_errors: dict[str, float]
    cross_validated: bool
    kriging_weight: float
    held_out_errors: dict[str, float]
    spot_errors: np.ndarray | None
    gains: np.ndarray
    fit_residual_pct: np.ndarray
    timings_s: dict[str, float]
    notes: tuple[str, ...] = field(default_factory=tuple)


def _energy(space: str, pixels: np.ndarray, spectra: np.ndarray) -> dict[str, Any]:
    """The energy options of the solve in the appearance space ``space``, a learned one
    fitted on all the spots."""
    energy = _ENERGY | {"appearance": space}
    return fitted_on(energy, pixels, spectra) if space in LEARNED_SPACES else energy


def _in_window(errors: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """Held-out ``errors`` of the spot pixels ``inside`` the cross-validation's window, in the
    order of all spot pixels, NaN for those outside it."""
    every = np.full(inside.shape, np.nan)
    every[inside] = errors
    return every


def _channel_integrals(response: SampledSpectra, low: float, high: float) -> np.ndarray:
    """Per channel, the share of the response's integral between ``low`` and ``high`` nm."""
    fine = WavelengthGrid(
        np.linspace(response.grid.wavelengths_nm[0], response.grid.wavelengths_nm[-1], 2001)
    )
    values = resample(response, fine).values
    weights = fine.quadrature_weights()
    inside = (fine.wavelengths_nm >= low) & (fine.wavelengths_nm <= high)
    total = values @ weights
    return np.asarray((values[:, inside] @ weights[inside]) / total)


def solve_grid(spots: SampledSpectra, response: SampledSpectra) -> tuple[WavelengthGrid, list[str]]:
    """The wavelengths to reconstruct on (module description, step 1) and notes on them.

    Raises
    ------
    InputError
        When the spots cover less than :data:`MIN_COVERAGE` of a channel's response.
    """
    wavelengths = spots.grid.wavelengths_nm
    low, high = response.grid.wavelengths_nm[[0, -1]]
    shares = _channel_integrals(response, wavelengths[0], wavelengths[-1])
    if np.any(shares < MIN_COVERAGE):
        worst = int(np.argmin(shares))
        raise InputError(
            f"spots: measured over {wavelengths[0]:g}-{wavelengths[-1]:g} nm, which holds "
            f"{100 * shares[worst]:.0f} % of the camera's {'RGB'[worst]} response "
            f"({low:g}-{high:g} nm); expected spectra covering at least "
            f"{100 * MIN_COVERAGE:.0f} % of every channel"
        )
    kept = wavelengths[(wavelengths >= low) & (wavelengths <= high)]
    notes = []
    if kept.size < 2:
        raise InputError(
            f"spots: fewer than 2 of their wavelengths lie within the response's {low:g}-"
            f"{high:g} nm"
        )
    if kept.size > MAX_BANDS and np.mean(np.diff(kept)) < FINEST_STEP_NM:
        start = FINEST_STEP_NM * np.ceil(kept[0] / FINEST_STEP_NM)
        stop = FINEST_STEP_NM * np.floor(kept[-1] / FINEST_STEP_NM)
        grid = WavelengthGrid.regular(start, stop, FINEST_STEP_NM)
        notes.append(f"spot spectra averaged from {kept.size} wavelengths onto {grid.describe()}")
        return grid, notes
    return WavelengthGrid(kept), notes


def spectralize_image(
    rgb: np.ndarray,
    spots: SpotSpectra,
    response: SampledSpectra,
    *,
    fast: bool = False,
    appearance: str = "auto",
    kriging: bool = True,
    camera_degree: int = MAX_DEGREE,
    tol: float = 1e-6,
    cross_validation_pixels: int | None = CROSS_VALIDATION_PIXELS,
    sample_stride: int = SAMPLE_STRIDE,
    progress: bool = False,
) -> ImageSpectralization:
    """Spectralize ``rgb`` from the spot spectra (module description).

    Parameters
    ----------
    rgb
        ``(H, W, 3)`` linear camera values.
    spots
        Spot spectra at pixels of the image.
    response
        ``(3, K')`` the camera's spectral response, rows R, G, B, any scale.
    fast
        The thesis's prior (and, unless ``appearance`` names a space, its RGBXY space) without
        cross-validation: no spot errors, no blend.
    appearance
        ``"auto"``: the appearance space chosen by the cross-validation among
        :data:`~recon.spectralize.appearance_choice.SPACES`; or one of them.
    kriging
        With the cross-validation, blend in the kriged estimate by the weight it chooses
        (module description, step 5).
    camera_degree
        Highest degree of the camera term's smooth factor per channel
        (:func:`recon.image_spectralization.camera_fit.camera_term`); 0: a gain per channel.
    tol
        Relative residual of the solves (:func:`recon.spectralize.solve.reconstruct`).
    cross_validation_pixels
        An image of more pixels is cross-validated in a central window of about this many
        (:func:`recon.image_spectralization.window.cross_validation_window`; module
        description, step 3); ``None``: the whole image.
    sample_stride
        In the RGBXY space on an image of at least
        :data:`~recon.spectralize.hierarchy.MIN_PIXELS` pixels, the energy is solved (in the
        folds and finally) on every ``sample_stride``-th pixel of every ``sample_stride``-th
        row and the spots, the other pixels taken from the solved ones
        (:mod:`recon.spectralize.hierarchy`; module description, step 4); 1: on every pixel.
    progress
        Show progress bars.

    Returns
    -------
    ImageSpectralization
    """
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise InputError(f"rgb: expected (H, W, 3) camera values, got shape {rgb.shape}")
    if response.values.ndim != 2 or response.values.shape[0] != 3:
        raise InputError(
            f"response: expected three channels R, G, B, got {response.values.shape[0]}"
        )
    if appearance not in APPEARANCES:
        raise InputError(f"appearance: expected one of {APPEARANCES}, got {appearance!r}")
    if not (isinstance(sample_stride, (int, np.integer)) and sample_stride >= 1):
        raise InputError(f"sample_stride: expected an integer >= 1, got {sample_stride!r}")
    pixels = spots.flat_pixels(rgb.shape[:2])
    if pixels.size < MIN_SPOTS:
        raise InputError(
            f"spots {spots.source}: {pixels.size} spot(s); expected at least {MIN_SPOTS} "
            f"(two per fold of the {FOLDS}-fold cross-validation)"
        )
    grid, notes = solve_grid(spots.spectra, response)
    spectra = resample(spots.spectra, grid, method="box" if notes else "linear").values
    flat = rgb.reshape(-1, 3)
    camera = camera_term(response, grid, flat[pixels], spectra, max_degree=camera_degree)
    r_cam = camera.matrix
    timings, choice, appearance_errors, warm_start = {}, None, {}, None
    graph: NeighbourGraph | None = None
    stride = hierarchy.stride_for(rgb.shape, sample_stride)
    if fast:
        energy = _energy(FAST_APPEARANCE if appearance == "auto" else appearance, pixels, spectra)
    else:
        started = time.perf_counter()
        window = cross_validation_window(rgb.shape[:2], pixels, cross_validation_pixels)
        inside = window.inside(pixels)
        window_pixels, window_spectra = window.local(pixels[inside]), spectra[inside]
        chosen = choose_appearance(
            rgb[window.slices],
            r_cam,
            window_pixels,
            window_spectra,
            spaces=SPACES if appearance == "auto" else (appearance,),
            folds=FOLDS,
            sample_stride=stride,  # the folds solve as the whole image will be solved
            tol=tol,
            progress=progress,
            **_ENERGY,
        )
        timings["cross_validation"] = time.perf_counter() - started
        choice, energy = chosen.prior_choice, _ENERGY | chosen.energy
        if appearance == "auto":
            appearance_errors = chosen.held_out_errors
        if window.whole:
            graph, warm_start = chosen.graph, choice.fold_spectra
        else:
            energy = _energy(chosen.appearance, pixels, spectra)
            notes.append(
                f"space, prior and kriging weight chosen by the cross-validation of "
                f"{window.describe()} ({int(inside.sum())} of {pixels.size} spot pixels, "
                f"the others without a held-out error)"
            )
    prior = FAST_PRIOR if choice is None else choice.prior
    held_out = {} if choice is None else dict(choice.held_out_errors)
    spot_errors = None if choice is None else _in_window(choice.pixel_errors[prior], inside)
    weight = 0.0
    if choice is not None and kriging:
        if pixels.size > MAX_KRIGED_PIXELS:
            notes.append(
                f"no blend with the kriged estimate: {pixels.size} spot pixels, above the "
                f"{MAX_KRIGED_PIXELS} its m x m system is solved for"
            )
        else:
            started = time.perf_counter()
            kriging_choice = choose_kriging_weight(
                rgb[window.slices],
                r_cam,
                window_pixels,
                window_spectra,
                choice,
                correlation_length=default_correlation_length(*rgb.shape[:2]),
            )
            weight = kriging_choice.kriging_weight
            held_out |= {key: kriging_choice.held_out_errors[key] for key in ("kriging", "blend")}
            spot_errors = _in_window(kriging_choice.pixel_errors, inside)
            timings["kriging"] = time.perf_counter() - started
    if weight == 1.0:  # the blend is the kriged estimate alone: nothing to solve
        started = time.perf_counter()
        spectra_out = kriged_estimate(rgb, r_cam, pixels, spectra)
        timings["kriging"] += time.perf_counter() - started
        notes.append(
            "the kriged estimate alone: the held-out spots chose it over any blend with the "
            "spectralization, which was therefore not solved"
        )
    else:
        hierarchical = hierarchy.on_lattice(energy["appearance"], stride)
        if not hierarchical and graph is None:
            started = time.perf_counter()
            graph = graph_for(rgb, energy)
            timings["graph"] = time.perf_counter() - started
        started = time.perf_counter()
        spectra_out = hierarchy.reconstruct_image(
            rgb,
            r_cam,
            point_spectra=PointSpectra(pixels, spectra),
            stride=stride,
            graph=graph,
            initial=warm_start,
            prior=prior,
            tol=tol,
            progress=progress,
            **energy,
        )
        timings["solve"] = time.perf_counter() - started
        if hierarchical:
            notes.append(
                f"solved on one pixel in each {stride} x {stride} block and on the spots, the "
                f"other pixels from their nearest solved ones in appearance space"
            )
        if weight:
            started = time.perf_counter()
            spectra_out = blend_with_kriging(spectra_out, rgb, r_cam, pixels, spectra, weight)
            timings["kriging"] += time.perf_counter() - started
    cube = np.clip(spectra_out, 0.0, None).astype(np.float32)
    return ImageSpectralization(
        cube=cube,
        grid=grid,
        prior=prior,
        appearance=energy["appearance"],
        appearance_errors=appearance_errors,
        cross_validated=choice is not None,
        kriging_weight=weight,
        held_out_errors=held_out,
        spot_errors=spot_errors,
        gains=camera.gains,
        fit_residual_pct=camera.fit_residual_pct,
        timings_s=timings,
        notes=tuple(notes),
    )
