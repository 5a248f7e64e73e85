"""``spectwin demo``: the whole pipeline at small size on built-in defaults, with an HTML report.

1. Calibration session of the virtual gonioreflectometer (darks, response series, white
   standard) and ``calibrate`` (Robertson response, white factors, Eq. 3.4 exposure plan).
2. A measurement run of the colour checker at reduced sampling (:data:`DEMO_RINGS`: 5
   directions, the 20 light x view pairs the robot reaches), ``process`` into a BTF store
   (Eq. 3.6, registration), PCA compression (joint layout) into the store.
3. Evaluation against the twin's true BTF (Eq. 6.8 per chart field, corner errors).
4. Spectralization of a twin texture from RGB plus noisy band images (chapter 10 in miniature,
   :mod:`twin.studies.demo_spectralization`).
5. Validation: Figure 4.6 and the 45/0 comparison (:mod:`twin.validate.render_back`).

Writes the stores, PNGs, ``metrics.json`` and ``report.html`` into ``out``. A folder that a
previous demo wrote is replaced; any other non-empty folder is refused.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from recon.btf.compression import compress_btf, compression_report, save_compressed
from recon.btf.processing import process_gonio
from recon.calibration.gonio import calibrate_gonio
from recon.errors import InputError
from twin.gonio.capture import CAMERA_ID, run_gonio_calibration, run_gonio_measurement
from twin.gonio.render import GONIO_SPP
from twin.output_format import dumps
from twin.studies.demo_report import (
    plot_exposure_plan,
    plot_lamps_and_filter,
    plot_raw_frames,
    plot_spectralization,
    plot_textures,
    write_report,
)
from twin.studies.demo_spectralization import band_image_spectralization
from twin.validate.gonio_evaluation import GonioEvaluation, evaluate_gonio, write_gonio_figure
from twin.validate.render_back import validate_btf

__all__ = ["DEMO_RINGS", "DemoSettings", "run_demo"]

DEMO_RINGS = ((0.0, 1), (30.0, 4))
"""5 directions (polar 0 and 30 degrees): 20 reachable light x view pairs. So few directions
cannot hold the glossy fields' highlights: interpolated from the nearest measured pairs, they
spread into white patches in the Figure 4.6 renderings (the full 13 x 13 BTF renders them; the
metrics are those of the matte fields). A 60 degree ring instead registers its oblique frames at
256 px to 1.8 px only."""
_MARKER = ".spectwin-demo"


@dataclass(frozen=True)
class DemoSettings:
    """Sizes of the demo (defaults: about 10 minutes on 2 cores)."""

    rings: tuple[tuple[float, int], ...] = DEMO_RINGS
    pixels: int = 256
    texels: int = 64
    spp: int = GONIO_SPP
    figure_pixels: int = 96
    figure_spp: int = 256
    map_height: int = 32
    texture_texels: int = 48
    seed: int = 0


def _prepare(out: Path) -> None:
    if out.exists() and any(out.iterdir()):
        if not (out / _MARKER).exists():
            raise InputError(
                f"--out: {out} is not empty and was not written by spectwin demo; choose another"
            )
        shutil.rmtree(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / _MARKER).write_text("written by spectwin demo; replaced by the next demo run\n")


def run_demo(
    out: str | Path,
    settings: DemoSettings = DemoSettings(),
    *,
    step: Callable[[str], None] = lambda name: None,
) -> dict[str, Any]:
    """Run the demo into ``out`` (module docstring); returns the metrics written."""
    out = Path(out)
    _prepare(out)
    timings: dict[str, float] = {}

    @contextmanager
    def stage(name: str):
        step(name)
        started = time.perf_counter()
        yield
        timings[name] = round(time.perf_counter() - started, 1)

    with stage("calibration session"):
        plot_lamps_and_filter(out / "lamps_filter.png")
        run_gonio_calibration(out / "cal.capture.zarr", seed=settings.seed)
        calibration = calibrate_gonio(out / "cal.capture.zarr")
        calibration.save(out / "cal.json")
        plot_exposure_plan(calibration, out / "exposure_plan.png")
    with stage("measurement run"):
        capture = run_gonio_measurement(
            out / "run.capture.zarr",
            calibration.planned_exposure_s,
            rings=settings.rings,
            pixels=settings.pixels,
            spp=settings.spp,
            seed=settings.seed,
        )
        plot_raw_frames(capture, CAMERA_ID, out / "raw_frames.png")
    with stage("processing and compression"):
        btf = process_gonio(capture, calibration, out / "cc.btf.zarr", texels=settings.texels)
        if not btf.complete:
            raise InputError(
                f"processing left pairs unregistered: {list(btf.metadata.unregistered_pairs or ())}"
            )
        reflectance = np.asarray(btf.reflectance())
        compressed = compress_btf(reflectance, btf.grid, layout="joint")
        save_compressed(btf, compressed)
        compression = compression_report(compressed, reflectance)
        plot_textures(btf, out / "textures.png")
    with stage("evaluation against the truth"):
        evaluation = evaluate_gonio(out / "cc.btf.zarr")
        if not isinstance(evaluation, GonioEvaluation):  # a chart is evaluated field by field
            raise TypeError(f"expected a chart's evaluation, got {type(evaluation).__name__}")
        write_gonio_figure(evaluation, btf, out / "evaluation.png")
    with stage("spectralization"):
        spectralization = band_image_spectralization(
            texels=settings.texture_texels, seed=settings.seed
        )
        plot_spectralization(spectralization, out / "spectralization.png")
    with stage("validation rendering"):
        validation = validate_btf(
            out / "cc.btf.zarr",
            out / "validation",
            pixels=settings.figure_pixels,
            spp=settings.figure_spp,
            map_height=settings.map_height,
        )
    gonio = evaluation.summary()
    figure46, forty_five = validation["figure46"], validation["spectrophotometer_45_0"]
    metrics = {
        "description": (
            f"Virtual gonioreflectometer: colour checker, {btf.shape[0]} direction pairs, "
            f"{settings.pixels} px frames, {settings.texels}^2 texels, 33 bands; dome-style "
            f"spectralization of a {settings.texture_texels}^2 wallpaper texture; Figure 4.6 "
            f"at {settings.figure_pixels} px."
        ),
        "headline": {
            "BTF matte fields vs truth, mean Eq. 6.8 (%)": gonio[
                "mean_relative_error_matte_fields_pct"
            ],
            "registered corners, max error (px)": gonio["max_corner_error_px"],
            "exposure per pair (s)": float(calibration.planned_exposure_s.sum()),
            "PCA (joint) compression ratio": compression.ratio,
            "PCA mean Eq. 6.8 vs measured BTF (%)": compression.mean_relative_error_percent,
            "spectralization mean Eq. 6.8 (%)": spectralization.summary()[
                "mean_relative_error_pct"
            ],
            "spectralization mean Delta E94": spectralization.summary()["mean_delta_e94"],
            "Figure 4.6 field Delta E94, spectral": figure46["field_mean_delta_e94_spectral"],
            "Figure 4.6 field Delta E94, RGB": figure46["field_mean_delta_e94_rgb"],
            "45/0 matte fields, mean error (%)": forty_five["mean_error_matte_fields_pct"],
            "total time (s)": round(sum(timings.values()), 1),
        },
        "settings": asdict(settings),
        "gonio_evaluation": gonio,
        "compression": compression.as_dict(),
        "spectralization": spectralization.summary(),
        "validation": validation,
        "timings_s": timings,
    }
    (out / "metrics.json").write_text(dumps(metrics))
    write_report(out, metrics)
    return metrics
