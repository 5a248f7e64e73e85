"""Render time and memory of the BTF BSDF (twin.render.plugins.btf_bsdf): decoded table versus PCA
factors.

A square with the BTF under a constant spectral map, XYZ film. The BTF is a store's (argument)
or a synthetic one of the twin's gonio shape (13 x 13 directions, 156 pairs, 128^2 texels,
33 bands). Prints JSON.

Run: .venv/bin/python -m benchmarks.btf_render [BTF_STORE] [--pixels N] [--spp N]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from benchmarks.common import machine_description, peak_rss_mib
from recon.btf.compression import compress_btf
from recon.btf.store import BTFStore
from recon.spectra import DEFAULT_GRID, WavelengthGrid
from twin.render.plugins.btf_bsdf import btf_bsdf, compressed_product_table, product_table
from twin.render.plugins.spectral_envmap import SpectralMap, spectral_envmap
from twin.render.render import render_scene
from twin.render.spectra import specfilm
from twin.render.truth import band_passbands
from twin.render.variant import activate
from twin.rigs.hemisphere import sattler_directions

_BANDS = WavelengthGrid(np.array([440.0, 550.0, 650.0]))


def _synthetic(texels: int = 128):
    """Directions and a BTF of low spectral and angular rank plus 2 % texel noise."""
    rng = np.random.default_rng(0)
    directions = sattler_directions(((0.0, 1), (30.0, 4), (60.0, 8)))
    lights = np.repeat(directions, len(directions), axis=0)
    views = np.tile(directions, (len(directions), 1))
    keep = np.einsum("ij,ij->i", lights, views) < 0.999  # the rig cannot measure light = view
    lights, views = lights[keep], views[keep]
    texture = rng.uniform(0.05, 0.6, (1, texels, texels, DEFAULT_GRID.size))
    angular = 1 + 0.3 * np.cos(2 * lights[:, 0] + views[:, 1])[:, None, None, None]
    noise = 1 + 0.02 * rng.normal(size=(len(lights), texels, texels, 1))
    return lights, views, (texture * angular * noise / np.pi).astype(np.float32)


def _render_seconds(table, pixels: int, spp: int) -> float:
    import mitsuba as mi

    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": 2},
            "sensor": {
                "type": "perspective",
                "fov": 40,
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=[0, -1.5, 2], target=[0, 0, 0], up=[0, 0, 1]
                ),
                "film": specfilm(band_passbands(_BANDS), pixels, pixels),
                "sampler": {"type": "independent", "sample_count": spp},
            },
            "environment": spectral_envmap(
                SpectralMap(np.ones((16, 32, DEFAULT_GRID.size)), DEFAULT_GRID)
            ),
            "sample": {"type": "rectangle", "bsdf": btf_bsdf(table)},
        }
    )
    render_scene(scene, seed=0)  # kernel compilation
    started = time.perf_counter()
    render_scene(scene, seed=1)
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("btf", nargs="?", help="a complete BTF store (default: synthetic)")
    parser.add_argument("--pixels", type=int, default=128)
    parser.add_argument("--spp", type=int, default=64)
    arguments = parser.parse_args()
    report = activate()
    if arguments.btf:
        store = BTFStore.open(arguments.btf)
        lights, views = store.light_dirs, store.view_dirs
        values = np.asarray(store.reflectance())
    else:
        lights, views, values = _synthetic()
    results: dict[str, object] = {
        "machine": machine_description(),
        "variant": report.as_dict(),
        "btf_shape": list(values.shape),
        "image": f"{arguments.pixels}^2 px, {arguments.spp} spp, 3 bands",
    }
    tables = {"decoded": product_table(lights, views, values, DEFAULT_GRID)}
    for layout in ("joint", "per_band"):
        started = time.perf_counter()
        compressed = compress_btf(values, DEFAULT_GRID, layout=layout)
        results[f"compress_{layout}_s"] = round(time.perf_counter() - started, 1)
        results[f"compress_{layout}"] = repr(compressed)
        tables[f"pca_{layout}"] = compressed_product_table(lights, views, compressed)
    for name, table in tables.items():
        results[f"{name}_table_mib"] = round(table.nbytes / 2**20, 1)
        results[f"{name}_render_s"] = round(
            _render_seconds(table, arguments.pixels, arguments.spp), 2
        )
    results["peak_rss_mib"] = peak_rss_mib()
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
