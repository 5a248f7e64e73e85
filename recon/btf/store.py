"""The BTF store: a spectral bidirectional texture function in Zarr v3, assembled pair by pair.

A measured spectral BTF (thesis 4.1.2) is one registered, radiometrically and spectrally
calibrated texture per direction pair: reflectance in 1/sr on a wavelength grid. Calibration
produces the textures one direction pair at a time, so the store is created empty for a known
shape, grid and set of directions and filled incrementally; a flag per pair records what has been
written, and the store calls itself complete only when every pair is.

Layout of ``<name>.btf.zarr`` (ARCHITECTURE.md, "Stores"):

- attributes (:class:`recon.btf.schema.BTFAttrs`): ``format`` (``"spectwin.btf"``),
  ``format_version`` (a store of another version is refused on opening), ``store_id`` (its
  random identity), ``sealed`` (digests of what defines its content), ``units``
  (``"1/sr"``), ``material``, ``rig`` (of the source capture), ``source_capture`` (path of the
  capture store it was calibrated from, or null), ``calibration`` (a JSON summary of the
  calibration), ``complete``, ``inputs`` (the hashes of what processing read, which a resume must
  match: :mod:`recon.btf.inputs`), and what processing adds (:meth:`BTFStore.set_attribute`);
- ``reflectance``: float32 ``(n_pairs, H, W, K)``, one chunk per direction pair, band axis last,
  texel ``(y, x)`` row-major; unwritten pairs hold NaN;
- ``light_dirs``, ``view_dirs``: float64 ``(n_pairs, 3)`` unit vectors in the sample frame
  (z = surface normal);
- ``wavelengths``: float64 ``(K,)`` band centres in nm;
- ``written``: uint64 ``(n_pairs,)``, one chunk per pair: the seal of the pair's reflectance
  chunk (``hwbridge.integrity.Seal``), set only after the pair's texture is written; 0 while
  the pair is pending;
- ``pca/``: optional compressed form (thesis 4.1.2; written by :mod:`recon.btf.compression`),
  with its own attributes (:class:`recon.btf.schema.CompressedAttrs`), ``complete`` set after
  all of its arrays.

Conventions shared with the capture store (``hwbridge.store``): a store is never overwritten by
:meth:`BTFStore.create`; data are written before the flag that declares them; one writer owns each
chunk (a worker writes the pairs it owns, and the coordinator of a distributed run sets
``complete`` when the workers are done: :meth:`BTFStore.refresh_complete`), and rewriting a pair
first clears its flag, so an interrupted rewrite leaves the pair pending, never silently corrupt.

Integrity (``hwbridge.integrity``): every array ends its codec chain with a CRC-32C checksum, so a
chunk altered on disk raises on read, and every pair's reflectance chunk is sealed to its place
and the store, so one swapped, moved, copied from another store or of another shape is found and
refused like a corrupt one; the settings that define the store (material, rig, source capture,
calibration), its directions, bands and the shape, chunks and dtype of every array but the
compressed form's are sealed at creation, and :meth:`BTFStore.open` refuses a store where any
differs, naming them; :meth:`BTFStore.check` checks every pair flagged written
against its reflectance chunk (a missing chunk would read as NaN) and the compressed form's
chunks, and names the damaged pairs and chunk keys; :meth:`BTFStore.open` refuses missing or
unreadable metadata, naming the file; reading a pair whose chunk is missing or corrupt raises
:class:`~recon.errors.DamagedDataError`. :meth:`BTFStore.prepare_resume` flags damaged pairs
pending again, so a resumed processing writes them again. Stores made before
seals are refused by their format version.

References
----------
- The thesis, section 4.1.2 (texture extraction, Eq. 3.6, 6561 textures of 800 x 800 texels and
  33 bands, 516 GB).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import zarr

from hwbridge.integrity import (
    SEAL_DTYPE,
    ChunkChecker,
    ChunkProblem,
    IntegrityReport,
    Seal,
    checksum_only,
    checksum_state,
    checksummed_compressors,
    chunk_key,
    has_checksums,
    metadata_problem,
    read_flags,
    seal_problem,
    sealed_content,
    stored_arrays,
    with_empty_chunks,
)
from hwbridge.local_store import open_local_group
from hwbridge.schema import parse, refuse_other_version
from recon.btf.schema import (
    BTF_FORMAT,
    BTF_FORMAT_VERSION,
    BTF_UNITS,
    BTFAttrs,
    BTFInputs,
    CompressedAttrs,
)
from recon.errors import DamagedDataError, InputError, Remedy
from recon.spectra import WavelengthGrid

__all__ = [
    "BTF_FORMAT",
    "BTF_FORMAT_VERSION",
    "BTF_UNITS",
    "COMPRESSED_GROUP",
    "BTFStore",
    "write_btf",
]

COMPRESSED_GROUP = "pca"
"""Name of the group that holds the compressed form (ARCHITECTURE.md: ``pca/``)."""

_UNIT_TOLERANCE = 1e-6
_ARRAYS = ("reflectance", "light_dirs", "view_dirs", "wavelengths", "written")
# The attributes that define a store's content, sealed at creation with its directions and bands.
_SEALED_ATTRS = (
    "format",
    "format_version",
    "units",
    "material",
    "rig",
    "source_capture",
    "calibration",
)


def _check_directions(name: str, directions: np.ndarray, n_pairs: int | None) -> np.ndarray:
    """``directions`` as float64 ``(n, 3)`` finite unit vectors in the upper hemisphere."""
    directions = np.asarray(directions, dtype=np.float64)
    if directions.ndim != 2 or directions.shape[1] != 3 or directions.shape[0] == 0:
        raise InputError(
            f"{name}: expected an (n_pairs, 3) array of unit vectors, got shape {directions.shape}"
        )
    if n_pairs is not None and directions.shape[0] != n_pairs:
        raise InputError(
            f"{name}: expected {n_pairs} directions (one per pair), got {directions.shape[0]}"
        )
    if not np.all(np.isfinite(directions)):
        raise InputError(f"{name}: expected finite unit vectors, found NaN or infinity")
    norms = np.linalg.norm(directions, axis=1)
    bad = np.flatnonzero(np.abs(norms - 1.0) > _UNIT_TOLERANCE)
    if bad.size:
        raise InputError(
            f"{name}: expected unit vectors (|d| = 1 within {_UNIT_TOLERANCE:g}), but pair "
            f"{bad[0]} has |d| = {norms[bad[0]]:.9g} ({bad.size} such pairs)"
        )
    below = np.flatnonzero(directions[:, 2] < 0)
    if below.size:
        raise InputError(
            f"{name}: expected directions above the sample (z >= 0 in the sample frame), but "
            f"pair {below[0]} has z = {directions[below[0], 2]:.6g}"
        )
    return directions


def _texel_shape(texels: int | tuple[int, ...]) -> tuple[int, int]:
    shape = (texels, texels) if np.ndim(texels) == 0 else tuple(np.asarray(texels, dtype=object))
    if len(shape) != 2 or not all(
        isinstance(n, int | np.integer) and not isinstance(n, bool) and n > 0 for n in shape
    ):
        raise InputError(
            f"texels: expected a positive int or (height, width) of positive ints, got {texels!r}"
        )
    return int(shape[0]), int(shape[1])


def _json_attr(name: str, value: Any) -> Any:
    try:
        return json.loads(json.dumps(value))
    except (TypeError, ValueError) as error:
        raise InputError(
            f"{name}: expected JSON-serialisable data (numbers, strings, lists, dicts), got "
            f"{type(value).__name__}: {error}"
        ) from None


class BTFStore:
    """A spectral BTF store on disk; create it with :meth:`create`, reopen it with :meth:`open`.

    Opening reads only the small arrays (directions, wavelengths, flags); reflectance is read
    lazily, one direction pair (one chunk) at a time or as a whole.

    Examples
    --------
    >>> store = BTFStore.create(  # doctest: +SKIP
    ...     "wallpaper.btf.zarr", light_dirs=lights, view_dirs=views, texels=64,
    ...     grid=DEFAULT_GRID, material="wallpaper")
    >>> for pair, texture in enumerate(textures):  # as calibration proceeds  # doctest: +SKIP
    ...     store.write_pair(pair, texture, grid=DEFAULT_GRID)
    >>> store.complete  # doctest: +SKIP
    True
    """

    def __init__(self, group: zarr.Group, path: Path, *, writable: bool):
        self._group = group
        self.path = path
        self.writable = writable
        # The arrays as opened (their metadata read once; their chunks are read on each access).
        self._arrays: dict[str, zarr.Array[Any]] = {}
        attrs = group.attrs
        if attrs.get("format") != BTF_FORMAT:
            raise InputError(
                f"{path}: not a BTF store (format attribute {attrs.get('format')!r}, expected "
                f"{BTF_FORMAT!r})"
            )
        refuse_other_version(
            path,
            "a BTF store",
            "format version",
            attrs.get("format_version"),
            BTF_FORMAT_VERSION,
            remedy=Remedy.process,
        )
        parse(BTFAttrs, dict(attrs), f"{path}: BTF store attributes")
        problems = {name: metadata_problem(path, name) for name in _ARRAYS}
        if problems["written"] and not (path / "written").is_dir():
            # ``written`` is created last: without it (and its chunks) the creation stopped.
            missing = [name for name, problem in problems.items() if problem]
            raise InputError(
                f"{path}: BTF store lacks arrays {missing} (its creation was interrupted?)"
            )
        for name, problem in problems.items():
            if problem:
                raise DamagedDataError(
                    f"{path}: damaged store: {problem} (the metadata of {name}); process the "
                    "capture again"
                )
        checker = ChunkChecker(path, verify=False)
        for name in ("wavelengths", "light_dirs", "view_dirs"):
            array = self._array(name)
            if checker.check(array, (0,) * array.ndim):
                raise DamagedDataError(
                    f"{path}: damaged store: {chunk_key(array, (0,) * array.ndim)} is missing "
                    f"(the {name}); process the capture again"
                )
        self.grid = WavelengthGrid(self._read_small(self._array("wavelengths")))
        self.light_dirs = self._read_small(self._array("light_dirs"))
        self.view_dirs = self._read_small(self._array("view_dirs"))
        for directions in (self.light_dirs, self.view_dirs):
            directions.setflags(write=False)
        self._seal = Seal(str(attrs.get("store_id")))
        sealed = attrs.get("sealed")
        problem = seal_problem(
            self._seal,
            sealed if isinstance(sealed, dict) else {},
            _sealed_settings(attrs, self.light_dirs, self.view_dirs, self.grid.wavelengths_nm),
            stored_arrays(group, skip=COMPRESSED_GROUP).values(),
        )
        if problem:
            raise DamagedDataError(
                f"{path}: damaged store: {problem}; process the capture again",
                remedy=Remedy.process,
            )
        # Flags known to be set (a cache, refreshed lazily: other processes may write pairs); an
        # unreadable flag counts as unset here, and check() reports it.
        written = self._array("written")
        seals, _ = read_flags(checker, written, self._pair_name)
        self._known_written = seals.astype(bool)
        shape = self._array("reflectance").shape
        n_pairs = self.light_dirs.shape[0]
        if (
            len(shape) != 4
            or shape[0] != n_pairs
            or shape[3] != self.grid.size
            or self.view_dirs.shape != (n_pairs, 3)
            or written.shape != (n_pairs,)
        ):
            raise InputError(
                f"{path}: inconsistent BTF store: reflectance {shape}, light_dirs "
                f"{self.light_dirs.shape}, view_dirs {self.view_dirs.shape}, "
                f"{self.grid.size} wavelengths, written {written.shape}"
            )

    # -- creating and opening ----------------------------------------------------------------

    @classmethod
    def create(
        cls,
        path: str | Path,
        *,
        light_dirs: np.ndarray,
        view_dirs: np.ndarray,
        texels: int | tuple[int, ...],
        grid: WavelengthGrid,
        material: str,
        source_capture: str | Path | None = None,
        calibration: Mapping[str, Any] | None = None,
        rig: str | None = None,
        inputs: BTFInputs | None = None,
    ) -> BTFStore:
        """A new, empty store (no pair written); never overwrites an existing path.

        Parameters
        ----------
        path
            Directory of the store, by convention ``<name>.btf.zarr``.
        light_dirs, view_dirs
            ``(n_pairs, 3)`` unit vectors in the sample frame, z >= 0; pair ``i`` is lit from
            ``light_dirs[i]`` and seen from ``view_dirs[i]``.
        texels
            Texture size: ``n`` for ``n x n`` or ``(height, width)``.
        grid
            Band centres of the reflectance's last axis.
        material
            Name of the material sample.
        source_capture
            Path of the capture store the BTF is calibrated from (provenance), if any.
        calibration
            JSON-serialisable summary of the calibration (white reference, exposure plan, ...).
        rig
            The kind of rig the source capture was made with (the ``rig`` of its rig attribute), or
            ``None`` for a BTF from elsewhere (imported).
        inputs
            What processing makes the store from (:mod:`recon.btf.inputs`), recorded so that a
            resumed processing is refused other inputs; ``None`` records none.
        """
        path = Path(path)
        if path.exists():
            raise InputError(
                f"{path} exists: expected a new store (nothing was overwritten)",
                remedy=Remedy.resume_or_rename,
            )
        light_dirs = _check_directions("light_dirs", light_dirs, None)
        view_dirs = _check_directions("view_dirs", view_dirs, light_dirs.shape[0])
        height, width = _texel_shape(texels)
        if not isinstance(grid, WavelengthGrid):
            raise InputError(f"grid: expected a WavelengthGrid, got {type(grid).__name__}")
        if not isinstance(material, str) or not material.strip():
            raise InputError(f"material: expected a non-empty name, got {material!r}")
        attrs = parse(
            BTFAttrs,
            {
                "format": BTF_FORMAT,
                "format_version": BTF_FORMAT_VERSION,
                "store_id": Seal.new_id(),
                "sealed": {},
                "units": BTF_UNITS,
                "material": material,
                "rig": rig,
                "source_capture": None if source_capture is None else str(source_capture),
                "calibration": _json_attr("calibration", dict(calibration or {})),
                "complete": False,
                **({} if inputs is None else {"inputs": inputs.model_dump(mode="json")}),
            },
            f"{path}: BTF store attributes",
        )
        n_pairs, n_bands = light_dirs.shape[0], grid.size

        group = open_local_group(path, mode="w-", zarr_format=3)
        group.attrs.update(attrs.model_dump(mode="json", exclude_unset=True))
        group.create_array(
            "reflectance",
            shape=(n_pairs, height, width, n_bands),
            chunks=(1, height, width, n_bands),
            dtype="float32",
            fill_value=np.nan,
            attributes={"units": BTF_UNITS, "axes": ["pair", "y", "x", "band"]},
            compressors=checksummed_compressors(),
        )
        for name, directions in (("light_dirs", light_dirs), ("view_dirs", view_dirs)):
            array = group.create_array(
                name,
                shape=(n_pairs, 3),
                chunks=(n_pairs, 3),
                dtype="float64",
                compressors=checksummed_compressors(),
            )
            with_empty_chunks(array)[:] = directions
        wavelengths = group.create_array(
            "wavelengths",
            shape=(n_bands,),
            chunks=(n_bands,),
            dtype="float64",
            attributes={"units": "nm"},
            compressors=checksummed_compressors(),
        )
        wavelengths[:] = grid.wavelengths_nm
        group.create_array(
            "corners_xy",
            shape=(n_pairs, 4, 2),
            chunks=(1, 4, 2),
            dtype="float64",
            fill_value=np.nan,
            attributes={"units": "px", "meaning": "registered image corners of the texture square"},
            compressors=checksum_only(),
        )
        # Created last: a store whose creation was interrupted lacks it and does not open. A
        # pair's flag is the seal of its reflectance chunk (0: pending).
        group.create_array(
            "written",
            shape=(n_pairs,),
            chunks=(1,),
            dtype=SEAL_DTYPE,
            fill_value=0,
            compressors=checksum_only(),
        )
        stored = attrs.model_dump(mode="json", exclude_unset=True)
        settings = _sealed_settings(stored, light_dirs, view_dirs, grid.wavelengths_nm)
        group.attrs["sealed"] = Seal(attrs.store_id).settings(
            sealed_content(settings, stored_arrays(group).values())
        )
        return cls(group, path, writable=True)

    @classmethod
    def open(cls, path: str | Path, *, writable: bool = False) -> BTFStore:
        """Open an existing store, read-only unless ``writable`` (to resume writing pairs)."""
        path = Path(path)
        if not path.exists():
            raise InputError(f"{path} does not exist: expected a BTF store", remedy=Remedy.process)
        if not path.is_dir():
            raise InputError(
                f"{path} is a file: expected a BTF store (a folder)", remedy=Remedy.process
            )
        root_problem = metadata_problem(path, "")
        if root_problem and any((path / name).is_dir() for name in _ARRAYS):
            raise DamagedDataError(
                f"{path}: damaged store: {root_problem}: the root metadata (format, material, "
                "calibration, complete) is gone; process the capture again"
            )
        try:
            group = open_local_group(path, mode="r+" if writable else "r", zarr_format=3)
        except (OSError, ValueError, TypeError) as error:
            raise InputError(
                f"{path}: not a BTF store (not a Zarr v3 group: {error})", remedy=Remedy.process
            ) from None
        try:
            return cls(group, path, writable=writable)
        except json.JSONDecodeError as error:
            raise DamagedDataError(
                f"{path}: damaged store: unreadable metadata of an array ({error}); process the "
                "capture again"
            ) from error

    # -- description ---------------------------------------------------------------------------

    @property
    def shape(self) -> tuple[int, int, int, int]:
        """``(n_pairs, H, W, K)``."""
        n_pairs, height, width, bands = self._array("reflectance").shape
        return n_pairs, height, width, bands

    @property
    def n_pairs(self) -> int:
        return self.shape[0]

    @property
    def texels(self) -> tuple[int, int]:
        """``(H, W)``."""
        return self.shape[1], self.shape[2]

    @property
    def material(self) -> str:
        return self.metadata.material

    @property
    def attrs(self) -> dict[str, Any]:
        """All attributes (provenance included) as a plain dict, as now on disk; read them
        through :attr:`metadata`."""
        return dict(self._fresh_attrs())

    @property
    def metadata(self) -> BTFAttrs:
        """The attributes, validated, as now on disk."""
        return parse(BTFAttrs, self.attrs, f"{self.path}: BTF store attributes")

    @property
    def complete(self) -> bool:
        """True once every pair is written (and not being rewritten), as now on disk."""
        return bool(self._fresh_attrs()["complete"])

    def written(self) -> np.ndarray:
        """One bool per pair: its texture is written (a corrupt flag raises, naming it)."""
        written = self._array("written")
        try:
            self._known_written = np.asarray(written[:], dtype=bool)
        except (ValueError, RuntimeError) as error:
            _, problems = read_flags(ChunkChecker(self.path), written, self._pair_name)
            first = problems[0] if problems else f"written cannot be read ({error})"
            raise DamagedDataError(
                f"{self.path}: damaged store: {first}", remedy=Remedy.reprocess_pairs
            ) from None
        return self._known_written.copy()

    def pending_pairs(self) -> list[int]:
        """Indices of the pairs not yet written, ascending."""
        return np.flatnonzero(~self.written()).tolist()

    def __repr__(self) -> str:
        state = "complete" if self.complete else f"{len(self.pending_pairs())} pairs pending"
        return (
            f"BTFStore({str(self.path)!r}, material={self.material!r}, shape={self.shape}, "
            f"grid={self.grid.describe()}, {state})"
        )

    # -- writing -------------------------------------------------------------------------------

    def write_pair(
        self,
        pair: int,
        reflectance: np.ndarray,
        *,
        grid: WavelengthGrid | None = None,
        light_dir: np.ndarray | None = None,
        view_dir: np.ndarray | None = None,
        corners_xy: np.ndarray | None = None,
        check_complete: bool = True,
    ) -> None:
        """Write the texture of direction ``pair``, then flag it written.

        Idempotent for a redone pair. When the last pending pair is written the store is marked
        complete. Rewriting a pair of a complete store first marks it incomplete, and drops a
        compressed form (which no longer matches the reflectance).

        Parameters
        ----------
        pair
            Index in ``0 .. n_pairs - 1``.
        reflectance
            ``(H, W, K)`` finite reflectance in 1/sr (stored as float32).
        grid
            The grid of ``reflectance``'s band axis; when given it must equal the store's.
        light_dir, view_dir
            The pair's directions as the caller knows them; when given they must match the
            store's (within 1e-6), a guard against writing a texture into the wrong slot.
        corners_xy
            ``(4, 2)`` image corners ``(x, y)`` of the texture square in the raw frames, when the
            texture was registered (thesis 4.1.2); kept for checks, see :meth:`corners_xy`.
        check_complete
            ``False`` for a worker of a distributed run: it owns only its pairs' chunks and
            leaves ``complete`` to the coordinator (:meth:`refresh_complete`).
        """
        self._require_writable()
        pair = self._check_pair(pair)
        if grid is not None and grid != self.grid:
            raise InputError(
                f"grid: the texture is on {grid.describe()}, the store on {self.grid.describe()}; "
                "resample explicitly (recon.spectra.resample)"
            )
        for name, given, stored in (
            ("light_dir", light_dir, self.light_dirs),
            ("view_dir", view_dir, self.view_dirs),
        ):
            if given is not None and not np.allclose(
                np.asarray(given, np.float64), stored[pair], rtol=0, atol=_UNIT_TOLERANCE
            ):
                raise InputError(
                    f"{name}: pair {pair} of the store has {name} {stored[pair].tolist()}, got "
                    f"{np.asarray(given).tolist()}"
                )
        values = np.asarray(reflectance)
        expected = self.shape[1:]
        if values.shape != expected:
            raise InputError(
                f"reflectance: expected a texture of shape (H, W, K) = {expected}, got "
                f"{values.shape}"
            )
        if not np.issubdtype(values.dtype, np.floating) and not np.issubdtype(
            values.dtype, np.integer
        ):
            raise InputError(f"reflectance: expected real numbers, got {values.dtype}")
        with np.errstate(over="ignore"):
            values = values.astype(np.float32)
        if not np.all(np.isfinite(values)):
            bad = np.argwhere(~np.isfinite(values))[0].tolist()
            raise InputError(
                f"reflectance: expected finite values in 1/sr, found NaN or infinity (or a value "
                f"beyond float32) at (y, x, band) = {tuple(bad)} of pair {pair}"
            )
        written = self._array("written")
        if written[pair]:
            self._set_complete(False)
            written[pair] = False
            self._known_written[pair] = False
        self._drop_compressed()
        textures = self._array("reflectance")
        textures[pair] = values
        if corners_xy is not None:
            corners = np.asarray(corners_xy, dtype=np.float64)
            if corners.shape != (4, 2) or not np.all(np.isfinite(corners)):
                raise InputError(
                    f"corners_xy: expected finite (4, 2) image corners, got shape {corners.shape}"
                )
            self._array("corners_xy")[pair] = corners
        written[pair] = self._seal.chunk_on_disk(self.path, textures, (pair, 0, 0, 0))
        self._known_written[pair] = True
        if check_complete and self._all_written():
            self._set_complete(True)

    def refresh_complete(self) -> bool:
        """Set ``complete`` from the flags on disk (after the workers of a distributed run are
        done) and return it."""
        self._require_writable()
        complete = not self.pending_pairs()
        self._set_complete(complete)
        return complete

    def set_attribute(self, name: str, value: Any) -> None:
        """Record what processing found: one of the attributes of :class:`~recon.btf.schema.
        BTFAttrs` that creation leaves unset (``unregistered_pairs``, ``dome_pairs``, ...),
        checked against the model."""
        self._require_writable()
        added = [key for key, info in BTFAttrs.model_fields.items() if not info.is_required()]
        if name not in added:
            raise InputError(f"attribute {name!r}: expected one of {added}")
        checked = parse(
            BTFAttrs, {**self._fresh_attrs(), name: value}, f"{self.path}: attribute {name}"
        )
        self._group.attrs[name] = checked.model_dump(mode="json", include={name})[name]

    def corners_xy(self) -> np.ndarray:
        """``(n_pairs, 4, 2)`` registered image corners per pair (NaN where none were given)."""
        if "corners_xy" not in self._group:
            return np.full((self.n_pairs, 4, 2), np.nan)
        return np.asarray(self._array("corners_xy")[:])

    def mark_complete(self) -> None:
        """Recompute the complete flag from the pair flags (after writers in other processes);
        raise if any pair is still pending."""
        self._require_writable()
        pending = self.pending_pairs()
        if pending:
            self._set_complete(False)
            raise InputError(
                f"{self.path}: cannot mark complete, {len(pending)} pairs pending "
                f"(first {pending[:5]})"
            )
        self._set_complete(True)

    # -- reading -------------------------------------------------------------------------------

    def read(self, *, allow_incomplete: bool = False) -> np.ndarray:
        """The whole reflectance ``(n_pairs, H, W, K)`` float32 in 1/sr.

        An incomplete store raises unless ``allow_incomplete``; then unwritten pairs are NaN.
        """
        self._require_complete(allow_incomplete, "read")
        self._require_chunks(np.flatnonzero(self.written()))
        return self._decoded(slice(None))

    def read_pair(self, pair: int, *, allow_incomplete: bool = False) -> np.ndarray:
        """The texture ``(H, W, K)`` of one pair (one chunk read).

        A pair that is not written always raises; a written pair of an incomplete store is
        returned only with ``allow_incomplete``.
        """
        pair = self._check_pair(pair)
        self._require_complete(allow_incomplete, f"read pair {pair} of")
        if not self._array("written")[pair]:
            raise InputError(f"{self.path}: pair {pair} is not written yet")
        self._require_chunks([pair])
        return self._decoded(pair)

    def iter_pairs(self, *, allow_incomplete: bool = False) -> Iterator[tuple[int, np.ndarray]]:
        """``(pair, texture)`` for every written pair, one chunk in memory at a time."""
        self._require_complete(allow_incomplete, "iterate over")
        for pair in np.flatnonzero(self.written()).tolist():
            self._require_chunks([pair])
            yield pair, self._decoded(pair)

    def reflectance(self, *, allow_incomplete: bool = False) -> zarr.Array[Any]:
        """The lazy Zarr array ``(n_pairs, H, W, K)``: slicing it reads only the chunks needed
        (e.g. ``store.reflectance()[:, y, x]`` is the BRDF of texel ``(y, x)``)."""
        self._require_complete(allow_incomplete, "read")
        return self._array("reflectance")

    # -- the compressed form (recon.btf.compression) -------------------------------------------

    @property
    def has_compressed(self) -> bool:
        """True when a complete compressed form is stored."""
        return (
            COMPRESSED_GROUP in self._group
            and self._compressed_group().attrs.get("complete") is True
        )

    def write_compressed(self, arrays: Mapping[str, np.ndarray], attrs: Mapping[str, Any]) -> None:
        """Replace the ``pca/`` group with ``arrays`` (names may contain ``/``) and ``attrs``
        (:class:`~recon.btf.schema.CompressedAttrs` without ``arrays`` and ``complete``).

        The group's ``complete`` attribute turns true only after every array is written. The
        store itself must be complete: a compressed form describes the finished BTF.
        """
        self._require_writable()
        self._require_complete(False, "compress")
        described = parse(
            CompressedAttrs,
            {**attrs, "arrays": sorted(arrays), "complete": True},
            f"{self.path}: {COMPRESSED_GROUP}/ attributes",
        )
        self._drop_compressed()
        group = self._group.create_group(COMPRESSED_GROUP, attributes={"complete": False})
        for name, values in arrays.items():
            values = np.asarray(values)
            array = group.create_array(
                name,
                shape=values.shape,
                chunks=_compressed_chunks(values),
                dtype=values.dtype,
                compressors=checksummed_compressors(),
            )
            with_empty_chunks(array)[...] = values
        group.attrs.update(described.model_dump(mode="json"))

    def read_compressed(self) -> tuple[dict[str, np.ndarray], CompressedAttrs]:
        """The arrays and attributes of the ``pca/`` group; raise if absent or incomplete."""
        if COMPRESSED_GROUP not in self._group:
            raise InputError(f"{self.path}: no compressed form ({COMPRESSED_GROUP}/)")
        group = self._compressed_group()
        if group.attrs.get("complete") is not True:
            raise InputError(
                f"{self.path}: the compressed form ({COMPRESSED_GROUP}/) was not completely "
                "written; compress again"
            )
        attrs = parse(
            CompressedAttrs, dict(group.attrs), f"{self.path}: {COMPRESSED_GROUP}/ attributes"
        )
        arrays = {}
        for name in attrs.arrays:
            try:
                arrays[name] = np.asarray(_array_in(group, name, self.path)[...])
            except (KeyError, ValueError, RuntimeError) as error:
                raise DamagedDataError(
                    f"{self.path}: damaged store: the compressed form's array "
                    f"{COMPRESSED_GROUP}/{name} cannot be read ({error}); compress again"
                ) from None
        return arrays, attrs

    # -- integrity -----------------------------------------------------------------------------

    def check(self, *, verify: bool = True) -> IntegrityReport:
        """Check every pair flagged written against its chunks, and the compressed form's
        chunks (see ``hwbridge.integrity``).

        Parameters
        ----------
        verify
            Check the chunks' checksums too (reads every chunk once, without decompressing);
            ``False``: only that the chunk files exist.

        Returns
        -------
        IntegrityReport
            Pending pairs, missing and corrupt chunks by pair and chunk key (those of the
            compressed form name no pair), whether the store has checksums, its material and
            source capture.
        """
        checker = ChunkChecker(self.path, verify=verify, seal=self._seal)
        written = self._array("written")
        seals, problems = read_flags(checker, written, self._pair_name)
        flags = seals.astype(bool)
        reflectance = self._array("reflectance")
        corners = self._array("corners_xy") if "corners_xy" in self._group else None
        for pair in np.flatnonzero(flags).tolist():
            for array, required in ((reflectance, True), (corners, False)):
                if array is None:
                    continue
                coords = (pair, *(0,) * (array.ndim - 1))
                outcome = checker.check(array, coords, int(seals[pair]) if required else None)
                if outcome is not None and (required or outcome[0] == "corrupt"):
                    key = chunk_key(array, coords)
                    problems.append(ChunkProblem(self._pair_name(pair), key, *outcome, (pair,)))
        arrays = [self._array(name) for name in _ARRAYS]
        problems += self._compressed_problems(checker, arrays)
        attrs = self.metadata
        return IntegrityReport(
            path=self.path,
            kind="BTF",
            unit="pair",
            total=self.n_pairs,
            pending=np.flatnonzero(~flags).tolist(),
            complete_flag=attrs.complete,
            problems=problems,
            checksums=checksum_state(checker.checksums(array) for array in arrays),
            verified=verify,
            provenance={"material": attrs.material, "source_capture": attrs.source_capture},
        )

    def prepare_resume(self) -> list[ChunkProblem]:
        """Before processing resumes: flag the pairs whose chunks are missing or corrupt pending
        again (their corrupt chunks are deleted) and drop a damaged compressed form; returns the
        problems found."""
        self._require_writable()
        report = self.check()
        if report.flags_disagree or report.problems:
            self._set_complete(False)
        written = self._array("written")
        for problem in report.problems:
            if problem.problem == "corrupt":
                (self.path / problem.key).unlink(missing_ok=True)
            if not problem.units:
                self._drop_compressed()
        for pair in report.damaged_units:
            written[pair] = False
            self._known_written[pair] = False
        return report.problems

    def _compressed_problems(
        self, checker: ChunkChecker, arrays: list[zarr.Array[Any]]
    ) -> list[ChunkProblem]:
        """Missing or corrupt chunks of a complete compressed form (its arrays are added to
        ``arrays``, for the checksum state)."""
        if COMPRESSED_GROUP not in self._group:
            return []
        group = self._compressed_group()
        attrs: dict[str, Any] = dict(group.attrs)
        if attrs.get("complete") is not True:
            return []
        problems = []
        item = f"compressed form ({COMPRESSED_GROUP}/)"
        for name in attrs.get("arrays", []):
            node = f"{COMPRESSED_GROUP}/{name}"
            problem = metadata_problem(self.path, node)
            if problem:
                problems.append(ChunkProblem(item, f"{node}/zarr.json", "missing"))
                continue
            array = _array_in(group, name, self.path)
            arrays.append(array)
            # Written with every chunk, when it has checksums; before, chunks of only the fill
            # value were left out.
            required = has_checksums(array)
            for coords in np.ndindex(*array.cdata_shape):
                outcome = checker.check(array, tuple(coords))
                if outcome is not None and (required or outcome[0] == "corrupt"):
                    problems.append(ChunkProblem(item, chunk_key(array, coords), *outcome))
        return problems

    # -- helpers -------------------------------------------------------------------------------

    def _check_pair(self, pair: int) -> int:
        if isinstance(pair, bool) or not isinstance(pair, int | np.integer):
            raise InputError(f"pair: expected an integer index, got {pair!r}")
        if not 0 <= pair < self.n_pairs:
            raise InputError(f"pair: expected an index in 0..{self.n_pairs - 1}, got {pair}")
        return int(pair)

    def _pair_name(self, pair: int) -> str:
        return f"pair {pair}"

    def _array(self, name: str) -> zarr.Array[Any]:
        """The array ``name``, opened once per store object: an open is a metadata read, and a
        rendering reads each texture through several arrays."""
        array = self._arrays.get(name)
        if array is None:
            array = self._arrays[name] = _array_in(self._group, name, self.path)
        return array

    def _compressed_group(self) -> zarr.Group:
        group = self._group[COMPRESSED_GROUP]
        if not isinstance(group, zarr.Group):
            raise DamagedDataError(
                f"{self.path}: damaged store: {COMPRESSED_GROUP} is an array; compress again"
            )
        return group

    def _read_small(self, array: zarr.Array[Any]) -> np.ndarray:
        """A whole small array (directions, wavelengths); unreadable is a damaged store."""
        try:
            return np.asarray(array[:])
        except (ValueError, RuntimeError) as error:
            raise DamagedDataError(
                f"{self.path}: damaged store: {array.path} cannot be read "
                f"({' '.join(str(error).split())[:120]}); process the capture again"
            ) from None

    def _require_chunks(self, pairs: Iterable[int]) -> None:
        """Raise when a written pair's reflectance chunk is missing (it would read as NaN),
        corrupt or sealed elsewhere (another pair's, or another store's)."""
        reflectance = self._array("reflectance")
        checker = ChunkChecker(self.path, seal=self._seal)
        chosen = np.asarray(list(pairs), np.int64)
        for pair, sealed in zip(chosen.tolist(), self._seals(chosen).tolist(), strict=True):
            coords = (pair, 0, 0, 0)
            found = checker.check(reflectance, coords, sealed)
            if found:
                problem = ChunkProblem(
                    self._pair_name(pair), chunk_key(reflectance, coords), *found
                )
                raise DamagedDataError(
                    f"{self.path}: damaged store: {problem}", remedy=Remedy.reprocess_pairs
                )

    def _seals(self, pairs: np.ndarray) -> np.ndarray:
        """The seals of the reflectance chunks of ``pairs`` (their written flags); 0 where
        none is recorded, and everywhere when they cannot be read (:meth:`check` names the
        chunk)."""
        if not pairs.size:
            return np.zeros(0, np.uint64)
        try:
            return np.asarray(self._array("written").get_orthogonal_selection(pairs), np.uint64)
        except (ValueError, RuntimeError):
            return np.zeros(pairs.size, np.uint64)

    def _decoded(self, pairs: int | slice) -> np.ndarray:
        """Reflectance of ``pairs``; a chunk that cannot be decoded is a damaged store."""
        try:
            return np.asarray(self._array("reflectance")[pairs])
        except (ValueError, RuntimeError) as error:  # checksum and decompression errors
            where = f"pair {pairs}: " if isinstance(pairs, int) else ""
            raise DamagedDataError(
                f"{self.path}: damaged store: {where}a reflectance chunk cannot be decoded "
                f"({' '.join(str(error).split())[:120]}); process the capture again"
            ) from None

    def _require_writable(self) -> None:
        if not self.writable:
            raise InputError(f"{self.path}: the store was opened read-only and cannot be written")

    def _require_complete(self, allow_incomplete: bool, action: str) -> None:
        if not allow_incomplete and not self.complete:
            pending = self.pending_pairs()
            raise InputError(
                f"{self.path}: cannot {action} an incomplete BTF store ({len(pending)} of "
                f"{self.n_pairs} pairs pending, first {pending[:5]})",
                remedy=Remedy.finish_processing,
            )

    def _all_written(self) -> bool:
        """Whether every flag is set, reading only flags not known to be set and stopping at
        the first unset one (cheap for a writer that goes in order, correct with several)."""
        written = self._array("written")
        for pair in np.flatnonzero(~self._known_written):
            if not written[int(pair)]:
                return False
            self._known_written[pair] = True
        return True

    def _fresh_attrs(self) -> Mapping[str, Any]:
        """The group's attributes re-read from disk (another writer may have changed them)."""
        return open_local_group(self.path, mode="r", zarr_format=3).attrs

    def _set_complete(self, value: bool) -> None:
        self._group.attrs["complete"] = bool(value)

    def _drop_compressed(self) -> None:
        if COMPRESSED_GROUP in self._group:
            del self._group[COMPRESSED_GROUP]


def _sealed_settings(
    attrs: Mapping[str, Any],
    light_dirs: np.ndarray,
    view_dirs: np.ndarray,
    wavelengths_nm: np.ndarray,
) -> dict[str, object]:
    """What defines a store's content, sealed at creation: its settings (``_SEALED_ATTRS``),
    directions and bands."""
    return {
        **{name: attrs.get(name) for name in _SEALED_ATTRS},
        "values of light_dirs": np.asarray(light_dirs, np.float64),
        "values of view_dirs": np.asarray(view_dirs, np.float64),
        "values of wavelengths": np.asarray(wavelengths_nm, np.float64),
    }


def _array_in(group: zarr.Group, name: str, path: Path) -> zarr.Array[Any]:
    """The array ``name`` of ``group``; a group there is a damaged store."""
    array = group[name]
    if not isinstance(array, zarr.Array):
        raise DamagedDataError(f"{path}: damaged store: {array.path} is a group, not an array")
    return array


def _compressed_chunks(values: np.ndarray) -> tuple[int, ...]:
    """Chunks of about 16 MiB along the first axis (whole array when small)."""
    if values.ndim == 0:
        return ()
    row = max(1, int(np.prod(values.shape[1:], dtype=np.int64)) * values.dtype.itemsize)
    rows = int(np.clip((16 << 20) // row, 1, max(1, values.shape[0])))
    return (rows, *values.shape[1:])


def write_btf(
    path: str | Path,
    reflectance: np.ndarray,
    grid: WavelengthGrid,
    *,
    light_dirs: np.ndarray,
    view_dirs: np.ndarray,
    material: str,
    source_capture: str | Path | None = None,
    calibration: Mapping[str, Any] | None = None,
) -> BTFStore:
    """Create a store and write a whole ``(n_pairs, H, W, K)`` BTF into it, pair by pair."""
    values = np.asarray(reflectance)
    if values.ndim != 4:
        raise InputError(f"reflectance: expected (n_pairs, H, W, K), got shape {values.shape}")
    if values.shape[3] != getattr(grid, "size", None):
        raise InputError(
            f"reflectance: its last axis ({values.shape[3]}) does not match the grid "
            f"({grid.describe() if isinstance(grid, WavelengthGrid) else grid!r})"
        )
    if values.shape[0] != np.asarray(light_dirs).shape[0]:
        raise InputError(
            f"reflectance: {values.shape[0]} pairs, but {np.asarray(light_dirs).shape[0]} "
            "light directions"
        )
    store = BTFStore.create(
        path,
        light_dirs=light_dirs,
        view_dirs=view_dirs,
        texels=(values.shape[1], values.shape[2]),
        grid=grid,
        material=material,
        source_capture=source_capture,
        calibration=calibration,
    )
    for pair in range(values.shape[0]):
        store.write_pair(pair, values[pair], grid=grid)
    return store
