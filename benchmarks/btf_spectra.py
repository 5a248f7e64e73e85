"""Spectral BTFs from RGB BTFs and spot spectra (``spectwin btf import --spectra``) against the
truth, Jakob 2019 upsampling and the baselines. Prints JSON.

For each twin material: its true spectral BTF (``twin.render.truth.truth_btf``, 3 lights x 3
views, :data:`TEXELS` texels, reflectance factors ``pi * BTF``), its RGB BTF through a shipped
camera (:data:`CAMERA`) under CIE D65, and spot spectra at 1 % of the texels, taken from the
truth, in two cases: at 1 % of the texels of every pair (``every_pair``), or as many spots all at
one pair (``one_pair``: pair :data:`SPOT_PAIR`, light at 30 degrees, view at the normal, like a
spectrophotometer's 45/0). Against the truth at the texels that are not spots, mean Eq. 6.8 (%)
and mean Delta E94 (thesis illuminants), per method:

- ``joint`` and ``per_pair``: :func:`recon.btf.rgb_spectralization.spectralize_rgb_btf`, the
  two designs (its module description);
- ``jakob2019``: what the import does without spots, on the camera's values white-balanced
  (divided by a white's) and read as linear sRGB; ``jakob2019_srgb``: on the truth's exact
  linear sRGB under D65 (its best case, which no camera gives);
- ``a_plus``: Spectral A+ (``recon.baselines``) trained on every spot, on all pairs at once;
- ``murakami``: Murakami 2007 per pair from that pair's spots (``every_pair`` only), given the
  exact camera term (response times D65), where the spectralization fits its own to the spots.

A third case, ``one_reading``, has no spots but one 45/0 spectrophotometer reading over the whole
texture (:mod:`recon.btf.reading_spectralization`), given to the pair nearest 45/0 (pair
:data:`SPOT_PAIR`, 30/0, 15 degrees away), errors over every texel: ``reading_45_0`` with the
truth's mean at 45/0 itself (rendered apart: what an instrument reads), ``reading_at_pair`` with
the truth's mean at that pair (the 15 degrees taken out), and ``jakob2019``, ``jakob2019_srgb``
as above.

Run: PYTHONPATH=. .venv/bin/python -m benchmarks.btf_spectra [--materials lego wallpaper ...]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable

import colour
import numpy as np

from benchmarks.common import machine_description
from recon import baselines
from recon.btf.reading_spectralization import (
    GEOMETRY_DEG,
    Reading45,
    reading_pair,
    spectralize_from_reading,
)
from recon.btf.rgb_spectralization import BTFSpots, spectralize_rgb_btf
from recon.measured_data import read_camera_sensitivities
from recon.metrics import delta_e94, relative_error
from recon.rgb_upsampling import srgb_response, upsample_srgb
from recon.spectra import DEFAULT_GRID, SampledSpectra, from_colour, resample
from twin.materials import load_material
from twin.render.truth import truth_btf

CAMERA = "Nikon D850"
TEXELS = 32
SPP = 16
SPOT_SHARE = 0.01
SPOT_PAIR = 3
_ANGLES_DEG = ((0.0, 0.0), (30.0, 90.0), (60.0, 180.0))


def pair_directions() -> tuple[np.ndarray, np.ndarray]:
    """3 lights x 3 views (polar, azimuth in degrees): pair ``3 * light + view``."""
    theta, phi = np.radians(np.array(_ANGLES_DEG)).T
    dirs = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], 1)
    light, view = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    return dirs[light.ravel()], dirs[view.ravel()]


def camera_projection() -> np.ndarray:
    """``(K, 3)``: reflectance factors on ``DEFAULT_GRID`` to the camera's values under D65."""
    response = resample(read_camera_sensitivities(CAMERA), DEFAULT_GRID).values.T
    light = resample(from_colour(colour.SDS_ILLUMINANTS["D65"]), DEFAULT_GRID).values
    return response * (light * DEFAULT_GRID.quadrature_weights())[:, None]


def spot_texels(shape: tuple[int, int, int], case: str, rng: np.random.Generator) -> np.ndarray:
    """Flat indices of the spots: 1 % of each pair's texels, or as many at pair 0."""
    pairs, height, width = shape
    size = height * width
    per_pair = max(1, round(SPOT_SHARE * size))
    if case == "one_pair":
        chosen = rng.choice(size, min(size, per_pair * pairs), replace=False)
        return SPOT_PAIR * size + np.sort(chosen)
    return np.concatenate(
        [pair * size + np.sort(rng.choice(size, per_pair, replace=False)) for pair in range(pairs)]
    )


def _murakami(rgb: np.ndarray, projection: np.ndarray, pixels: np.ndarray, known: np.ndarray):
    size = rgb.shape[1] * rgb.shape[2]
    pair_of = pixels // size
    return np.stack(
        [
            baselines.recover(
                rgb[pair],
                projection,
                method="murakami",
                known_pixels=pixels[pair_of == pair] - pair * size,
                known_spectra=known[pair_of == pair],
            )
            for pair in range(rgb.shape[0])
        ]
    )


def _jakob(truth: np.ndarray, rgb: np.ndarray) -> dict[str, Callable[[], np.ndarray]]:
    """The two Jakob 2019 upsamplings (module description)."""
    white = np.ones(DEFAULT_GRID.size) @ camera_projection()
    return {
        "jakob2019": lambda: upsample_srgb(rgb / white, "jakob2019").values,
        "jakob2019_srgb": lambda: upsample_srgb(truth @ srgb_response(), "jakob2019").values,
    }


def run_case(truth: np.ndarray, case: str, seed: int) -> dict[str, dict[str, float]]:
    """Every method's errors on one material and spot case (module description)."""
    projection = camera_projection()
    rgb = truth @ projection
    pixels = spot_texels(truth.shape[:3], case, np.random.default_rng(seed))
    known = truth.reshape(-1, DEFAULT_GRID.size)[pixels]
    width = truth.shape[2]
    pair, texel = np.divmod(pixels, truth.shape[1] * width)
    where = np.stack([pair, texel % width, texel // width], axis=1)
    spots = BTFSpots(where, SampledSpectra(DEFAULT_GRID, known), "benchmark")
    response = read_camera_sensitivities(CAMERA)
    methods: dict[str, Callable[[], np.ndarray]] = {
        "joint": lambda: spectralize_rgb_btf(rgb, spots, response, design="joint").cube,
        "per_pair": lambda: spectralize_rgb_btf(rgb, spots, response, design="per_pair").cube,
        **_jakob(truth, rgb),
        "a_plus": lambda: baselines.recover(
            rgb, projection, method="a_plus", known_pixels=pixels, known_spectra=known
        ),
    }
    if case == "every_pair":
        methods["murakami"] = lambda: _murakami(rgb, projection, pixels, known)
    unknown = np.ones(truth.shape[:3], bool).ravel()
    unknown[pixels] = False
    return _errors(methods, truth, unknown)


def mean_at_45_0(material: str) -> np.ndarray:
    """``(K,)`` the twin's true mean reflectance factor over the texture of ``material``, lit
    at 45 degrees and seen along the normal: a 45/0 instrument's reading."""
    theta = np.radians(GEOMETRY_DEG[0])
    light, view = np.array([[np.sin(theta), 0.0, np.cos(theta)]]), np.array([[0.0, 0.0, 1.0]])
    btf = truth_btf(load_material(material), light, view, texels=TEXELS, spp=SPP, seed=0)
    return np.pi * btf[0].reshape(-1, DEFAULT_GRID.size).mean(axis=0).astype(np.float64)


def run_reading(truth: np.ndarray, at_45_0: np.ndarray) -> dict[str, dict[str, float]]:
    """The ``one_reading`` case (module description); ``at_45_0`` is the truth's mean over the
    texture at 45/0."""
    rgb = truth @ camera_projection()
    pair, _ = reading_pair(*pair_directions())
    response = read_camera_sensitivities(CAMERA)
    at_pair = truth[pair].reshape(-1, DEFAULT_GRID.size).mean(axis=0)

    def from_reading(mean: np.ndarray) -> np.ndarray:
        reading = Reading45(SampledSpectra(DEFAULT_GRID, mean[None]), "benchmark")
        return spectralize_from_reading(rgb, reading, response, pair=pair).cube

    methods: dict[str, Callable[[], np.ndarray]] = {
        "reading_45_0": lambda: from_reading(at_45_0),
        "reading_at_pair": lambda: from_reading(at_pair),
        **_jakob(truth, rgb),
    }
    return _errors(methods, truth, np.ones(truth.shape[:3], bool).ravel())


def _errors(
    methods: dict[str, Callable[[], np.ndarray]], truth: np.ndarray, kept: np.ndarray
) -> dict[str, dict[str, float]]:
    """Mean Eq. 6.8 (%), mean Delta E94 against ``truth`` and seconds of each method at the
    ``kept`` texels (flat)."""
    reference = truth.reshape(-1, DEFAULT_GRID.size)[kept]
    results = {}
    for name, method in methods.items():
        started = time.perf_counter()
        estimate = np.asarray(method(), np.float64).reshape(-1, DEFAULT_GRID.size)[kept]
        seconds = time.perf_counter() - started
        results[name] = {
            "eq_6_8_pct": round(float(np.mean(relative_error(estimate, reference))), 2),
            "delta_e94": round(float(np.mean(delta_e94(estimate, reference, DEFAULT_GRID))), 2),
            "seconds": round(seconds, 2),
        }
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--materials", nargs="+", default=["lego", "wallpaper", "colorchecker16"])
    parser.add_argument("--seed", type=int, default=0)
    arguments = parser.parse_args()
    light, view = pair_directions()
    report: dict[str, object] = {
        "machine": machine_description(),
        "camera": CAMERA,
        "pairs": len(light),
        "texels": TEXELS,
        "spot_share": SPOT_SHARE,
        "materials": {},
    }
    for name in arguments.materials:
        started = time.perf_counter()
        btf = truth_btf(load_material(name), light, view, texels=TEXELS, spp=SPP, seed=0)
        truth = np.pi * btf.astype(np.float64)
        render_s = time.perf_counter() - started
        report["materials"][name] = {  # type: ignore[index]
            "render_s": round(render_s, 1),
            **{case: run_case(truth, case, arguments.seed) for case in ("every_pair", "one_pair")},
            "one_reading": run_reading(truth, mean_at_45_0(name)),
        }
        print(f"{name} done", file=sys.stderr)
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
