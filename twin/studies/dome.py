"""The thesis's chapter 10 experiments on the twin dome (10.3-10.5), as numbers.

- :func:`schedules`: the band schedules for the thesis's parameters (8 images; 10 images with
  the noisiest band twice) and their exposure increase (thesis: +41 %, +61 %).
- :func:`single_image`: per material, single images (all 30 noisy bands + HDR RGB) under
  several LEDs, reconstructed with Eq. 10.12 (10.4.1); errors on the texels that show material.
- :func:`comparison`: the same single image by Dong et al. 2016 and Spectral A+ from the
  sphere-lit spectral image (10.4.3, 10.4.4).
- :func:`multi_image`: 10 images at the spectral camera's 45 degrees with the scheduled bands
  spread over them, 10 images from other RGB cameras without spectral data (10.4.2).
- :func:`metamer_diagnosis`: 10.4.2.1 in numbers: how often RGB appearance neighbours are
  spectrally different, and how much of the 600 nm band's structure its filter keeps.
- :func:`exposure_comparison`: hybrid capture versus long spectral-only exposures at equal
  error (10.5: 7.5 s instead of 226 s).
- :func:`cross_check`: Fig. 10.4, RGB predicted from a calibrated spectral image versus RGB
  measured, per colour-checker field.
- :func:`twin.studies.dome_stores.store_study`: 10.4.2 and 10.5 on rendered dome capture
  stores processed by :mod:`recon.dome`, next to the analytic path taking the same images.
- :func:`run_dome_study`: all of them, written to ``dome_study.json`` with the figures of
  :mod:`twin.studies.dome_figures`.

Two imaging scales. The single-image, multi-image and comparison experiments image each
material at its physical size (a 4 cm sample at 32 texels: 12 x 12 spectral-camera pixels per
texel, averaged). The thesis evaluates camera pixels (10.5, Fig. 10.24: pixel spectra), so the
single images are repeated, and the 10.5 exposure comparison run, at ``PER_PIXEL_TEXEL_PX``: one
Bayer quad of the RGB camera and 2 x 2 spectral-camera pixels per texel, where a band's noise is
a pixel's and the filters of Fig. 10.5 matter.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import ndimage

from recon.baselines import recover
from recon.errors import InputError
from recon.metrics import relative_error
from recon.spectralize.appearance import appearance_neighbours, appearance_points
from recon.spectralize.solve import dynamic_scale
from twin.components.targets import zenith_white_reflectance
from twin.dome.capture_study import (
    DomeCapture,
    ReconstructionErrors,
    dome_light_directions,
    reconstruct_capture,
    simulate_capture,
    sphere_lit_spectra,
)
from twin.dome.exposure_plan import band_schedules
from twin.dome.setup import (
    BAND_GRID,
    CALIBRATION_LIGHT,
    DARK_FRAMES_PER_TIME,
    SPECTRAL_VIEW,
    THESIS_BANDS_NM,
    DomeSetup,
    dome_setup,
)
from twin.materials import load_material
from twin.output_format import dumps
from twin.render.truth import texture_truth
from twin.rigs.dome_geometry import dome_geometry
from twin.rigs.hemisphere import direction
from twin.sensor.white_reference import equalized_exposures_s
from twin.studies import dome_figures

__all__ = [
    "DOME_MATERIALS",
    "PER_PIXEL_TEXEL_PX",
    "P_DYN",
    "SINGLE_IMAGE_LEDS",
    "SingleImage",
    "comparison",
    "cross_check",
    "exposure_comparison",
    "metamer_diagnosis",
    "multi_image",
    "reference_exposures",
    "run_dome_study",
    "schedules",
    "single_image",
]

P_DYN = 0.5
"""Eq. 10.2's exponent; the thesis found 0.5-0.6 best."""

SINGLE_IMAGE_LEDS = (12, 40, 70, 100)
"""LEDs of the single-image experiment: polar 17, 26, 35 and 44 degrees in four azimuths, none
in the spectral camera's mirror direction (the thesis does not say which light it used)."""

_SPHERE_LEDS = tuple(range(0, 198, 11))  # 18 of the 198 LEDs stand for all of them


def schedules(setup: DomeSetup) -> dict[str, dict]:
    """The 8-image and the 10-image schedule (noisiest bands twice, as many as fit) of the plan."""
    return band_schedules(setup.exposures_s)


@dataclass(frozen=True)
class SingleImage:
    """Single-image captures of one material, their reconstructions and errors."""

    captures: tuple[DomeCapture, ...]
    cubes: tuple[np.ndarray, ...]
    errors: tuple[ReconstructionErrors, ...]

    def summary(self) -> dict[str, float]:
        """Errors pooled over all images (material texels only)."""
        pooled = ReconstructionErrors(
            np.concatenate([e.relative_pct for e in self.errors]),
            np.concatenate([e.delta_e94 for e in self.errors]),
            np.concatenate([e.material for e in self.errors]),
        )
        return pooled.summary()


def single_image(
    setup: DomeSetup,
    material: str,
    rng: np.random.Generator,
    *,
    leds: Sequence[int] = SINGLE_IMAGE_LEDS,
) -> SingleImage:
    """One single-image capture and reconstruction per LED of ``leds`` (10.4.1)."""
    texels = setup.cameras.spectral.height // setup.cameras.pixels_per_texel
    captures, cubes, errors = [], [], []
    for led in leds:
        light = dome_light_directions(setup, [led])
        truth = texture_truth(material, light, SPECTRAL_VIEW[None], texels=texels)
        capture = simulate_capture(setup, truth, light, [list(range(THESIS_BANDS_NM.size))], rng)
        cube = reconstruct_capture(setup, capture, p_dyn=P_DYN)
        captures.append(capture)
        cubes.append(cube)
        errors.append(ReconstructionErrors.of(cube, capture.truth))
    return SingleImage(tuple(captures), tuple(cubes), tuple(errors))


def comparison(
    setup: DomeSetup, material: str, single: SingleImage, rng: np.random.Generator
) -> dict[str, dict[str, float]]:
    """Dong et al. 2016 (3-component NMF basis) and Spectral A+ (:math:`\\lambda = 10^{-5}`,
    thesis 10.4.4) from the sphere-lit spectral image, on the single images' RGB."""
    texels = setup.cameras.spectral.height // setup.cameras.pixels_per_texel
    sphere = sphere_lit_spectra(
        setup, material, SPECTRAL_VIEW, rng, texels=texels, leds=_SPHERE_LEDS
    )
    known = np.clip(sphere.reshape(-1, sphere.shape[-1]), 0, None)
    training = known[rng.choice(known.shape[0], min(1000, known.shape[0]), replace=False)]
    results: dict[str, list] = {"dong": [], "a_plus": []}
    for capture in single.captures:
        rgb = capture.rgb
        results["dong"].append(recover(rgb, setup.response, method="dong", known_spectra=known))
        results["a_plus"].append(
            recover(rgb, setup.response, method="a_plus", known_spectra=training, ridge_lambda=1e-5)
        )
    out = {"spectralization": single.summary()}
    for name, cubes in results.items():
        errors = [
            ReconstructionErrors.of(cube, capture.truth)
            for cube, capture in zip(cubes, single.captures, strict=True)
        ]
        out[name] = SingleImage(single.captures, tuple(cubes), tuple(errors)).summary()
    return out


def multi_image(
    setup: DomeSetup, material: str, rng: np.random.Generator
) -> tuple[DomeCapture, ReconstructionErrors, dict[str, dict[str, float]]]:
    """20 images reconstructed jointly (10.4.2): images 0-9 seen by the spectral camera (45
    degrees; the stage turned by 36 degrees each) with the 10-image schedule's bands, images
    10-19 seen by the other RGB cameras, without spectral data."""
    texels = setup.cameras.spectral.height // setup.cameras.pixels_per_texel
    geometry = dome_geometry(setup.cameras.config)
    polar = np.degrees(np.arccos(geometry.led_directions[:, 2]))
    usable = np.flatnonzero((polar > 10) & (polar < 60))
    leds = usable[(np.arange(20) * 37) % usable.size]
    stage = np.arange(10) * 36.0
    spectral_views = direction(np.full(10, 45.0), 15.0 + stage)
    other_polar = [p for p in setup.cameras.config.rgb_camera_polar_deg if p != 45.0][:10]
    other_views = direction(np.array(other_polar), stage)
    views = np.concatenate([spectral_views, other_views])
    lights = dome_light_directions(setup, leds)
    truth = texture_truth(material, lights, views, texels=texels)
    plan = schedules(setup)["10_images"]["images"]
    capture = simulate_capture(setup, truth, lights, plan + [[] for _ in range(10)], rng)
    cube = reconstruct_capture(setup, capture, p_dyn=P_DYN)
    errors = ReconstructionErrors.of(cube, capture.truth)
    return (
        capture,
        errors,
        {
            "with_spectral_data": errors.summary(slice(0, 10)),
            "without_spectral_data": errors.summary(slice(10, 20)),
        },
    )


def metamer_diagnosis(setup: DomeSetup, capture: DomeCapture) -> dict[str, float]:
    """10.4.2.1 in numbers for image 0 of ``capture``.

    ``metameric_link_pct``: of the RGB appearance links (3 neighbours, scaled RGB as the
    reconstruction uses), the share whose RGB differ by less than 3 % while their true spectra
    differ by more than 10 % (Eq. 6.8). ``structure_kept_600nm_pct``: the standard deviation of
    the true 600 nm band after the band's Gaussian filter, relative to before (Fig. 10.21).
    """
    rgb = capture.rgb[:1]
    truth = capture.truth[0].reshape(-1, capture.truth.shape[-1])
    scale = dynamic_scale(rgb, P_DYN).reshape(*rgb.shape[:-1], 1)
    graph = appearance_neighbours(appearance_points(rgb * scale, "rgb"), k=3)
    flat_rgb = rgb.reshape(-1, 3)
    material = truth.mean(-1) >= 0.01
    links = material[graph.first] & material[graph.second]
    first, second = graph.first[links], graph.second[links]
    rgb_distance = np.abs(flat_rgb[first] - flat_rgb[second]).sum(-1) / flat_rgb[first].sum(-1)
    spectral_distance = relative_error(truth[second], truth[first])
    metameric = (rgb_distance < 0.03) & (spectral_distance > 10.0)
    band = int(np.flatnonzero(THESIS_BANDS_NM == 600.0)[0])
    image = capture.truth[0][..., band]
    sigma = max(float(setup.filter_sigma()[band]), 1.0)
    filtered = ndimage.gaussian_filter(image, sigma)
    return {
        "links": int(first.size),
        "metameric_link_pct": float(100 * metameric.mean()),
        "median_rgb_link_distance_pct": float(100 * np.median(rgb_distance)),
        "median_spectral_link_error_pct": float(np.median(spectral_distance)),
        "structure_kept_600nm_pct": float(100 * filtered.std() / image.std()),
        "filter_sigma_600nm_px": sigma,
    }


def exposure_comparison(
    setup: DomeSetup,
    material: str,
    rng: np.random.Generator,
    *,
    led: int = SINGLE_IMAGE_LEDS[0],
    hybrid_scales: Sequence[float] = (1.0, 0.25, 1 / 12),
) -> dict[str, Any]:
    """Hybrid captures (RGB set + all band exposures of one image, counted one after the other)
    against spectral-only captures with long exposures (10.5, Fig. 10.24), errors on the
    material texels.

    Hybrid: the plan's band exposures times ``hybrid_scales`` (1/12 gives about the 7.5 s of
    thesis 10.5), reconstructed by Eq. 10.12; ``direct`` is the same noisy band images used as
    they are (Fig. 10.24's green spectra). Spectral-only: exposures bringing the white reference
    to 80 % of saturation in every band (Eq. 3.4; the reference), and the same divided by 4, 16
    and 64, the band images used as they are. ``equal_error_spectral_only_s`` interpolates
    (log-log) the spectral-only time whose error equals each hybrid's.
    """
    texels = setup.cameras.spectral.height // setup.cameras.pixels_per_texel
    light = dome_light_directions(setup, [led])
    truth = texture_truth(material, light, SPECTRAL_VIEW[None], texels=texels)
    hybrids = []
    for scale in hybrid_scales:
        capture = simulate_capture(
            setup, truth, light, [list(range(THESIS_BANDS_NM.size))], rng, exposure_scale=scale
        )
        errors = ReconstructionErrors.of(
            reconstruct_capture(setup, capture, p_dyn=P_DYN), capture.truth
        )
        direct = ReconstructionErrors.of(capture.band_values(), capture.truth).summary()
        hybrids.append(
            {
                "scale": float(scale),
                "total_s": capture.rgb_exposure_s + capture.spectral_exposure_s,
                "spectral_s": capture.spectral_exposure_s,
                "error_pct": errors.summary()["mean_relative_error_pct"],
                "delta_e94": errors.summary()["mean_delta_e94"],
                "direct_error_pct": direct["mean_relative_error_pct"],
                "direct_delta_e94": direct["mean_delta_e94"],
            }
        )
    rates = _band_rates(setup, capture)
    reference = reference_exposures(setup)
    totals, direct_errors = [], []
    for factor in (1.0, 4.0, 16.0, 64.0):
        values = _spectral_only(setup, rates, reference / factor, rng)
        totals.append(float((reference / factor).sum()))
        direct_errors.append(ReconstructionErrors.of(values[None], capture.truth[:1]).summary())
    errors_pct = np.array([e["mean_relative_error_pct"] for e in direct_errors])
    order = np.argsort(errors_pct)
    for hybrid in hybrids:
        hybrid["equal_error_spectral_only_s"] = float(
            np.exp(
                np.interp(
                    np.log(hybrid["error_pct"]),
                    np.log(errors_pct[order]),
                    np.log(np.array(totals)[order]),
                )
            )
        )
        hybrid["reference_over_hybrid"] = totals[0] / hybrid["total_s"]
    return {
        "pixels_per_texel": setup.cameras.pixels_per_texel,
        "hybrid": hybrids,
        "spectral_only_totals_s": totals,
        "spectral_only_errors_pct": errors_pct.tolist(),
        "reference_total_s": totals[0],
        "reference_error_pct": direct_errors[0]["mean_relative_error_pct"],
        "reference_delta_e94": direct_errors[0]["mean_delta_e94"],
    }


def _spectral_only(
    setup: DomeSetup, rates: np.ndarray, exposures: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """Band reflectance images ``(H, W, 30)`` from one frame per band at ``exposures``."""
    return np.stack(
        [
            setup.spectral.reflectance(
                setup.cameras.band_frame(rates[..., band], float(t), rng),
                float(t),
                band,
                setup.led_per_band[band],
                1.0,
                texel_px=setup.cameras.pixels_per_texel,
            )
            for band, t in enumerate(exposures)
        ],
        axis=-1,
    )


def reference_exposures(setup: DomeSetup) -> np.ndarray:
    """Spectral-only reference exposures: the white reference at 80 % of saturation in every
    band (Eq. 3.4)."""
    _, white = setup.cameras.white_rates()
    return equalized_exposures_s(setup.cameras.spectral, white, white_fill=0.8)


def _band_rates(setup: DomeSetup, capture: DomeCapture) -> np.ndarray:
    """Noise-free band rates ``(H, W, 30)`` of image 0 facing the LED (cos 1): the truth times
    the white reference's rates over its reflectance."""
    _, white = setup.cameras.white_rates()
    return capture.truth[0] * (white / zenith_white_reflectance(BAND_GRID).values)


def cross_check(setup: DomeSetup, rng: np.random.Generator) -> dict[str, Any]:
    """Fig. 10.4: the colour checker's RGB predicted from a spectral image (long exposures,
    calibrated, times :math:`R_{cam}`) against its measured HDR RGB, per field (medians over
    each field's inner texels)."""
    exposures = reference_exposures(setup)
    capture = simulate_capture(setup, setup.calibration_truth, CALIBRATION_LIGHT[None], [[]], rng)
    spectral = _spectral_only(setup, _band_rates(setup, capture), exposures, rng)
    predicted = spectral @ setup.response
    measured = capture.rgb[0]
    fields = _field_medians(predicted), _field_medians(measured)
    difference = 100 * (fields[0] - fields[1]) / fields[1]
    return {
        "predicted": predicted,
        "measured": measured,
        "field_difference_pct": difference,
        "mean_abs_field_difference_pct": float(np.abs(difference).mean()),
        "max_abs_field_difference_pct": float(np.abs(difference).max()),
    }


def _field_medians(image: np.ndarray, grid: int = 4) -> np.ndarray:
    """Median of the inner half of each of the ``grid x grid`` fields, ``(grid * grid, C)``."""
    side = image.shape[0]
    if side % grid:
        raise InputError(f"image: {side} texels do not split into {grid} fields")
    step = side // grid
    inner = slice(step // 4, step - step // 4)
    return np.array(
        [
            np.median(
                image[r * step : (r + 1) * step, c * step : (c + 1) * step][inner, inner].reshape(
                    -1, image.shape[-1]
                ),
                axis=0,
            )
            for r in range(grid)
            for c in range(grid)
        ]
    )


DOME_MATERIALS = ("lego", "wallpaper", "colorchecker16", "red_fabric")
"""The thesis's four example materials (10.4)."""

PER_PIXEL_TEXEL_PX = 2
"""Camera pixels across a texel in the per-pixel regime (module description)."""


def _errors_of(result: SingleImage) -> dict[str, np.ndarray]:
    return {
        "relative": np.concatenate([e.relative_pct[e.material] for e in result.errors]),
        "delta_e": np.concatenate([e.delta_e94[e.material] for e in result.errors]),
    }


def run_dome_study(
    out: str | Path,
    *,
    texels: int = 32,
    materials: Sequence[str] = DOME_MATERIALS,
    seed: int = 0,
    dark_frames: int = DARK_FRAMES_PER_TIME,
    analytic: bool = True,
    store_metrics: Callable[[], dict] | None = None,
    step: Callable[[str], None] = lambda name: None,
) -> dict:
    """Run the experiments of :mod:`twin.studies.dome`, write the JSON and figures to ``out``.

    ``analytic``: the experiments on frames computed from the texture truth (module
    description), whose dome calibrations average ``dark_frames`` dark frames per exposure
    time (thesis 10.3: 200). ``store_metrics``: the same chapter's 10.4.2 multi-image
    experiment and 10.5 exposure totals from dome capture stores, processed by :mod:`recon.dome`
    (:func:`twin.studies.dome_stores.store_study` with its arguments bound), run after the
    analytic path and reported under ``"stores"`` next to the analytic path's numbers for the
    same images; ``None`` skips them.
    """
    unknown = sorted(set(materials) - set(DOME_MATERIALS))
    if unknown or not materials:
        raise InputError(
            f"materials: expected some of {list(DOME_MATERIALS)}, got {list(materials)}"
        )
    if texels < 8 or texels % 4:
        raise InputError(f"texels: expected a multiple of 4, at least 8, got {texels}")
    if not analytic and store_metrics is None:
        raise InputError("analytic, capture: expected the analytic path, stores or both")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    metrics = _analytic_study(out, texels, materials, seed, dark_frames, step) if analytic else {}
    if store_metrics is not None:
        metrics["stores"] = store_metrics()
        dome_figures.write_store_comparison(metrics["stores"], out / "stores_vs_analytic.png")
        dome_figures.write_error_budget(metrics["stores"], out / "error_budget.png")
    (out / "dome_study.json").write_text(dumps(metrics))
    return metrics


def _analytic_study(
    out: Path,
    texels: int,
    materials: Sequence[str],
    seed: int,
    dark_frames: int,
    step: Callable[[str], None],
) -> dict:
    """The experiments on the analytic path, their figures written to ``out``."""
    rng = np.random.default_rng(seed)
    setups: dict[float, DomeSetup] = {}

    def setup_for(material: str) -> DomeSetup:
        size = load_material(material).size_m
        if size not in setups:
            step(f"calibrating the dome for {size * 100:.2f} cm samples")
            setups[size] = dome_setup(
                texels, sample_size_m=size, dark_frames=dark_frames, seed=seed
            )
        return setups[size]

    first = setup_for(materials[0])
    step("calibrating the dome at one Bayer quad per texel")
    per_pixel = dome_setup(texels, texel_px=PER_PIXEL_TEXEL_PX, dark_frames=dark_frames, seed=seed)
    plans = schedules(first)
    metrics: dict = {
        "texels": texels,
        "dark_frames_per_time": dark_frames,
        "schedules": plans,
        "materials": {},
    }
    singles, multis = {}, {}
    for material in materials:
        setup = setup_for(material)
        step(f"{material}: single images")
        singles[material] = single_image(setup, material, rng)
        step(f"{material}: Dong 2016 and Spectral A+")
        compared = comparison(setup, material, singles[material], rng)
        step(f"{material}: 20 images")
        _, errors, multi = multi_image(setup, material, rng)
        multis[material] = errors
        step(f"{material}: single images at one Bayer quad per texel")
        per_pixel_single = single_image(per_pixel, material, rng)
        metrics["materials"][material] = {
            "pixels_per_texel": setup.cameras.pixels_per_texel,
            "single_image": singles[material].summary(),
            "comparison": compared,
            "multi_image": multi,
            "metamer_diagnosis": metamer_diagnosis(setup, singles[material].captures[0]),
            "per_pixel": {
                "pixels_per_texel": PER_PIXEL_TEXEL_PX,
                "single_image": per_pixel_single.summary(),
                "metamer_diagnosis": metamer_diagnosis(per_pixel, per_pixel_single.captures[0]),
            },
        }
    step("exposure comparison (one Bayer quad per texel) and cross-check")
    metrics["exposure_10_5"] = exposure_comparison(per_pixel, "colorchecker16", rng)
    check = cross_check(setup_for("colorchecker16"), rng)
    metrics["cross_check_10_4"] = {
        key: value for key, value in check.items() if key not in ("measured", "predicted")
    }
    metrics["plan"] = {
        "bands_nm": THESIS_BANDS_NM,
        "exposures_s": first.exposures_s,
        "filter_sigma_texels": first.filter_sigma(),
        "grey_relative_noise": first.relative_noise,
    }
    step("figures")
    dome_figures.write_plan(first, plans, out / "fig10_5_plan.png")
    dome_figures.write_error_histograms(
        {m: _errors_of(r) for m, r in singles.items()},
        "single images (Eq. 10.12)",
        out / "fig10_7_single_image_errors.png",
    )
    dome_figures.write_texel_spectra(singles, out / "fig10_9_spectra.png")
    dome_figures.write_error_histograms(
        {
            f"{material} {label}": {
                "relative": errors.relative_pct[part][errors.material[part]],
                "delta_e": errors.delta_e94[part][errors.material[part]],
            }
            for material, errors in multis.items()
            for label, part in (("with bands", slice(0, 10)), ("without", slice(10, 20)))
        },
        "20 images: 10 with spectral data at 45 degrees, 10 without",
        out / "fig10_13_multi_image.png",
    )
    dome_figures.write_comparison(metrics, out / "fig10_23_comparison.png")
    dome_figures.write_cross_check(check, out / "fig10_4_cross_check.png")
    dome_figures.write_exposure_vs_error(metrics["exposure_10_5"], out / "exposure_vs_error.png")
    return metrics
