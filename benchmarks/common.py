"""Helpers shared by the benchmark scripts."""

from __future__ import annotations

import argparse
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


def add_dome_size_arguments(parser: argparse.ArgumentParser) -> None:
    """The reduced dome capture's size as options, 2 x 24 x 3 at 64 texels by default, at the
    capture's own samples per pixel unless ``--spp`` is given
    (``twin.dome.programs.DomeCaptureSize``)."""
    for name, default in (
        ("--stage-positions", 2),
        ("--leds", 24),
        ("--rgb-cameras", 3),
        ("--texels", 64),
        ("--spp", None),
    ):
        parser.add_argument(name, type=int, default=default)


def dome_size_settings(arguments: argparse.Namespace) -> dict[str, int]:
    """The options of :func:`add_dome_size_arguments` that are set, by ``DomeCaptureSize``'s
    field names."""
    names = ("stage_positions", "leds", "rgb_cameras", "texels", "spp")
    return {
        name: getattr(arguments, name) for name in names if getattr(arguments, name) is not None
    }
