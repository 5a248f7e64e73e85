"""A BTF store as a folder of spectral OpenEXR slices with a JSON direction index, and back.

:func:`export_btf` writes one spectral EXR per direction pair (``pair_00000.exr``, ...; the
Fichet et al. 2021 layout of :mod:`recon.spectral_exr`, reflective ``T.<wavelength>nm``
channels, float32, so every value round-trips bit for bit) and ``directions.json``: the light and
view direction of every pair with its file, the wavelengths, the texture size, the units and the
store's attributes (material, provenance, calibration). The index is written last, by rename: a
folder without it is an export that did not finish. :func:`import_exr_slices` reads such a folder
into a new BTF store, which is then identical to the exported one (reflectance, directions,
wavelengths, registered corners and attributes).

References
----------
- Fichet, A., Pacanowski, R., & Wilkie, A. (2021). An OpenEXR Layout for Spectral Images.
  Journal of Computer Graphics Techniques, 10(3), 1-18.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from recon.btf.store import BTF_UNITS, BTFStore
from recon.errors import DamagedDataError, InputError, Remedy
from recon.progress import progress_steps
from recon.spectra import WavelengthGrid
from recon.spectral_exr import read_spectral_exr, write_spectral_exr

__all__ = ["EXCHANGE_FORMAT", "INDEX_NAME", "export_btf", "import_exr_slices"]

EXCHANGE_FORMAT = "spectwin.btf-exr-slices"
EXCHANGE_VERSION = 1
INDEX_NAME = "directions.json"
# The store's own: a new store is made with its own format, progress, identity and seals.
_STORE_ATTRIBUTES = ("format", "format_version", "complete", "units", "store_id", "sealed")


def _slice_name(pair: int) -> str:
    return f"pair_{pair:05d}.exr"


def _corners_entry(corners: np.ndarray) -> list[Any] | None:
    """Registered corners as a JSON list, ``None`` where none were given (NaN)."""
    return None if np.isnan(corners).any() else corners.tolist()


def export_btf(store: BTFStore, out_dir: str | Path, *, progress: bool = False) -> Path:
    """Write a complete BTF store as spectral EXR slices plus ``directions.json``.

    Parameters
    ----------
    store
        A complete store (:meth:`BTFStore.open`).
    out_dir
        A folder that does not exist yet or is empty; it is created.
    progress
        Show a progress bar over the pairs.

    Returns
    -------
    pathlib.Path
        The index file.
    """
    out_dir = Path(out_dir)
    if out_dir.exists() and (not out_dir.is_dir() or any(out_dir.iterdir())):
        raise InputError(
            f"{out_dir}: expected a new or empty folder for the slices (nothing was overwritten)"
        )
    if not store.complete:
        raise InputError(
            f"{store.path}: cannot export an incomplete BTF store ({len(store.pending_pairs())} "
            "pairs pending)",
            remedy=Remedy.finish_processing,
        )
    out_dir.mkdir(parents=True, exist_ok=True)
    corners = store.corners_xy()
    pairs = []
    with progress_steps("export BTF slices", store.n_pairs, enabled=progress) as advance:
        for pair, texture in store.iter_pairs():
            write_spectral_exr(
                out_dir / _slice_name(pair),
                np.asarray(texture, np.float32),
                store.grid,
                kind="reflective",
                attributes={"btfPair": str(pair), "material": store.material},
            )
            pairs.append(
                {
                    "file": _slice_name(pair),
                    "light_dir": store.light_dirs[pair].tolist(),
                    "view_dir": store.view_dirs[pair].tolist(),
                    "corners_xy": _corners_entry(corners[pair]),
                }
            )
            advance()
    index = {
        "format": EXCHANGE_FORMAT,
        "format_version": EXCHANGE_VERSION,
        "units": BTF_UNITS,
        "texels": list(store.texels),
        "wavelengths_nm": store.grid.wavelengths_nm.tolist(),
        "attributes": {k: v for k, v in store.attrs.items() if k not in _STORE_ATTRIBUTES},
        "pairs": pairs,
    }
    handle, temporary = tempfile.mkstemp(suffix=".json", dir=out_dir)
    with os.fdopen(handle, "w") as file:
        json.dump(index, file, indent=1)
    os.replace(temporary, out_dir / INDEX_NAME)
    return out_dir / INDEX_NAME


def _read_index(folder: Path) -> dict[str, Any]:
    path = folder / INDEX_NAME
    if not folder.is_dir():
        raise InputError(
            f"{folder}: expected a folder of spectral EXR slices with {INDEX_NAME}",
            remedy=Remedy.export_btf,
        )
    if not path.is_file():
        raise InputError(
            f"{folder}: no {INDEX_NAME}; expected the direction index of an export of a BTF store "
            "(a folder without it is an export that did not finish)",
            remedy=Remedy.export_btf,
        )
    try:
        index = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as error:
        raise DamagedDataError(f"{path}: unreadable direction index ({error})") from error
    if not isinstance(index, dict) or index.get("format") != EXCHANGE_FORMAT:
        raise InputError(
            f"{path}: format {index.get('format') if isinstance(index, dict) else None!r}, "
            f"expected {EXCHANGE_FORMAT!r}"
        )
    if index.get("format_version") != EXCHANGE_VERSION:
        raise InputError(
            f"{path}: format version {index.get('format_version')!r} is not supported "
            f"(expected {EXCHANGE_VERSION})"
        )
    if index.get("units") != BTF_UNITS:
        raise InputError(
            f"{path}: units {index.get('units')!r}, expected {BTF_UNITS!r} (BTF reflectance)"
        )
    for field, kind in (("pairs", list), ("wavelengths_nm", list), ("texels", list)):
        if not isinstance(index.get(field), kind) or not index[field]:
            raise InputError(f"{path}: field {field!r} must be a non-empty list")
    for number, entry in enumerate(index["pairs"]):
        if not isinstance(entry, dict) or not {"file", "light_dir", "view_dir"} <= set(entry):
            raise InputError(
                f"{path}: pairs[{number}] must name 'file', 'light_dir' and 'view_dir'"
            )
    return index


def import_exr_slices(
    folder: str | Path, out_path: str | Path, *, progress: bool = False
) -> BTFStore:
    """Read a folder written by :func:`export_btf` into a new BTF store at ``out_path``.

    Every slice must hold the index's wavelengths at the index's texture size. The store is
    complete only once every pair is written; an import cut short leaves an incomplete store.

    Returns
    -------
    BTFStore
        The new store, open for reading.
    """
    folder = Path(folder)
    index = _read_index(folder)
    grid = WavelengthGrid(np.asarray(index["wavelengths_nm"], np.float64))
    texels = tuple(int(v) for v in index["texels"])
    entries = index["pairs"]
    attributes = dict(index.get("attributes") or {})
    store = BTFStore.create(
        out_path,
        light_dirs=np.array([e["light_dir"] for e in entries], np.float64),
        view_dirs=np.array([e["view_dir"] for e in entries], np.float64),
        texels=texels,
        grid=grid,
        material=attributes.pop("material", "imported"),
        source_capture=attributes.pop("source_capture", None),
        calibration=attributes.pop("calibration", None),
        rig=attributes.pop("rig", None),
    )
    for name, value in attributes.items():
        store.set_attribute(name, value)
    with progress_steps("import BTF slices", len(entries), enabled=progress) as advance:
        for pair, entry in enumerate(entries):
            image = read_spectral_exr(folder / str(entry["file"]))
            if image.grid != grid or image.cube.shape[:2] != texels:
                raise DamagedDataError(
                    f"{folder / str(entry['file'])}: {image.cube.shape[:2]} px on "
                    f"{image.grid.describe()}, expected {texels} px on {grid.describe()} as "
                    f"{INDEX_NAME} says"
                )
            corners = entry.get("corners_xy")
            store.write_pair(
                pair,
                image.cube,
                grid=grid,
                corners_xy=None if corners is None else np.asarray(corners, np.float64),
            )
            advance()
    return BTFStore.open(out_path)
