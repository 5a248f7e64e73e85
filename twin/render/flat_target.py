"""Flat Lambertian targets under a distant lamp: the analytic test scene of the renderer.

A chart of flat diffuse patches (a single white plane, or the 24 ColorChecker patches) lies in
the plane z = 0, lit by a distant lamp from ``incidence_deg`` off the normal and seen from above
by an orthographic camera with a ``specfilm``. A Lambertian patch of reflectance
:math:`\\rho(\\lambda)` under irradiance :math:`E(\\lambda)` at incidence :math:`\\theta` has
radiance :math:`L = \\rho E \\cos\\theta / \\pi` in every direction (thesis Eq. 3.3 uses the same
relation for the white standard), so each band of the render has the closed form
:math:`\\int \\rho E \\cos\\theta / \\pi \\, S_k \\, d\\lambda` (:func:`analytic_band_radiance`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from recon.errors import InputError
from recon.spectra import SampledSpectra, band_integrals
from twin.render.render import render_scene
from twin.render.spectra import irregular_spectrum, ldsampler, specfilm
from twin.render.variant import activate

__all__ = ["analytic_band_radiance", "flat_target_scene", "patch_means", "render_flat_target"]


def _check_inputs(
    reflectances: SampledSpectra, irradiance: SampledSpectra, bands: SampledSpectra
) -> np.ndarray:
    if irradiance.values.ndim != 1:
        raise InputError(
            f"irradiance: expected one spectrum, got values of shape {irradiance.values.shape}"
        )
    irradiance.require_non_negative("irradiance")
    reflectances.require_non_negative("reflectances")
    rows = np.atleast_2d(reflectances.values)
    if rows.ndim != 2 or np.any(rows > 1):
        raise InputError(
            "reflectances: expected one or more reflectance spectra with values in [0, 1]"
        )
    for name, spectra in (("irradiance", irradiance), ("bands", bands)):
        if spectra.grid != reflectances.grid:
            raise InputError(
                f"{name}: expected the reflectances' grid ({reflectances.grid.describe()}), got "
                f"{spectra.grid.describe()}"
            )
    return rows


def analytic_band_radiance(
    reflectances: SampledSpectra,
    irradiance: SampledSpectra,
    bands: SampledSpectra,
    *,
    incidence_deg: float = 0.0,
) -> np.ndarray:
    """Closed-form band radiance of Lambertian patches, ``(n_patches, n_bands)``.

    Parameters
    ----------
    reflectances
        Patch reflectances, values ``(n_patches, K)`` or ``(K,)``.
    irradiance
        Irradiance on a surface facing the lamp, W m^-2 nm^-1.
    bands
        Channel responses :math:`S_k`, values ``(n_bands, K)``.
    incidence_deg
        Angle between the lamp direction and the patch normal.

    Returns
    -------
    numpy.ndarray
        :math:`\\int \\rho E \\cos\\theta / \\pi \\, S_k \\, d\\lambda` in W m^-2 sr^-1 (times the
        unit of :math:`S_k`).
    """
    rows = _check_inputs(reflectances, irradiance, bands)
    cosine = math.cos(math.radians(incidence_deg))
    radiance = SampledSpectra(reflectances.grid, rows * irradiance.values * cosine / math.pi)
    return band_integrals(radiance, bands)


def flat_target_scene(
    reflectances: SampledSpectra,
    irradiance: SampledSpectra,
    bands: SampledSpectra,
    *,
    columns: int = 1,
    pixels_per_patch: int = 64,
    patch_fill: float = 1.0,
    incidence_deg: float = 0.0,
    spp: int = 256,
) -> dict[str, object]:
    """Mitsuba scene dict of the chart; patch ``i`` sits in row ``i // columns``, column
    ``i % columns``.

    Each patch covers ``patch_fill`` of its square cell (1.0: patches touch, a single patch fills
    the image). The image is ``columns * pixels_per_patch`` wide and ``rows * pixels_per_patch``
    high, with one cell per ``pixels_per_patch`` square block of pixels.
    """
    rows_of_reflectance = _check_inputs(reflectances, irradiance, bands)
    if not 0 < patch_fill <= 1:
        raise InputError(f"patch_fill: expected a fraction in (0, 1], got {patch_fill}")
    if not 0 <= incidence_deg < 90:
        raise InputError(f"incidence_deg: expected [0, 90), got {incidence_deg}")
    if columns < 1 or pixels_per_patch < 1 or spp < 1:
        raise InputError("columns, pixels_per_patch, spp: expected positive integers")
    activate()
    import mitsuba as mi

    transform = mi.ScalarTransform4f
    count = rows_of_reflectance.shape[0]
    chart_rows = math.ceil(count / columns)
    scene: dict[str, object] = {
        "type": "scene",
        "integrator": {"type": "direct"},
        "sensor": {
            "type": "orthographic",
            # The orthographic camera sees x in [-s, s]; y follows from the film's aspect ratio.
            "to_world": transform.look_at(origin=[0, 0, 1], target=[0, 0, 0], up=[0, 1, 0])
            @ transform.scale([columns, columns, 1]),
            "film": specfilm(bands, columns * pixels_per_patch, chart_rows * pixels_per_patch),
            "sampler": ldsampler(spp),
        },
        "lamp": {
            "type": "directional",
            "direction": [
                -math.sin(math.radians(incidence_deg)),
                0.0,
                -math.cos(math.radians(incidence_deg)),
            ],
            "irradiance": irregular_spectrum(irradiance),
        },
    }
    for index, reflectance in enumerate(rows_of_reflectance):
        row, column = divmod(index, columns)
        # Cell centres in world units; a cell is 2 x 2 units, the camera looks down -z with
        # image columns along world +x and image rows along world -y.
        centre_x = 2 * column + 1 - columns
        centre_y = chart_rows - (2 * row + 1)
        scene[f"patch_{index:03d}"] = {
            "type": "rectangle",
            "to_world": transform.translate([centre_x, centre_y, 0]) @ transform.scale(patch_fill),
            "bsdf": {
                "type": "diffuse",
                "reflectance": irregular_spectrum(SampledSpectra(reflectances.grid, reflectance)),
            },
        }
    return scene


def render_flat_target(
    reflectances: SampledSpectra,
    irradiance: SampledSpectra,
    bands: SampledSpectra,
    *,
    seed: int = 0,
    **layout: Any,
) -> np.ndarray:
    """Render the chart of :func:`flat_target_scene`: band radiance image ``(H, W, n_bands)``."""
    return render_scene(flat_target_scene(reflectances, irradiance, bands, **layout), seed)


def patch_means(
    image: np.ndarray, count: int, *, columns: int = 1, inner_fraction: float = 0.5
) -> np.ndarray:
    """Mean band radiance over the central ``inner_fraction`` of each patch's cell.

    Returns an array ``(count, n_bands)``.
    """
    chart_rows = math.ceil(count / columns)
    cell = image.shape[1] // columns
    if image.shape[0] != chart_rows * cell or image.shape[1] != columns * cell:
        raise InputError(
            f"image: expected {chart_rows * cell}x{columns * cell} pixels for {count} patches in "
            f"{columns} columns, got {image.shape[0]}x{image.shape[1]}"
        )
    margin = int(round(cell * (1 - inner_fraction) / 2))
    means = []
    for index in range(count):
        row, column = divmod(index, columns)
        block = image[
            row * cell + margin : (row + 1) * cell - margin,
            column * cell + margin : (column + 1) * cell - margin,
        ]
        means.append(block.reshape(-1, image.shape[-1]).mean(axis=0))
    return np.array(means)
