"""Integrity of spectwin's Zarr v3 stores: a checksum per chunk, and the progress record checked
against the chunks on disk.

The capture store (:mod:`hwbridge.store`) and the BTF store (``recon.btf.store``) record
progress with a flag per unit of work (a capture step, a BTF direction pair) and write the unit's
chunks before its flag. Two kinds of damage escape Zarr on its own:

- a chunk file that is deleted reads as the array's fill value, silently (a frame of zeros);
- a chunk file that is truncated or altered decodes into an error deep inside a codec, or, when
  the bytes still decompress, into wrong numbers.

So every array these stores create ends its codec chain with the ``crc32c`` codec, after Zstd
(:func:`checksummed_compressors`): a chunk altered on disk raises on read instead of decoding.
:class:`ChunkChecker` checks a unit's chunks without decompressing them (the checksum covers the
compressed bytes): the chunk file must exist and, where the array has checksums, its last four
bytes must be the CRC-32C of the rest. Arrays made before checksums are checked by decoding
their chunks, which finds missing and truncated chunks but not every altered byte; the report
says "checksums: no".

The stores live in local folders; chunk files are named by Zarr's default chunk key encoding
(``<array>/c/<i>/<j>/...``), which is what :func:`chunk_key` gives.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import google_crc32c
import numpy as np
import zarr
from zarr.codecs import Crc32cCodec, ZstdCodec

from hwbridge.errors import DamagedDataError

__all__ = [
    "ChunkChecker",
    "ChunkProblem",
    "IntegrityReport",
    "array_at",
    "checksum_state",
    "checksummed_compressors",
    "chunk_key",
    "group_at",
    "has_checksums",
    "metadata_problem",
    "read_flags",
    "with_empty_chunks",
]


def checksummed_compressors(level: int = 0) -> tuple[ZstdCodec, Crc32cCodec]:
    """The bytes-to-bytes codecs of every new array: Zstd (at ``level``; 0 is Zstd's default,
    3), then CRC-32C over the compressed bytes
    (``create_array(..., compressors=checksummed_compressors())``)."""
    return ZstdCodec(level=level, checksum=False), Crc32cCodec()


def array_at(group: zarr.Group, key: str) -> zarr.Array[Any]:
    """The array at ``key`` in ``group``; a group there is a damaged store."""
    node = group[key]
    if not isinstance(node, zarr.Array):
        raise DamagedDataError(f"damaged store: {key} is a group where an array belongs")
    return node


def group_at(group: zarr.Group, key: str) -> zarr.Group:
    """The group at ``key`` in ``group``; an array there is a damaged store."""
    node = group[key]
    if not isinstance(node, zarr.Group):
        raise DamagedDataError(f"damaged store: {key} is an array where a group belongs")
    return node


def has_checksums(array: zarr.Array[Any]) -> bool:
    """Whether the chunks of ``array`` end with a CRC-32C of their bytes (crc32c is the last
    codec of its chain)."""
    codecs: tuple[object, ...] = getattr(array.metadata, "codecs", ())  # v2 metadata has none
    return bool(codecs) and isinstance(codecs[-1], Crc32cCodec)


def with_empty_chunks(array: zarr.Array[Any]) -> zarr.Array[Any]:
    """``array`` writing every chunk, also one that holds only the fill value (Zarr skips those
    by default, which would make a frame of zeros look like a missing chunk)."""
    return array.with_config({"write_empty_chunks": True})


def chunk_key(array: zarr.Array[Any], coords: tuple[int, ...]) -> str:
    """Path of the chunk at grid position ``coords`` inside the store, e.g.
    ``frames/k4/c/80/0/0``."""
    return f"{array.path}/{array.metadata.encode_chunk_key(coords)}"


def metadata_problem(root: Path, node: str) -> str | None:
    """What is wrong with the ``zarr.json`` of ``node`` (``""`` for the root), or ``None``."""
    file = root / node / "zarr.json" if node else root / "zarr.json"
    if not file.is_file():
        return f"{file} is missing"
    try:
        document = json.loads(file.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as error:
        return f"{file} is unreadable ({error})"
    if not isinstance(document, dict) or document.get("zarr_format") != 3:
        return f"{file} is not Zarr v3 metadata"
    return None


@dataclass(frozen=True)
class ChunkProblem:
    """A chunk of a unit of work that is missing or corrupt.

    Attributes
    ----------
    item
        The unit, for people: ``"camera k4 step 86 (frame 80)"``, ``"pair 3"``.
    key
        Path of the chunk in the store, ``frames/k4/c/80/0/0``.
    problem
        ``"missing"`` or ``"corrupt"``.
    detail
        Why a chunk is corrupt (checksum mismatch, cannot be decoded).
    units
        The steps or pairs whose data the chunk holds (one for a chunk per frame; none for an
        array of the whole store).
    """

    item: str
    key: str
    problem: str
    detail: str = ""
    units: tuple[int, ...] = ()

    def __str__(self) -> str:
        detail = f" ({self.detail})" if self.detail else ""
        return f"{self.item}: {self.key} is {self.problem}{detail}"

    def as_dict(self) -> dict[str, Any]:
        return {
            "item": self.item,
            "key": self.key,
            "problem": self.problem,
            "detail": self.detail,
            "units": list(self.units),
        }


class ChunkChecker:
    """Checks chunks of the arrays of one store folder (see the module docstring).

    Parameters
    ----------
    root
        The store's folder.
    verify
        Check the bytes (checksum, or decoding for arrays without checksums); ``False``: only
        that the chunk files exist.
    """

    def __init__(self, root: Path, *, verify: bool = True):
        self.root = Path(root)
        self.verify = verify
        self._arrays: dict[str, tuple[str, zarr.Array[Any], bool]] = {}

    def _array(self, array: zarr.Array[Any]) -> tuple[str, zarr.Array[Any], bool]:
        """The array's folder, the array and whether it has checksums (looked up once)."""
        path = array.path
        if path not in self._arrays:
            self._arrays[path] = (os.path.join(self.root, path), array, has_checksums(array))
        return self._arrays[path]

    def checksums(self, array: zarr.Array[Any]) -> bool:
        return self._array(array)[2]

    def check(self, array: zarr.Array[Any], coords: tuple[int, ...]) -> tuple[str, str] | None:
        """``None`` for a sound chunk, else ``(problem, detail)``: ``("missing", "")`` or
        ``("corrupt", why)``."""
        folder, array, checksums = self._array(array)
        file = os.path.join(folder, array.metadata.encode_chunk_key(coords))
        if not self.verify or not checksums:
            if not os.path.isfile(file):
                return "missing", ""
            return None if not self.verify else self._decode(array, coords)
        try:
            with open(file, "rb") as handle:
                data = handle.read()
        except (FileNotFoundError, IsADirectoryError):
            return "missing", ""
        if len(data) < 4:
            return "corrupt", f"{len(data)} bytes, shorter than its checksum"
        if google_crc32c.value(data[:-4]) != int.from_bytes(data[-4:], "little"):
            return "corrupt", "checksum mismatch"
        return None

    @staticmethod
    def _decode(array: zarr.Array[Any], coords: tuple[int, ...]) -> tuple[str, str] | None:
        """Decode a chunk of an array without checksums (an older store)."""
        selection = tuple(
            slice(c * size, (c + 1) * size) for c, size in zip(coords, array.chunks, strict=True)
        )
        try:
            array[selection]
        except Exception as error:  # any codec's decoding error: the chunk is unreadable
            return "corrupt", _decoding_error(error)
        return None


def _decoding_error(error: Exception) -> str:
    return f"cannot be decoded: {' '.join(str(error).split())[:120]}"


def read_flags(
    checker: ChunkChecker, array: zarr.Array[Any], name: Callable[[int], str]
) -> tuple[np.ndarray, list[ChunkProblem]]:
    """The flags of a 1-D bool progress array, and the problems of its unreadable chunks (their
    flags read as not set: the units are pending again). ``name(unit)`` describes a unit."""
    try:
        return np.asarray(array[:], dtype=bool), []
    except Exception:  # a corrupt flag chunk: find it below
        pass
    flags = np.zeros(array.shape[0], dtype=bool)
    problems = []
    size = array.chunks[0]
    for chunk in range(-(-array.shape[0] // size)):
        units = range(chunk * size, min((chunk + 1) * size, array.shape[0]))
        found = checker.check(array, (chunk,))
        if found is None:
            try:
                flags[units.start : units.stop] = array[units.start : units.stop]
                continue
            except Exception as error:  # unverified (verify=False) and unreadable
                found = "corrupt", _decoding_error(error)
        if found[0] == "corrupt":
            problems.append(
                ChunkProblem(
                    f"{name(units.start)} (progress flag)",
                    chunk_key(array, (chunk,)),
                    "corrupt",
                    found[1],
                    tuple(units),
                )
            )
    return flags, problems


@dataclass
class IntegrityReport:
    """The state of a store: progress, damaged chunks, checksums, provenance.

    Attributes
    ----------
    path
        The store.
    kind
        ``"capture"`` or ``"BTF"``.
    unit
        ``"step"`` or ``"pair"``.
    total
        Number of units (steps of the plan, direction pairs).
    pending
        Units not flagged done.
    complete_flag
        The store's ``complete`` attribute.
    problems
        Missing or corrupt chunks of units flagged done (and of whole-store arrays).
    checksums
        ``"yes"``, ``"no"`` (a store made before checksums) or ``"partly"``.
    verified
        Whether the chunks' bytes were checked, not only their presence.
    provenance
        What made the store: ``seed``, ``program``, ``backend``, ...
    """

    path: Path
    kind: str
    unit: str
    total: int
    pending: list[int]
    complete_flag: bool
    problems: list[ChunkProblem] = field(default_factory=list)
    checksums: str = "yes"
    verified: bool = True
    provenance: dict[str, Any] = field(default_factory=dict)

    @property
    def missing(self) -> list[ChunkProblem]:
        return [p for p in self.problems if p.problem == "missing"]

    @property
    def corrupt(self) -> list[ChunkProblem]:
        return [p for p in self.problems if p.problem == "corrupt"]

    @property
    def damaged_units(self) -> list[int]:
        """Units flagged done whose chunks are missing or corrupt, ascending."""
        return sorted({unit for problem in self.problems for unit in problem.units})

    @property
    def flags_disagree(self) -> bool:
        """The store says it is complete, but units are pending (a flag was lost)."""
        return self.complete_flag and bool(self.pending)

    @property
    def complete(self) -> bool:
        """Every unit flagged done (and the store says so)."""
        return self.complete_flag and not self.pending

    @property
    def healthy(self) -> bool:
        """No missing or corrupt chunk, and the complete flag agrees with the progress flags
        (an interrupted, incomplete store is healthy: it resumes)."""
        return not self.problems and not self.flags_disagree

    def damage(self) -> str | None:
        """One line naming the first damage, or ``None`` for a healthy store."""
        if self.problems:
            more = len(self.problems) - 1
            rest = f" (and {more} more damaged chunk{'s' * (more > 1)})" if more else ""
            return f"{self.problems[0]}{rest}"
        if self.flags_disagree:
            units = "s" * (len(self.pending) > 1)
            return (
                f"marked complete, but the progress flag{units} of {self.unit}{units} "
                f"{_shortened(self.pending)} {'are' if units else 'is'} not set"
            )
        return None

    def summary(self) -> dict[str, Any]:
        """The report as a flat summary, one value per line of a table."""
        first = [str(problem) for problem in self.problems[:4]]
        return {
            "store": str(self.path),
            "kind": self.kind,
            **self.provenance,
            "verdict": "healthy" if self.healthy else "damaged",
            "complete": self.complete,
            f"{self.unit}s": self.total,
            f"pending_{self.unit}s": len(self.pending),
            "missing_chunks": len(self.missing),
            "corrupt_chunks": len(self.corrupt),
            "first_damaged": first or "none",
            "flags": self.damage() if self.flags_disagree else "consistent",
            "checksums": self.checksums,
        }

    def as_dict(self) -> dict[str, Any]:
        """Everything, for JSON."""
        return {
            **self.summary(),
            "first_damaged": [str(problem) for problem in self.problems[:4]],
            "pending": self.pending,
            "damaged": [problem.as_dict() for problem in self.problems],
            "verified": self.verified,
        }


def _shortened(units: Iterable[int], shown: int = 5) -> str:
    units = list(units)
    text = ", ".join(str(unit) for unit in units[:shown])
    return text + (f", ... ({len(units)} in all)" if len(units) > shown else "")


def checksum_state(flags: Iterable[bool]) -> str:
    """``"yes"``, ``"no"`` or ``"partly"`` for the checksum flags of a store's arrays."""
    flags = list(flags)
    return "yes" if all(flags) else "no" if not any(flags) else "partly"
