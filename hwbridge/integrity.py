"""Integrity of spectwin's Zarr v3 stores: a checksum per chunk, and the progress record checked
against the chunks on disk.

The capture store (:mod:`hwbridge.store`) and the BTF store (``recon.btf.store``) record
progress with a flag per unit of work (a capture step, a BTF direction pair) and write the unit's
chunks before its flag. Two kinds of damage escape Zarr on its own:

- a chunk file that is deleted reads as the array's fill value, silently (a frame of zeros);
- a chunk file that is truncated or altered decodes into an error deep inside a codec, or, when
  the bytes still decompress, into wrong numbers.

So every array these stores create ends its codec chain with the ``crc32c`` codec, after Zstd
(:func:`checksummed_compressors`) or alone for the small per-unit arrays (index fields, flags:
:func:`checksum_only`): a chunk altered on disk raises on read instead of decoding.
:class:`ChunkChecker` checks a unit's chunks without decompressing them (the checksum covers the
compressed bytes): the chunk file must exist and, where the array has checksums, its last four
bytes must be the CRC-32C of the rest. Arrays made before checksums are checked by decoding
their chunks, which finds missing and truncated chunks but not every altered byte; the report
says "checksums: no".

A checksum alone does not say where a chunk belongs: a chunk swapped with another of its array,
copied over one, copied from another store or from an array of another chunk shape still
matches its own checksum. So each store is made with a random identity (``store_id``) and
seals its units' chunks (:class:`Seal`): when a unit's chunk is written, the store records a
64-bit digest of its identity, the chunk's key (the array's path and the chunk's grid
coordinates), the array's chunk shape and the chunk's CRC-32C; :class:`ChunkChecker` recomputes
it from the chunk on disk. A chunk that is not the one written in its place ("sealed
elsewhere") is reported and refused like a corrupt one. The settings that define a store's
content and the layout of its arrays are sealed at creation in the same way
(:meth:`Seal.settings`): :meth:`Seal.changed` names every setting or array edited since.

The stores live in local folders; chunk files are named by Zarr's default chunk key encoding
(``<array>/c/<i>/<j>/...``), which is what :func:`chunk_key` gives.
"""

from __future__ import annotations

import hashlib
import json
import os
import secrets
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
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
    "SEAL_DTYPE",
    "Seal",
    "array_at",
    "checksum_only",
    "checksum_state",
    "checksummed_compressors",
    "chunk_key",
    "group_at",
    "has_checksums",
    "metadata_problem",
    "read_flags",
    "seal_problem",
    "sealed_content",
    "stored_arrays",
    "with_empty_chunks",
]

SEAL_DTYPE = "uint64"
"""The type of a chunk's seal as the stores record it; 0 (the fill value) is no seal."""


def checksummed_compressors(level: int = 0) -> tuple[ZstdCodec, Crc32cCodec]:
    """The bytes-to-bytes codecs of every new array: Zstd (at ``level``; 0 is Zstd's default,
    3), then CRC-32C over the compressed bytes
    (``create_array(..., compressors=checksummed_compressors())``)."""
    return ZstdCodec(level=level, checksum=False), Crc32cCodec()


def checksum_only() -> tuple[Crc32cCodec]:
    """The bytes-to-bytes codecs of the small per-unit arrays (index fields, progress and
    written flags): CRC-32C alone. A chunk of a few bytes does not compress (Zstd's frame
    header is longer than a flag), and Zstd's codec hands every chunk to a thread, which cost
    more than the chunk's read or write (BENCHMARKS.md, "Capture store I/O")."""
    return (Crc32cCodec(),)


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


class Seal:
    """The seals of one store: digests keyed by its identity that tie its chunks to their
    places and its settings to their values at creation (see the module docstring).

    Parameters
    ----------
    store_id
        The store's identity (:meth:`new_id`), from its root attributes.
    """

    def __init__(self, store_id: str):
        self.store_id = store_id

    @staticmethod
    def new_id() -> str:
        """A new store's identity: 128 random bits, as hex."""
        return secrets.token_hex(16)

    def _digest(self, *parts: bytes) -> bytes:
        digest = hashlib.blake2b(self.store_id.encode(), digest_size=8)
        for part in parts:
            digest.update(len(part).to_bytes(8, "little"))
            digest.update(part)
        return digest.digest()

    def chunk(self, key: str, chunk_shape: Sequence[int], checksum: bytes) -> int:
        """The seal (never 0) of the chunk at ``key`` (:func:`chunk_key`: the array's path and
        the chunk's grid coordinates) of an array of chunks of ``chunk_shape``, whose bytes
        end with ``checksum`` (their CRC-32C, the crc32c codec's last four bytes)."""
        place = f"{key} {list(chunk_shape)}".encode()
        return max(1, int.from_bytes(self._digest(place, checksum), "little"))

    def chunk_on_disk(self, root: Path, array: zarr.Array[Any], coords: tuple[int, ...]) -> int:
        """The seal of the chunk of ``array`` at ``coords`` as now written under ``root``
        (the array must have checksums: :func:`has_checksums`)."""
        key = chunk_key(array, coords)
        with open(root / key, "rb") as handle:
            handle.seek(-4, os.SEEK_END)
            return self.chunk(key, array.chunks, handle.read(4))

    def settings(self, settings: Mapping[str, object]) -> dict[str, str]:
        """A digest (hex) per setting: JSON values, or arrays (by their dtype, shape and
        bytes); :func:`sealed_content` adds the layouts of a store's arrays."""
        sealed = {}
        for name, value in settings.items():
            if isinstance(value, np.ndarray):
                described = f"{value.dtype.str} {list(value.shape)}".encode()
                data = described + np.ascontiguousarray(value).tobytes()
            else:
                data = json.dumps(value, sort_keys=True, separators=(",", ":")).encode()
            sealed[name] = self._digest(name.encode(), data).hex()
        return sealed

    def changed(self, sealed: Mapping[str, str], settings: Mapping[str, object]) -> list[str]:
        """The names of the settings (and arrays) that differ from ``sealed``, those added or
        gone included, sorted."""
        now = self.settings(settings)
        return sorted(name for name in {*sealed, *now} if sealed.get(name) != now.get(name))


def stored_arrays(group: zarr.Group, skip: str | None = None) -> dict[str, zarr.Array[Any]]:
    """Every array of ``group`` and of its subgroups by path, but those under ``skip``."""
    with warnings.catch_warnings():  # files of the store's own, such as its writer's lock
        warnings.filterwarnings("ignore", "Object at .* is not recognized", UserWarning)
        members = group.members(max_depth=None)
    return {
        path: node
        for path, node in members
        if isinstance(node, zarr.Array) and path.split("/")[0] != skip
    }


def sealed_content(
    settings: Mapping[str, object], arrays: Iterable[zarr.Array[Any]]
) -> dict[str, object]:
    """What a store seals: ``settings`` and, by its path, every array's shape, chunk shape and
    dtype."""
    layouts = {
        array.path: {
            "shape": list(array.shape),
            "chunks": list(array.chunks),
            "dtype": str(array.dtype),
        }
        for array in arrays
    }
    return {**settings, **layouts}


def seal_problem(
    seal: Seal,
    sealed: Mapping[str, str],
    settings: Mapping[str, object],
    arrays: Iterable[zarr.Array[Any]],
) -> str | None:
    """What differs from the store's sealed ``settings`` and array layouts, in words, or
    ``None``."""
    changed = seal.changed(sealed, sealed_content(settings, arrays))
    if not changed:
        return None
    verb = "differs" if len(changed) == 1 else "differ"
    return f"{', '.join(changed)} {verb} from what the store was created with"


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
    seal
        The store's seals: a chunk given its recorded seal is checked against it too.
    """

    def __init__(self, root: Path, *, verify: bool = True, seal: Seal | None = None):
        self.root = Path(root)
        self.verify = verify
        self.seal = seal
        self._arrays: dict[str, tuple[str, zarr.Array[Any], bool, tuple[int, ...]]] = {}

    def _array(self, array: zarr.Array[Any]) -> tuple[str, zarr.Array[Any], bool, tuple[int, ...]]:
        """The array's path, the array, whether it has checksums and its chunk shape (looked
        up once)."""
        path = array.path
        if path not in self._arrays:
            self._arrays[path] = (path, array, has_checksums(array), array.chunks)
        return self._arrays[path]

    def checksums(self, array: zarr.Array[Any]) -> bool:
        return self._array(array)[2]

    def check(
        self, array: zarr.Array[Any], coords: tuple[int, ...], sealed: int | None = None
    ) -> tuple[str, str] | None:
        """``None`` for a sound chunk, else ``(problem, detail)``: ``("missing", "")`` or
        ``("corrupt", why)``; a chunk whose seal is not ``sealed`` (when given, verifying, and
        the checker has the store's :class:`Seal`) is corrupt too: it was written elsewhere."""
        path, array, checksums, chunk_shape = self._array(array)
        key = f"{path}/{array.metadata.encode_chunk_key(coords)}"
        file = os.path.join(self.root, key)
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
        if sealed is None or self.seal is None:
            return None
        if not sealed:
            return "corrupt", "no seal recorded for it"
        if self.seal.chunk(key, chunk_shape, data[-4:]) != sealed:
            return "corrupt", "sealed elsewhere: moved, swapped, from another store or reshaped"
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
    """The values of a 1-D progress array as stored (bool flags, or the seals of a BTF store's
    pairs, 0 while pending), and the problems of its unreadable chunks (their values read as
    not set: the units are pending again). ``name(unit)`` describes a unit."""
    try:
        return np.asarray(array[:]), []
    except Exception:  # a corrupt flag chunk: find it below
        pass
    flags = np.zeros(array.shape[0], dtype=array.dtype)
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
