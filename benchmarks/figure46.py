"""Figure 4.6 (thesis 4.2) on a BTF of the colour checker: the numbers of
``twin.validate.render_back``. Prints JSON.

``--sampling`` names the direction sampling (``twin.gonio.capture.SAMPLINGS``): ``reduced``,
the twin's 13 x 13 (the 13 directions of ``REDUCED_RINGS``, polar 0, 30, 60 degrees with 1, 4,
8 azimuths, as lights and as views, 169 combinations of which the rig reaches 156), or
``glossy``, Sattler's 57 directions up to 60 degrees (``GLOSSY_RINGS``, 3192 reachable pairs);
the renderer fills missing combinations from the nearest measured view of the same light. The
BTF is either

- ``--btf STORE``: a measured BTF store (README, ground-truth section: ``spectwin capture
  --program gonio-run``, ``calibrate``, ``process``), or
- by default the twin's true BTF for the sampling's pairs, band-weighted like the instrument
  (filter x sensor x lamp, as ``spectwin evaluate`` renders it), at ``--texels``.

For each image setting (pixels, samples per pixel) it renders Figure 4.6
(``twin.validate.figure46.render_figure46``: the photograph of the true material in the room,
the spectral and the RGB rendering of the BTF under the captured map) and prints the summary:
Delta E94 against the photograph per pixel and per field mean, matte and glossy fields apart.

Run: .venv/bin/python -m benchmarks.figure46 [--btf STORE] [--texels N] [--sampling glossy]
"""

from __future__ import annotations

import argparse
import json
import time

from benchmarks.common import machine_description, peak_rss_mib
from recon.btf.store import BTFStore
from recon.spectra import DEFAULT_GRID
from twin.gonio.capture import SAMPLINGS, gonio_pairs
from twin.materials import load_material
from twin.render.plugins.btf_bsdf import product_table, store_table
from twin.render.truth import truth_btf
from twin.rigs.rig_config import load_rig
from twin.sensor.band_weights import instrument_passbands
from twin.validate.figure46 import render_figure46

SETTINGS = ((128, 64), (96, 256))  # (pixels, spp): the two of twin.validate.render_back


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--btf", help="a measured BTF store (default: the twin's true BTF)")
    parser.add_argument("--texels", type=int, default=64, help="texels of the true BTF")
    parser.add_argument(
        "--sampling",
        choices=sorted(SAMPLINGS),
        default="reduced",
        help="directions of the true BTF (twin.gonio.capture.SAMPLINGS)",
    )
    parser.add_argument(
        "--no-lobes", action="store_true", help="render without the fitted specular lobes"
    )
    arguments = parser.parse_args()
    started = time.perf_counter()
    if arguments.btf:
        btf = BTFStore.open(arguments.btf)
        material, table = (
            load_material(btf.material),
            store_table(btf, lobes=not arguments.no_lobes),
        )
        source = {"btf": arguments.btf, "pairs": int(btf.written().sum()), "texels": btf.texels[0]}
    else:
        config, material = load_rig("gonio"), load_material("colorchecker16")
        pairs = gonio_pairs(config, SAMPLINGS[arguments.sampling])
        reflectance = truth_btf(
            material,
            pairs.light_dirs,
            pairs.view_dirs,
            texels=arguments.texels,
            passbands=instrument_passbands(config),
        )
        table = product_table(
            pairs.light_dirs,
            pairs.view_dirs,
            reflectance,
            DEFAULT_GRID,
            lobes=not arguments.no_lobes,
        )
        source = {
            "btf": f"twin truth, instrument band weights, {arguments.sampling} sampling",
            "pairs": len(pairs.light_dirs),
            "texels": arguments.texels,
        }
    results: dict[str, object] = {
        "machine": machine_description(),
        "source": source,
        "table": f"{len(table.light_dirs)} lights x {len(table.view_dirs)} views",
        "specular_lobes": not arguments.no_lobes,
        "btf_s": round(time.perf_counter() - started, 1),
    }
    for pixels, spp in SETTINGS:
        started = time.perf_counter()
        figure = render_figure46(material, table, pixels=pixels, spp=spp)
        results[f"{pixels}px_{spp}spp"] = {
            **{key: round(value, 3) for key, value in figure.summary().items()},
            "seconds": round(time.perf_counter() - started, 1),
        }
    results["peak_rss_mib"] = peak_rss_mib()
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
