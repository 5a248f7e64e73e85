"""One writer per store: an advisory lock file inside the store folder.

A writer (a capture and its resumption, the processing and the compression writing a BTF
store) holds ``<store>/.writer.lock`` for its whole run: an exclusive
``fcntl.flock`` on the file, which records the owner (PID, host, start time, command line). A
second writer is refused with :class:`~hwbridge.errors.StoreBusy`, whose one-line message names
the owner. The workers of a distributed capture or processing write their chunks inside the lock
of the process that coordinates them and take none themselves.

A store that does not exist yet cannot hold a file, so its creator first reserves the name with
the same kind of lock in the file ``.<name>.writer.lock`` beside it (:meth:`StoreLock.reserve`),
creates the store and then moves that very file into the store (:meth:`StoreLock.move_into`: a
hard link, refused if the store already has a lock file, so the lock is never free in between).
Two creators of one store, or a creator and a resume, never run at once.

A writer holds the same lock on the store folder itself, so that deleting the lock file (by hand,
or by a tool that tidies hidden files) does not let a second writer in: the folder stays locked
while its writer runs, and the refusal says that its lock file was deleted.

Stale locks: the kernel drops a ``flock`` when the process holding it ends, however it ends, so a
writer killed with SIGKILL leaves its lock file behind (still naming it) but not held. The next
writer locks the file, notes the old owner (:attr:`StoreLock.stale_owner`: it ended without
releasing) and writes itself in. A held lock whose recorded process is gone on this host was
inherited by a process that it started; the message says so. A clean release deletes the file
(after checking, under the lock, that it is still the file the writer locked), so a complete
store carries no lock file.

The lock is advisory: readers do not take it, and a program that ignores it is not stopped.
``flock`` is reliable on local filesystems and on NFSv4, where Linux maps it to NFS locks.
"""

from __future__ import annotations

import contextlib
import datetime
import errno
import fcntl
import json
import os
import shlex
import socket
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from hwbridge.errors import InputError, Remedy, StoreBusy

__all__ = [
    "LOCK_NAME",
    "LockOwner",
    "StoreLock",
    "lock_owner",
    "require_new_store",
    "require_no_writer",
]

LOCK_NAME = ".writer.lock"
"""The lock file inside a store folder."""

_ATTEMPTS = 5  # a lock file replaced under us (released and deleted by its owner): try again
_BUSY_TRIES = 3  # a lock found held is tried again after _BUSY_WAIT_S (another process's probe)
_BUSY_WAIT_S = 0.02


@dataclass(frozen=True)
class LockOwner:
    """Who holds (or held) a store's lock, as its lock file records it."""

    pid: int
    host: str
    since: str
    command: str = ""

    @classmethod
    def current(cls) -> LockOwner:
        now = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
        command = shlex.join([Path(sys.argv[0]).name, *sys.argv[1:]]) if sys.argv else ""
        return cls(os.getpid(), socket.gethostname(), now, command[:500])

    @classmethod
    def parse(cls, text: str) -> LockOwner | None:
        try:
            record = json.loads(text)
            return cls(
                int(record["pid"]),
                str(record["host"]),
                str(record["since"]),
                str(record.get("command", "")),
            )
        except (ValueError, KeyError, TypeError):
            return None

    def dumps(self) -> str:
        return json.dumps(
            {"pid": self.pid, "host": self.host, "since": self.since, "command": self.command}
        )

    @property
    def gone(self) -> bool:
        """Whether the recorded process no longer runs (known only on its own host)."""
        if self.host != socket.gethostname():
            return False
        try:
            os.kill(self.pid, 0)
        except ProcessLookupError:
            return True
        except PermissionError:  # another user's process: it runs
            return False
        return False

    def describe(self) -> str:
        """``PID 4242 on host lab1 since 2026-05-02T10:11:12+02:00``."""
        text = f"PID {self.pid} on host {self.host} since {self.since}"
        if self.gone:
            text += " (that process has ended; a process it started still holds the lock)"
        return text


def _reservation(path: Path) -> Path:
    """The lock file that reserves the name of a store being created."""
    return path.with_name(f".{path.name}{LOCK_NAME}")


def _read_owner(lock_file: Path) -> LockOwner | None:
    try:
        return LockOwner.parse(lock_file.read_text())
    except OSError:
        return None


def _busy(store: Path, lock_file: Path, creating: bool) -> StoreBusy:
    owner = _read_owner(lock_file)
    for _ in range(20):  # the owner may be between taking the lock and writing its name
        if owner is not None:
            break
        time.sleep(0.01)
        owner = _read_owner(lock_file)
    if owner is not None:
        who = owner.describe()
    elif lock_file.exists():
        who = "another process (it has not written its name yet)"
    else:
        who = f"another process (its lock file {lock_file.name} was deleted)"
    doing = "created" if creating else "written"
    return StoreBusy(
        f"{store} is being {doing} by {who}; one writer at a time: wait for it to end, or stop it"
    )


def _same_file(fd: int, lock_file: Path) -> bool:
    try:
        on_disk = os.stat(lock_file)
    except FileNotFoundError:
        return False
    held = os.fstat(fd)
    return (on_disk.st_dev, on_disk.st_ino) == (held.st_dev, held.st_ino)


def _take(fd: int, unsupported: tuple[int, ...]) -> bool | None:
    """Take the exclusive flock of the open ``fd``: ``True``; ``False`` when another open file
    holds it; ``None`` where the filesystem cannot lock it (an errno in ``unsupported``). The
    descriptor is closed unless the lock was taken."""
    try:
        _flock(fd)
    except BlockingIOError:
        os.close(fd)
        return False
    except OSError as error:
        os.close(fd)
        if error.errno in unsupported:
            return None
        raise
    return True


def _try_lock(lock_file: Path) -> int | None:
    """An open descriptor of ``lock_file`` (created if missing) holding its exclusive flock, or
    ``None`` when another open file holds it."""
    for _ in range(_ATTEMPTS):
        try:
            fd = os.open(lock_file, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as error:
            raise InputError(
                f"{lock_file}: cannot open the writer lock of the store ({error.strerror})"
            ) from None
        taken = _take(fd, (errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS))
        if taken is None:
            raise InputError(
                f"{lock_file.parent}: the filesystem does not support file locks (flock), so "
                "nothing can make sure that only one process writes the store; use a local or "
                "NFSv4 folder"
            )
        if not taken:
            return None
        if _same_file(fd, lock_file):
            return fd
        os.close(fd)  # its owner released and deleted it between our open and flock
    return None


_NO_FOLDER_LOCKS = (errno.EBADF, errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS)
"""A folder that cannot be locked (NFS turns flock into byte-range locks, which need a file open
for writing): the lock file alone guards its store."""

_UNLOCKED_FOLDER = -1
"""What :func:`_lock_folder` returns for a folder that cannot be locked."""


def _lock_folder(store: Path) -> int | None:
    """An open descriptor of the store folder holding its exclusive flock, ``None`` when another
    open file holds it, :data:`_UNLOCKED_FOLDER` where the filesystem cannot lock folders."""
    fd = os.open(store, os.O_RDONLY | os.O_DIRECTORY)
    taken = _take(fd, _NO_FOLDER_LOCKS)
    if taken is None:
        return _UNLOCKED_FOLDER
    return fd if taken else None


def _unlock_folder(fd: int | None) -> None:
    """Drop the folder's lock taken by :func:`_lock_folder` (if any)."""
    if fd is not None and fd != _UNLOCKED_FOLDER:
        os.close(fd)


def _held_by_other(lock_file: Path) -> bool:
    """Whether another open file holds the flock of ``lock_file`` (or of a store folder),
    without creating the file."""
    folder = lock_file.is_dir()
    try:
        fd = os.open(lock_file, os.O_RDONLY if folder else os.O_RDWR)
    except FileNotFoundError:
        return False
    try:
        _flock(fd)
    except BlockingIOError:
        return True
    except OSError as error:
        if folder and error.errno in _NO_FOLDER_LOCKS:
            return False  # the lock file alone guards the store
        raise
    finally:
        os.close(fd)  # closing drops a flock we took
    return False


def _flock(fd: int) -> None:
    """Take the exclusive flock of ``fd`` without waiting for its holder, but trying again
    briefly: a lock held only for an instant is another process testing it (:func:`lock_owner`),
    one held longer a writer (``BlockingIOError``)."""
    for attempt in range(_BUSY_TRIES):
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return
        except BlockingIOError:
            if attempt == _BUSY_TRIES - 1:
                raise
            time.sleep(_BUSY_WAIT_S)


class StoreLock:
    """The writer lock of one store, held from :meth:`acquire` (or :meth:`reserve`) until
    :meth:`release`; a context manager that releases on exit.

    Attributes
    ----------
    store
        The store folder.
    owner
        This writer, as written into the lock file.
    stale_owner
        The writer recorded in the lock file when this one took it: a writer that ended without
        releasing (killed), or ``None``.
    """

    def __init__(self, store: Path, lock_file: Path, fd: int):
        self.store = store
        self._file = lock_file
        self._fd: int | None = fd
        self._folder_fd: int | None = None  # the store folder's flock, once the store exists
        self.stale_owner = _read_owner(lock_file)
        self.owner = LockOwner.current()
        os.ftruncate(fd, 0)
        os.pwrite(fd, (self.owner.dumps() + "\n").encode(), 0)
        os.fsync(fd)

    # -- taking ---------------------------------------------------------------------------------

    @classmethod
    def acquire(cls, store: str | Path) -> StoreLock:
        """Lock the existing store folder ``store``.

        Raises
        ------
        StoreBusy
            Another writer holds the store's lock, or is still creating the store.
        InputError
            ``store`` is not a folder.
        """
        store = Path(store)
        reservation = _reservation(store)
        if _held_by_other(reservation):  # its creator has not moved its lock in yet
            raise _busy(store, reservation, creating=True)
        lock = cls._inside(store)
        _remove_stale(reservation)
        return lock

    @classmethod
    def _inside(cls, store: Path) -> StoreLock:
        """Lock the file inside the existing store folder ``store``."""
        if not store.is_dir():
            what = "is a file" if store.exists() else "does not exist"
            raise InputError(f"{store} {what}: expected a store folder")
        lock_file = store / LOCK_NAME
        folder = _lock_folder(store)
        fd = None if folder is None else _try_lock(lock_file)
        if fd is None:
            _unlock_folder(folder)
            raise _busy(store, lock_file, creating=False)
        lock = cls(store, lock_file, fd)
        lock._folder_fd = folder
        return lock

    @classmethod
    def reserve(cls, store: str | Path) -> StoreLock:
        """Reserve the name of a store about to be created (``store`` must not exist): the lock
        lies beside it until :meth:`move_into` moves it inside.

        Raises
        ------
        StoreBusy
            Another writer is creating or writing ``store``.
        InputError
            ``store`` exists already (to continue a store, :meth:`acquire` its lock).
        """
        store = Path(store)
        if store.exists():
            _refuse_existing(store)
        reservation = _reservation(store)
        reservation.parent.mkdir(parents=True, exist_ok=True)
        fd = _try_lock(reservation)
        if fd is None:
            raise _busy(store, reservation, creating=True)
        lock = cls(store, reservation, fd)
        if store.exists():  # created and released by another writer since the first check
            lock.release()
            _refuse_existing(store)
        return lock

    def move_into(self) -> None:
        """After creating the store of a :meth:`reserve`: move the held lock file inside it.

        The file is hard-linked into the store, which is refused if the store has a lock file
        already (another writer took it meanwhile: :class:`StoreBusy`), then unlinked beside it;
        the flock stays held throughout, the file being the same. The store folder's own lock
        is taken first.
        """
        inside = self.store / LOCK_NAME
        if self._file == inside:
            return
        if self._folder_fd is None:
            self._folder_fd = _lock_folder(self.store)
            if self._folder_fd is None:
                raise _busy(self.store, inside, creating=False)
        try:
            os.link(self._file, inside)
        except FileExistsError:
            fd = _try_lock(inside)  # a stale file is taken over, a held one refused
            if fd is None:
                raise _busy(self.store, inside, creating=False) from None
            self._adopt(StoreLock(self.store, inside, fd))
            return
        os.unlink(self._file)
        self._file = inside

    def _adopt(self, other: StoreLock) -> None:
        """Give up the reservation for ``other``, a lock of the store's lock file (the folder's
        lock stays held)."""
        folder, self._folder_fd = self._folder_fd, None
        self.release()
        self._file, self._fd, self._folder_fd = other._file, other._fd, folder
        self.stale_owner = other.stale_owner or self.stale_owner
        other._fd = None

    # -- releasing ------------------------------------------------------------------------------

    @property
    def held(self) -> bool:
        return self._fd is not None

    def release(self) -> None:
        """Delete the lock file (still the one locked) and drop the lock; idempotent."""
        if self._fd is None:
            return
        fd, self._fd = self._fd, None
        folder, self._folder_fd = self._folder_fd, None
        try:
            if _same_file(fd, self._file):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(self._file)
        finally:
            os.close(fd)
            _unlock_folder(folder)

    def __enter__(self) -> StoreLock:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.release()

    def __repr__(self) -> str:
        state = "held" if self.held else "released"
        return f"StoreLock({str(self.store)!r}, {state})"


def require_new_store(store: str | Path) -> None:
    """Refuse ``store`` if it exists: :class:`StoreBusy` naming its writer when one holds it,
    else :class:`~hwbridge.errors.InputError`."""
    store = Path(store)
    if store.exists():
        _refuse_existing(store)


def require_no_writer(store: str | Path) -> None:
    """Refuse ``store`` with :class:`StoreBusy` naming its writer while one holds it (checked
    before anything else about the store: a store being written is naturally incomplete). A
    path that is not a folder is left to the checks that say what it should be."""
    store = Path(store)
    if store.exists() and not store.is_dir():
        return
    held = _held(store)
    if held is not None:
        raise _busy(store, held, creating=held != store / LOCK_NAME)


def _held(store: Path) -> Path | None:
    """The lock file of the writer that holds ``store`` (its folder or its lock file) or
    reserves its name, ``None`` if none does."""
    if _held_by_other(store) or _held_by_other(store / LOCK_NAME):
        return store / LOCK_NAME
    reservation = _reservation(store)
    return reservation if _held_by_other(reservation) else None


def _refuse_existing(store: Path) -> None:
    lock_file = store / LOCK_NAME
    if _held_by_other(store) or _held_by_other(lock_file):
        raise _busy(store, lock_file, creating=False)
    raise InputError(
        f"{store} exists: expected a new store (nothing was overwritten)",
        remedy=Remedy.resume_or_rename,
    )


def _remove_stale(reservation: Path) -> None:
    """Delete the reservation file a killed creator left beside its store (if no one holds it)."""
    fd = _try_lock(reservation) if reservation.exists() else None
    if fd is not None:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(reservation)
        os.close(fd)


def lock_owner(store: str | Path) -> LockOwner | None:
    """The writer holding ``store``'s lock (or reserving its name) now, ``None`` if none."""
    held = _held(Path(store))
    return None if held is None else _read_owner(held) or LockOwner(-1, "?", "?")
