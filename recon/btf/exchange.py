"""A BTF store as a folder of spectral OpenEXR slices with a JSON direction index, and back.

:func:`export_btf` writes one spectral EXR per direction pair (``pair_00000.exr``, ...; the
Fichet et al. 2021 layout of :mod:`recon.spectral_exr`, reflective ``T.<wavelength>nm``
channels, float32, so every value round-trips bit for bit) and ``directions.json``: the light and
view direction of every pair with its file, the wavelengths, the texture size, the units and the
store's attributes (material, provenance, calibration). The index is written last, by rename: a
folder without it is an export that did not finish. :func:`import_exr_slices` reads such a folder
into a new BTF store, which is then identical to the exported one (reflectance, directions,
wavelengths, registered corners and attributes); it checks the index and every slice's header
before it writes, and builds the store under a temporary name (:mod:`recon.btf.staging`).

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
from pydantic import Field, PositiveInt

from hwbridge.schema import StoreModel, parse
from recon.btf.schema import BTF_FORMAT, BTF_FORMAT_VERSION, BTFAttrs
from recon.btf.staging import staged
from recon.btf.store import BTF_UNITS, BTFStore
from recon.errors import DamagedDataError, InputError, Remedy
from recon.progress import progress_steps
from recon.spectra import WavelengthGrid
from recon.spectral_exr import read_spectral_exr, read_spectral_layout, write_spectral_exr

__all__ = ["EXCHANGE_FORMAT", "INDEX_NAME", "export_btf", "import_exr_slices"]

EXCHANGE_FORMAT = "spectwin.btf-exr-slices"
EXCHANGE_VERSION = 1
INDEX_NAME = "directions.json"
# The store's own: a new store is made with its own format, progress, identity and seals.
_STORE_ATTRIBUTES = ("format", "format_version", "complete", "units", "store_id", "sealed")
_SLICE_FIELDS = ("texels", "wavelengths_nm", "pairs")
_MAX_COMPRESSION = 1032  # deflate's largest ratio: an EXR holds no more pixels than this allows


class SliceEntry(StoreModel):
    """One direction pair of ``directions.json``: its slice, a file in the index's folder."""

    file: str = Field(pattern=r"^[^/\\]+\.exr$", description="the slice's file name")
    light_dir: tuple[float, float, float] = Field(description="unit vector, sample frame")
    view_dir: tuple[float, float, float] = Field(description="unit vector, sample frame")
    corners_xy: tuple[tuple[float, float], ...] | None = Field(
        None, min_length=4, max_length=4, description="registered image corners, or null"
    )


class SliceIndex(StoreModel):
    """The texture size, wavelengths and pairs of ``directions.json``."""

    texels: tuple[PositiveInt, PositiveInt] = Field(description="(H, W) of every slice")
    wavelengths_nm: tuple[float, ...] = Field(min_length=1, description="the channels' nm")
    pairs: tuple[SliceEntry, ...] = Field(min_length=1, description="one entry per pair")


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
    return index


def import_exr_slices(
    folder: str | Path, out_path: str | Path, *, progress: bool = False
) -> BTFStore:
    """Read a folder written by :func:`export_btf` into a new BTF store at ``out_path``.

    Everything is checked before the store is made: the index (its fields, the attributes it
    gives, which never include the store's own ``format``, ``format_version``, ``units`` and
    ``complete``), and every slice's header (reflective ``T`` channels at the index's
    wavelengths, the index's texture size; emissive ``S0`` channels hold radiance, not
    reflectance, and are refused). The store is built under a temporary name beside
    ``out_path`` and renamed to it once every pair is in (:func:`recon.btf.staging.staged`):
    an import that fails leaves nothing behind.

    Parameters
    ----------
    folder
        The slices and their ``directions.json``.
    out_path
        The new store (must not exist).
    progress
        Show a progress bar over the pairs.

    Returns
    -------
    BTFStore
        The new, complete store, open for reading.
    """
    folder = Path(folder)
    index = _read_index(folder)
    where = str(folder / INDEX_NAME)
    slices = parse(SliceIndex, {key: index[key] for key in _SLICE_FIELDS}, where)
    grid = WavelengthGrid(np.asarray(slices.wavelengths_nm, np.float64))
    attributes = _imported_attributes(index.get("attributes"), where)
    for entry in slices.pairs:
        _check_slice(folder / entry.file, slices.texels, grid)
    with staged(out_path) as building:
        store = BTFStore.create(
            building,
            light_dirs=np.array([entry.light_dir for entry in slices.pairs], np.float64),
            view_dirs=np.array([entry.view_dir for entry in slices.pairs], np.float64),
            texels=slices.texels,
            grid=grid,
            material=attributes.pop("material"),
            source_capture=attributes.pop("source_capture"),
            calibration=attributes.pop("calibration"),
            rig=attributes.pop("rig"),
        )
        for name, value in attributes.items():
            store.set_attribute(name, value)
        with progress_steps("import BTF slices", len(slices.pairs), enabled=progress) as advance:
            for pair, entry in enumerate(slices.pairs):
                image = read_spectral_exr(folder / entry.file)
                if image.cube.dtype.kind != "f":
                    raise DamagedDataError(
                        f"{folder / entry.file}: {image.cube.dtype} pixels; expected float16 "
                        "or float32 reflectance"
                    )
                store.write_pair(
                    pair,
                    image.cube,
                    grid=grid,
                    corners_xy=None if entry.corners_xy is None else np.asarray(entry.corners_xy),
                )
                advance()
    return BTFStore.open(out_path)


def _imported_attributes(given: object, where: str) -> dict[str, Any]:
    """The store attributes an index gives, checked as :class:`~recon.btf.schema.BTFAttrs`
    with the store's own left to the store; each field the store needs, with its default."""
    if not isinstance(given, dict):
        raise InputError(f"{where}: attributes: expected an object of the store's attributes")
    own = sorted(set(given) & set(_STORE_ATTRIBUTES))
    if own:
        raise InputError(
            f"{where}: attributes {own} are the BTF store's own, set by the import; expected "
            "only the material, provenance and what processing found"
        )
    defaults: dict[str, Any] = {
        "material": "imported",
        "source_capture": None,
        "calibration": {},
        "rig": None,
    }
    attributes = {**defaults, **given}
    own_values = {
        "format": BTF_FORMAT,
        "format_version": BTF_FORMAT_VERSION,
        "units": BTF_UNITS,
        "complete": False,
        "store_id": "made by the import",
        "sealed": {},
    }
    parse(BTFAttrs, {**attributes, **own_values}, f"{where}: attributes")
    return attributes


def _check_slice(path: Path, texels: tuple[int, int], grid: WavelengthGrid) -> None:
    """Refuse a slice whose header does not hold reflectance at ``texels`` on ``grid`` (no
    pixel is read)."""
    layout = read_spectral_layout(path)
    if layout.kind != "reflective":
        raise InputError(
            f"{path}: emissive (S0) channels hold radiance; expected reflectance in reflective "
            "(T) channels"
        )
    if layout.grid != grid or layout.shape != texels:
        raise DamagedDataError(
            f"{path}: {layout.shape} px on {layout.grid.describe()}, expected {texels} px on "
            f"{grid.describe()} as {INDEX_NAME} says"
        )
    bytes_needed = texels[0] * texels[1] * grid.size * 2  # half floats at the least
    if bytes_needed > _MAX_COMPRESSION * path.stat().st_size:
        raise DamagedDataError(
            f"{path}: {path.stat().st_size} bytes cannot hold {texels} px x {grid.size} "
            "channels; expected a complete slice"
        )
