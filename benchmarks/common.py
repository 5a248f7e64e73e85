"""Helpers shared by the benchmark scripts."""

from __future__ import annotations

import os
import platform
import resource
import time
from collections.abc import Callable
from typing import TypeVar

Result = TypeVar("Result")


def machine_description() -> str:
    """CPU architecture, core count and Python version of this machine."""
    return f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"


def peak_rss_mib() -> int:
    """Peak resident memory of this process so far, MiB."""
    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)


def timed(function: Callable[[], Result]) -> tuple[Result, float]:
    """``function()``'s result and its wall-clock time in seconds (to 0.01 s)."""
    started = time.perf_counter()
    result = function()
    return result, round(time.perf_counter() - started, 2)
