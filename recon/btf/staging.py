"""A new store built under a temporary name beside its target and renamed into place when done.

An import reads a whole BTF from elsewhere into a new store. Built in place, a failure on the way
(a bad slice, a full disk, Ctrl-C) would leave a half store under the name the user gave, which
can be neither resumed (an import has nothing to resume from) nor overwritten (stores never are).
:func:`staged` builds it in a hidden folder beside the target, in the same file system, and
renames it to the target only once the build has finished: the target then either does not exist
or holds the complete store.
"""

from __future__ import annotations

import os
import secrets
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from recon.errors import InputError, Remedy

__all__ = ["staged"]


@contextmanager
def staged(path: str | Path) -> Iterator[Path]:
    """A temporary path beside ``path`` to build a new store in: renamed to ``path`` when the
    block ends, removed when the block raises (an interrupt included).

    Parameters
    ----------
    path
        Where the store is to be; must not exist.

    Yields
    ------
    pathlib.Path
        The temporary path (``.<name>.<random>.partial`` in the same folder), not yet created.

    Raises
    ------
    InputError
        ``path`` exists, before the build or (made by another writer meanwhile) after it.
    """
    path = Path(path)
    _require_new(path)
    temporary = path.with_name(f".{path.name}.{secrets.token_hex(6)}.partial")
    try:
        yield temporary
        _require_new(path)
        os.rename(temporary, path)
    except BaseException:
        shutil.rmtree(temporary, ignore_errors=True)
        raise


def _require_new(path: Path) -> None:
    if path.exists() or path.is_symlink():
        raise InputError(
            f"{path} exists: expected a new store (nothing was overwritten)",
            remedy=Remedy.resume_or_rename,
        )
