"""Replay of real captures: ingest a folder of frames into a capture store via a mapping file.

A mapping (YAML) names the camera, describes the rig, and lists regular expressions over the
folder's relative paths; named groups ``exposure_ms``, ``exposure_s`` and ``band_nm`` become index
fields and each pattern sets the frame ``kind`` (and optionally ``light_id``, ``view_id``). The
resulting store has backend ``replay`` and reads exactly like a simulated one; its ``rig``
attribute is the mapping's description of the rig (:class:`hwbridge.schema.ReplayRigAttrs`).
Mappings shipped with spectwin live in ``hwbridge/mappings`` (``llanos2019``).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import tifffile
import yaml

from hwbridge.errors import InputError
from hwbridge.lock import StoreLock
from hwbridge.schema import FRAME_KINDS, NO_LIGHT, NO_VIEW, ReplayRigAttrs, parse
from hwbridge.store import CaptureStore, FrameRecord

__all__ = ["MAPPING_DIR", "ingest", "load_mapping"]

MAPPING_DIR = Path(__file__).resolve().parent / "mappings"


def load_mapping(name_or_path: str | Path) -> dict[str, Any]:
    """A shipped mapping by name (``"llanos2019"``) or a mapping file by path, validated; its
    ``rig`` becomes the store's :class:`~hwbridge.schema.ReplayRigAttrs` (program: the
    mapping's name)."""
    path = Path(name_or_path)
    if not path.suffix:
        path = MAPPING_DIR / f"{name_or_path}.yaml"
    if not path.is_file():
        known = sorted(p.stem for p in MAPPING_DIR.glob("*.yaml"))
        raise InputError(f"mapping: no file {path}; expected a path or one of {known}")
    mapping = yaml.safe_load(path.read_text())
    if not isinstance(mapping, dict) or not {"camera", "files"} <= set(mapping):
        raise InputError(f"{path}: expected a mapping with 'camera' and 'files'")
    for entry in mapping["files"]:
        if entry.get("kind") not in FRAME_KINDS:
            raise InputError(f"{path}: kind {entry.get('kind')!r} is not one of {FRAME_KINDS}")
        re.compile(entry["pattern"])
    described = mapping.get("rig") or {}
    mapping["rig"] = parse(
        ReplayRigAttrs, {"rig": "replay", "program": path.stem, **described}, f"{path}: rig"
    )
    return mapping


def _exposure_s(groups: dict[str, str], path: str) -> float:
    if "exposure_s" in groups:
        return float(groups["exposure_s"])
    if "exposure_ms" in groups:
        return float(groups["exposure_ms"]) / 1000
    raise InputError(f"{path}: the mapping's pattern gives no exposure_ms or exposure_s")


def ingest(source: str | Path, mapping: str | Path, store_path: str | Path) -> CaptureStore:
    """Read every mapped frame of ``source`` into a new capture store at ``store_path``."""
    source = Path(source)
    if not source.is_dir():
        raise InputError(f"source: {source} is not a folder")
    spec = load_mapping(mapping)
    matched = []
    for entry in spec["files"]:
        pattern = re.compile(entry["pattern"])
        for file in sorted(source.rglob("*")):
            relative = file.relative_to(source).as_posix()
            found = pattern.fullmatch(relative)
            if found:
                matched.append((relative, entry, found.groupdict()))
    if not matched:
        raise InputError(f"{source}: no file matches the mapping's patterns")
    first = tifffile.imread(source / matched[0][0])
    camera = spec["camera"]
    plan = []
    for relative, entry, groups in matched:
        plan.append(
            {
                "camera": camera,
                "kind": entry["kind"],
                "exposure_s": _exposure_s(groups, relative),
                "file": relative,
                **({"band_nm": float(groups["band_nm"])} if "band_nm" in groups else {}),
            }
        )
    with StoreLock.reserve(store_path) as lock:  # one writer per store (hwbridge.lock)
        store = CaptureStore.create(
            store_path,
            rig=spec["rig"],
            backend="replay",
            seed=0,
            plan=plan,
            cameras={camera: first.shape},
        )
        lock.move_into()
        for step, ((relative, entry, _), settings) in enumerate(zip(matched, plan, strict=True)):
            frame = tifffile.imread(source / relative)
            if frame.shape != first.shape:
                raise InputError(f"{relative}: shape {frame.shape} differs from {first.shape}")
            record = FrameRecord(
                kind=settings["kind"],
                exposure_s=settings["exposure_s"],
                timestamp=(source / relative).stat().st_mtime,
                light_id=int(entry.get("light_id", NO_LIGHT)),
                view_id=int(entry.get("view_id", NO_VIEW)),
                band_nm=settings.get("band_nm", float("nan")),
            )
            store.write_frame(step, np.asarray(frame).astype(np.uint16), record)
            store.mark_done(step)
    return store
