"""Fixtures shared by the tests and by the docstring examples of twin, recon and hwbridge."""

import importlib
import os
import shutil
import subprocess
import uuid
from pathlib import Path

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
"""The variables that size the BLAS and OpenMP thread pools of numpy, scipy and their kin."""

MALLOC_SETTINGS = {
    "MALLOC_MMAP_THRESHOLD_": str(32 * 2**20),
    "MALLOC_TRIM_THRESHOLD_": str(16 * 2**30),
    "MALLOC_TOP_PAD_": str(512 * 2**20),
}
"""glibc's allocator kept from handing freed memory back to the system: arrays up to 32 MiB
from the heap (not each from its own ``mmap``), the heap not trimmed, grown 512 MiB at a time."""


def pytest_configure(config: pytest.Config) -> None:
    """Settings for the processes the suite starts (its workers, the commands and notebook
    kernels of its tests), then the workers' thread pools (:func:`_share_the_cores`)."""
    _keep_freed_memory()
    _share_the_cores()


FILE_SECONDS_KEY = "spectwin/file_seconds"
"""pytest's cache entry: each test file's seconds (setup, call, teardown) in the last run."""


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The longest test files first, each file's tests together and in their order: spread over
    the workers file by file in this order (``make test``), the long files start early and the
    short ones fill in at the end, so that the workers finish together. The lengths are those of
    the last run (pytest's cache); without them, the files that render (``render`` mark) first.
    """
    cache = getattr(config, "cache", None)  # None with -p no:cacheprovider
    seconds: dict[str, float] = cache.get(FILE_SECONDS_KEY, {}) if cache else {}
    rendering = {item.path for item in items if item.get_closest_marker("render")}

    def longest_first(item: pytest.Item) -> tuple[float, bool]:
        return -seconds.get(item.nodeid.partition("::")[0], 0.0), item.path not in rendering

    items.sort(key=longest_first)


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    """Each test file's seconds, for the next run's order (the controlling process sees the
    reports of every worker)."""
    file = report.nodeid.partition("::")[0]
    _FILE_SECONDS[file] = _FILE_SECONDS.get(file, 0.0) + report.duration


_FILE_SECONDS: dict[str, float] = {}


def pytest_sessionfinish(session: pytest.Session) -> None:
    """The seconds of the files run, kept for the next run with those of the others."""
    cache = getattr(session.config, "cache", None)
    if cache is None or hasattr(session.config, "workerinput") or not _FILE_SECONDS:
        return
    known: dict[str, float] = cache.get(FILE_SECONDS_KEY, {})
    cache.set(FILE_SECONDS_KEY, known | {file: round(s, 2) for file, s in _FILE_SECONDS.items()})


def pytest_sessionstart(session: pytest.Session) -> None:
    """The old sessions' temporary folders removed while this session runs
    (:func:`_remove_old_temporary_folders`)."""
    _remove_old_temporary_folders(session.config)


def _remove_old_temporary_folders(config: pytest.Config) -> None:
    """Start removing the numbered temporary folders of sessions older than those pytest keeps
    (``tmp_path_retention_count``), in a background ``rm``, from the controlling process only.

    pytest removes them itself when the session ends, one file at a time from Python: a whole
    suite's folder holds about 110,000 files (capture stores, one chunk per frame and index
    field), 15 s of ``rm -rf`` on this kind of machine and two to three times that from Python,
    after the last test. Folders another running session holds (its ``.lock``) are left alone.
    """
    if hasattr(config, "workerinput") or config.option.basetemp or shutil.which("rm") is None:
        return
    factory = getattr(config, "_tmp_path_factory", None)
    if factory is None or config.getini("tmp_path_retention_policy") == "none":
        return
    current = factory.getbasetemp()
    if not current.name.rpartition("-")[2].isdigit():
        return
    keep = int(config.getini("tmp_path_retention_count"))
    root, number = current.parent, int(current.name.rpartition("-")[2])
    old = [
        folder
        for folder in root.glob("pytest-*")
        if folder.name.rpartition("-")[2].isdigit()
        and int(folder.name.rpartition("-")[2]) <= number - keep
        and not (folder / ".lock").exists()
    ]
    doomed: list[Path] = list(root.glob(".removing-*"))  # left by a session stopped early
    for folder in old:
        target = root / f".removing-{folder.name}-{uuid.uuid4().hex[:8]}"
        try:
            folder.rename(target)
        except OSError:  # moved or removed by another session starting at the same time
            continue
        doomed.append(target)
    if doomed:
        subprocess.Popen(
            ["rm", "-rf", *map(str, doomed)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )


def _keep_freed_memory() -> None:
    """:data:`MALLOC_SETTINGS` for every process started from here on, unless set already.

    The tests allocate and free arrays of megabytes by the thousand; freed, glibc returns them
    to the system and the next array faults its pages in again. On a virtual machine each such
    page fault is expensive: kept, the suite's page faults fell from 10.2 to 4.2 million and its
    system CPU time from 147 to 103 s (BENCHMARKS.md, "The test suite"). The variables are read
    when a process starts, so this process keeps its own allocator's settings.
    """
    for name, value in MALLOC_SETTINGS.items():
        os.environ.setdefault(name, value)


def _share_the_cores() -> None:
    """Each of several test workers gets its share of the cores for BLAS and OpenMP threads, in
    this process and in the processes its tests start (notebook kernels, commands), unless the
    variables are set already. Each worker's library pools are sized for the whole machine
    otherwise: two workers on two cores ran four BLAS threads, whose spinning cost a sixth of
    the suite's CPU time (BENCHMARKS.md, "The test suite")."""
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
    if workers < 2:
        return
    threads = max(1, (os.cpu_count() or 1) // workers)
    for name in THREAD_VARIABLES:
        os.environ.setdefault(name, str(threads))
    threadpool_limits(int(os.environ["OPENBLAS_NUM_THREADS"]))


NUMPY_DEFAULT_PRINT_OPTIONS = {
    "edgeitems": 3,
    "threshold": 1000,
    "floatmode": "maxprec",
    "precision": 8,
    "suppress": False,
    "linewidth": 75,
    "nanstr": "nan",
    "infstr": "inf",
    "sign": "-",
    "formatter": None,
    "legacy": False,
}
"""numpy's print options as numpy sets them, which the docstring examples are written for."""


@pytest.fixture(autouse=True)
def numpy_default_printing(request):
    """Docstring examples print arrays with numpy's default options, whatever was imported.

    colour-science calls ``np.set_printoptions(legacy="1.13")`` when it is imported; it is
    imported first, so that its change lands before the defaults are set, not in the middle of
    an example. The options in force before the example are restored after it.
    """
    if not isinstance(request.node, pytest.DoctestItem):
        yield
        return
    importlib.import_module("colour")
    with np.printoptions(**NUMPY_DEFAULT_PRINT_OPTIONS):
        yield
