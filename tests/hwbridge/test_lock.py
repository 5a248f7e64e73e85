"""The writer lock of a store (hwbridge.lock): one writer at a time, the owner named, stale
locks of killed writers taken over, the lock moved into a store created under it."""

import json
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from hwbridge.errors import InputError, Remedy, StoreBusy
from hwbridge.lock import (
    LOCK_NAME,
    LockOwner,
    StoreLock,
    lock_owner,
    require_new_store,
    require_no_writer,
)

ROOT = Path(__file__).resolve().parents[2]
HOLDER = """
import sys, time
from hwbridge.lock import StoreLock
lock = StoreLock.{how}(sys.argv[1])
print("locked", flush=True)
time.sleep(120)
"""
# A writer that takes the lock file of an existing store by flock alone (not asking whether the
# store is still being created): the race that StoreLock.move_into must survive.
RAW_HOLDER = """
import fcntl, json, os, socket, sys, time
fd = os.open(os.path.join(sys.argv[1], ".writer.lock"), os.O_RDWR | os.O_CREAT)
fcntl.flock(fd, fcntl.LOCK_EX)
record = {"pid": os.getpid(), "host": socket.gethostname(), "since": "now"}
os.write(fd, json.dumps(record).encode())
print("locked", flush=True)
time.sleep(120)
"""


def _holder(path: Path, how: str = "acquire") -> subprocess.Popen:
    """Another process that takes the lock of ``path`` and keeps it."""
    script = RAW_HOLDER if how == "raw" else HOLDER.format(how=how)
    process = subprocess.Popen(
        [sys.executable, "-c", script, str(path)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert process.stdout.readline().strip() == "locked"
    return process


def _kill(process: subprocess.Popen) -> None:
    process.send_signal(signal.SIGKILL)
    process.wait()


def test_a_lock_records_its_owner_and_a_second_writer_is_refused_naming_it(tmp_path):
    store = tmp_path / "a.capture.zarr"
    store.mkdir()
    with StoreLock.acquire(store) as lock:
        record = json.loads((store / LOCK_NAME).read_text())
        assert record["pid"] == os.getpid() and record["host"] == socket.gethostname()
        assert record["since"] == lock.owner.since and lock.stale_owner is None
        with pytest.raises(StoreBusy, match=rf"is being written by PID {os.getpid()} on host "):
            StoreLock.acquire(store)  # another open file, even in this process
        assert lock_owner(store) == lock.owner
    assert not (store / LOCK_NAME).exists() and lock_owner(store) is None
    StoreLock.acquire(store).release()  # free again


def test_another_process_holding_the_lock_is_named_and_its_lock_is_taken_over_once_killed(
    tmp_path,
):
    store = tmp_path / "b.capture.zarr"
    store.mkdir()
    holder = _holder(store)
    try:
        with pytest.raises(StoreBusy) as refused:
            StoreLock.acquire(store)
        message = str(refused.value)
        assert f"PID {holder.pid} on host {socket.gethostname()} since " in message
        assert "\n" not in message
    finally:
        _kill(holder)
    # The killed writer's file is still there, naming it, but the kernel dropped its lock.
    assert json.loads((store / LOCK_NAME).read_text())["pid"] == holder.pid
    assert LockOwner.parse((store / LOCK_NAME).read_text()).gone
    with StoreLock.acquire(store) as lock:
        assert lock.stale_owner is not None and lock.stale_owner.pid == holder.pid
        assert json.loads((store / LOCK_NAME).read_text())["pid"] == os.getpid()


def test_a_new_store_is_reserved_beside_its_name_then_locked_inside(tmp_path):
    store = tmp_path / "c.capture.zarr"
    reservation = tmp_path / f".c.capture.zarr{LOCK_NAME}"
    lock = StoreLock.reserve(store)
    assert reservation.exists() and not store.exists()
    with pytest.raises(StoreBusy, match="is being created by PID"):
        StoreLock.reserve(store)
    with pytest.raises(StoreBusy, match="is being created by PID"):
        StoreLock.acquire(store)  # a resume while it is created
    store.mkdir()  # the creator makes the store ...
    with pytest.raises(StoreBusy, match="is being created by PID"):
        StoreLock.acquire(store)  # ... whose lock is still beside it
    lock.move_into()
    assert not reservation.exists() and (store / LOCK_NAME).exists()
    with pytest.raises(StoreBusy, match="is being written by PID"):
        StoreLock.acquire(store)
    with pytest.raises(StoreBusy, match="is being written by PID"):
        require_new_store(store)
    lock.release()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.capture.zarr"]
    assert list(store.iterdir()) == []
    with pytest.raises(InputError, match="exists: expected a new store") as refused:
        StoreLock.reserve(store)
    assert refused.value.remedy is Remedy.resume_or_rename


def test_a_killed_creator_leaves_a_reservation_that_the_next_creator_takes_over(tmp_path):
    store = tmp_path / "d.capture.zarr"
    holder = _holder(store, how="reserve")
    with pytest.raises(StoreBusy, match=f"is being created by PID {holder.pid}"):
        StoreLock.reserve(store)
    _kill(holder)
    with StoreLock.reserve(store) as lock:
        assert lock.stale_owner.pid == holder.pid
        store.mkdir()
        lock.move_into()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.capture.zarr"]


def test_moving_into_a_store_that_another_writer_locked_meanwhile_is_refused(tmp_path):
    store = tmp_path / "e.capture.zarr"
    lock = StoreLock.reserve(store)
    store.mkdir()
    other = _holder(store, how="raw")  # took the store between its creation and the move
    try:
        with pytest.raises(StoreBusy, match=f"PID {other.pid}"):
            lock.move_into()
    finally:
        lock.release()
        _kill(other)
    with StoreLock.reserve(tmp_path / "f.capture.zarr") as stale_inside:
        (tmp_path / "f.capture.zarr").mkdir()
        (tmp_path / "f.capture.zarr" / LOCK_NAME).write_text(
            LockOwner(999999, "elsewhere", "2020-01-01T00:00:00+00:00").dumps()
        )
        stale_inside.move_into()  # a file no one holds: taken over
        assert stale_inside.stale_owner.host == "elsewhere"
    assert not (tmp_path / "f.capture.zarr" / LOCK_NAME).exists()


def test_a_held_lock_whose_recorded_process_has_ended_says_a_child_holds_it(tmp_path):
    ended = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    owner = LockOwner(int(ended.stdout), socket.gethostname(), "2026-01-01T00:00:00+00:00")
    assert owner.gone and "a process it started still holds the lock" in owner.describe()
    assert not LockOwner(os.getpid(), socket.gethostname(), "now").gone
    assert not LockOwner(1, "another-host", "now").gone  # unknowable from here


def test_locking_a_file_or_a_missing_folder_is_refused(tmp_path):
    plain = tmp_path / "plain.txt"
    plain.write_text("not a store")
    with pytest.raises(InputError, match="is a file"):
        StoreLock.acquire(plain)
    with pytest.raises(InputError, match="does not exist"):
        StoreLock.acquire(tmp_path / "nosuch.zarr")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plain.txt"]


def test_a_deleted_lock_file_keeps_the_second_writer_out(tmp_path):
    """The writer holds the store folder's lock too: deleting its lock file lets no one in."""
    store = tmp_path / "g.zarr"
    store.mkdir()
    lock = StoreLock.acquire(store)
    (store / LOCK_NAME).unlink()  # someone deleted it by hand ...
    with pytest.raises(StoreBusy, match=r"its lock file \.writer\.lock was deleted"):
        StoreLock.acquire(store)  # ... and the next writer is still refused
    with pytest.raises(StoreBusy):
        require_no_writer(store)
    assert lock_owner(store) is not None
    lock.release()
    successor = StoreLock.acquire(store)
    successor.release()
    assert not (store / LOCK_NAME).exists() and lock_owner(store) is None
