"""Import of a UBO2014 file (``spectwin btf import FILE.btf --texels N``): the time to decode a
direction pair from the factors and the whole import into a spectral store.

The file is written in the DFMF layout by ``scripts/bonn_btf_files.py`` (half floats, the
components of an SVD), from a smooth RGB texture scaled per pair: 13 directions (169 pairs) of
256 x 256 texels by default. Real UBO2014 files have 151 directions (22801 pairs) of 400 x 400
texels; decoding scales with texels x components, the import with pairs.

Run: .venv/bin/python -m benchmarks.bonn_import OUT_DIR [--directions 13] [--texels 64]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import time
from pathlib import Path

import numpy as np

from benchmarks.common import machine_description
from recon.btf.bonn_formats import read_ubo2014
from recon.btf.rgb_import import import_rgb_images

_SIDE = 256
_COMPONENTS = 16


def _writers():
    path = Path(__file__).parents[1] / "scripts" / "bonn_btf_files.py"
    spec = importlib.util.spec_from_file_location("bonn_btf_files", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="a new folder for the file and the store")
    parser.add_argument("--directions", type=int, default=13)
    parser.add_argument("--texels", type=int, default=64)
    arguments = parser.parse_args()
    arguments.out.mkdir(parents=True)
    count = arguments.directions
    rng = np.random.default_rng(0)
    rows, columns = np.mgrid[0:_SIDE, 0:_SIDE] / _SIDE
    texture = 0.2 + 0.6 * np.stack([rows, columns, 0.5 + 0.5 * np.sin(8 * rows * columns)], -1)
    images = (0.3 + 0.7 * rng.random((count, count, 1, 1, 3))) * texture
    directions = np.stack(
        [np.radians(np.linspace(0, 75, count)), np.radians(np.linspace(0, 330, count))], -1
    )
    path = arguments.out / "sample.btf"
    _writers().write_ubo2014(path, directions, directions, images, components=_COMPONENTS)
    reader = read_ubo2014(path)
    started = time.perf_counter()
    for pair in range(10):
        reader.read(pair)
    decode_s = (time.perf_counter() - started) / 10
    started = time.perf_counter()
    store = import_rgb_images(path, arguments.out / "sample.btf.zarr", texels=arguments.texels)
    import_s = time.perf_counter() - started
    print(
        json.dumps(
            {
                "machine": machine_description(),
                "pairs": count * count,
                "texels_in_file": f"{_SIDE}x{_SIDE}",
                "components_per_channel": _COMPONENTS,
                "file_mb": round(path.stat().st_size / 1e6, 1),
                "decode_one_pair_ms": round(1000 * decode_s, 1),
                "stored_texels": "x".join(map(str, store.texels)),
                "import_s": round(import_s, 1),
                "import_per_pair_ms": round(1000 * import_s / store.n_pairs, 1),
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
