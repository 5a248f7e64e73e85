"""Helpers shared by the benchmark scripts."""

from __future__ import annotations

import argparse
import importlib.util
import os
import platform
import resource
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

Result = TypeVar("Result")


def load_script(name: str) -> Any:
    """A module of ``scripts/`` (not a package: loaded from its file)."""
    path = Path(__file__).parents[1] / "scripts" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise ImportError(f"no script {path}")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


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


def cpu_s() -> float:
    """CPU seconds of this process so far (user and system, every thread)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


class StageTimer:
    """Wall and CPU seconds spent in each stage of a capture: ``stages`` maps a stage's name to
    the ``(owner, function name)`` places whose calls count for it (the outermost timed call
    counts; a place the code does not have is skipped)."""

    def __init__(self, stages: dict[str, list[tuple[Any, str]]]) -> None:
        self.stages = stages
        self.wall: defaultdict[str, float] = defaultdict(float)
        self.cpu: defaultdict[str, float] = defaultdict(float)
        self._inside = False

    def wrap(self, stage: str, function):
        def timed_call(*args, **kwargs):
            if self._inside:
                return function(*args, **kwargs)
            self._inside = True
            wall, cpu = time.perf_counter(), cpu_s()
            try:
                return function(*args, **kwargs)
            finally:
                self.wall[stage] += time.perf_counter() - wall
                self.cpu[stage] += cpu_s() - cpu
                self._inside = False

        return timed_call

    @contextmanager
    def installed(self) -> Iterator[StageTimer]:
        saved = []
        for stage, places in self.stages.items():
            for owner, name in places:
                if owner is not None and hasattr(owner, name):
                    saved.append((owner, name, getattr(owner, name)))
                    setattr(owner, name, self.wrap(stage, getattr(owner, name)))
        try:
            yield self
        finally:
            for owner, name, original in saved:
                setattr(owner, name, original)


def timed_stages(
    stages: dict[str, list[tuple[Any, str]]], work: Callable[[], object]
) -> dict[str, dict[str, float]]:
    """Run ``work``; its wall and CPU seconds in total and per stage (:class:`StageTimer`),
    ``other`` the rest."""
    timer = StageTimer(stages)
    with timer.installed():
        wall, cpu = time.perf_counter(), cpu_s()
        work()
        wall, cpu = time.perf_counter() - wall, cpu_s() - cpu
    result = {stage: {"wall_s": timer.wall[stage], "cpu_s": timer.cpu[stage]} for stage in stages}
    result["other"] = {
        "wall_s": wall - sum(timer.wall.values()),
        "cpu_s": cpu - sum(timer.cpu.values()),
    }
    result["total"] = {"wall_s": wall, "cpu_s": cpu}
    return result


def per_unit(stages: dict[str, dict[str, float]], units: float) -> dict[str, dict[str, float]]:
    """:func:`timed_stages`' seconds per unit (pair, stage position), to the millisecond."""
    return {
        stage: {key: round(value / units, 3) for key, value in times.items()}
        for stage, times in stages.items()
    }
