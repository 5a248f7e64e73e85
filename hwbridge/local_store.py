"""Zarr groups on the local file system, with small files read and written where they are asked
for.

Zarr's :class:`~zarr.storage.LocalStore` hands every file read and write to a thread (its event
loop must not block on disk). For the capture and BTF stores most files are a few bytes to a few
kilobytes (an index field of one frame, a progress flag, metadata), and the hand-over costs more
than the read or write. :class:`LocalFileStore` reads and writes files up to
:data:`IN_PLACE_BYTES` in place and leaves larger ones (frames, textures) to threads, where
several proceed at once. With the small arrays' chunks left uncompressed
(:func:`hwbridge.integrity.checksum_only`), a one-element write costs 1.0 ms of CPU time instead
of 1.7, a read 0.7 ms instead of 1.2, and a real capture's step (frame, index, flag) 15-17 ms
instead of 33-35 (``benchmarks/store_io.py``; BENCHMARKS.md, "Capture store I/O").
"""

from __future__ import annotations

import os
import stat
import uuid
from pathlib import Path
from typing import Any, Literal

import zarr
from zarr.abc.store import ByteRequest
from zarr.core.buffer import Buffer, BufferPrototype, default_buffer_prototype
from zarr.storage import LocalStore

IN_PLACE_BYTES = 1 << 16
"""Files up to this size (64 KiB) are read and written without a thread hand-over."""


class LocalFileStore(LocalStore):
    """A :class:`~zarr.storage.LocalStore` that reads and writes small files in place.

    Writes stay atomic (a uniquely named partial file renamed over the target), as Zarr's are.

    Examples
    --------
    >>> import tempfile
    >>> import numpy as np
    >>> folder = Path(tempfile.mkdtemp())
    >>> group = open_local_group(folder / "flags.zarr", mode="w-")
    >>> flags = group.create_array("flags", shape=(4,), chunks=(1,), dtype="bool")
    >>> flags[1:3] = True
    >>> open_local_group(folder / "flags.zarr", mode="r")["flags"][:].tolist()
    [False, True, True, False]
    """

    async def get(
        self,
        key: str,
        prototype: BufferPrototype | None = None,
        byte_range: ByteRequest | None = None,
    ) -> Buffer | None:
        if byte_range is None:
            path = self.root / key
            try:
                found = path.stat()
            except (FileNotFoundError, NotADirectoryError):
                return None
            if found.st_size <= IN_PLACE_BYTES and stat.S_ISREG(found.st_mode):
                if not self._is_open:
                    await self._open()
                buffer = (prototype or default_buffer_prototype()).buffer
                return buffer.from_bytes(path.read_bytes())
        return await super().get(key, prototype, byte_range)

    async def set(self, key: str, value: Buffer) -> None:
        if len(value) > IN_PLACE_BYTES:
            await super().set(key, value)
            return
        if not self._is_open:
            await self._open()
        self._check_writable()
        path = self.root / key
        path.parent.mkdir(parents=True, exist_ok=True)
        partial = path.with_name(f".{path.name}.{uuid.uuid4().hex}.partial")
        try:
            partial.write_bytes(value.as_buffer_like())
            os.replace(partial, path)
        except BaseException:
            partial.unlink(missing_ok=True)
            raise


def open_local_group(
    path: str | Path, *, mode: Literal["r", "r+", "w-"], **options: Any
) -> zarr.Group:
    """The Zarr group at ``path`` on a :class:`LocalFileStore` (``mode`` and ``options`` as
    :func:`zarr.open_group` takes them)."""
    store = LocalFileStore(Path(path), read_only=mode == "r")
    return zarr.open_group(store=store, mode=mode, **options)
