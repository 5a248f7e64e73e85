"""Mutation check of the core numerics: does a plausible bug make a test fail?

Each mutation (a sign flip, a factor of 2, a band shifted by one, swapped inputs) replaces one
core function. For each, pytest runs the test files named for it in a subprocess, with this
module loaded as a plugin (``-p benchmarks.mutation_check``) and ``SPECTWIN_MUTATION`` naming
the mutation: the plugin patches the function when it is imported, before any test module. The
first failing test is the one that caught the mutation. Prints JSON::

    python benchmarks/mutation_check.py [--control] [NAME ...]

``--control`` also runs all the named test files once without a mutation (they must pass, so
that a failure under a mutation is the mutation's doing).
"""

from __future__ import annotations

import functools
import importlib
import json
import os
import platform
import re
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Mutation:
    name: str
    target: str  # "module:attribute" or "module:Class.method"
    description: str
    tests: tuple[str, ...]
    wrap: Callable[[Callable], Callable]


def _result(change: Callable) -> Callable[[Callable], Callable]:
    """A mutation that changes the function's result."""

    def wrap(original: Callable) -> Callable:
        @functools.wraps(original)
        def mutated(*args, **kwargs):
            return change(original(*args, **kwargs), args, kwargs)

        return mutated

    return wrap


def _arguments(change: Callable) -> Callable[[Callable], Callable]:
    """A mutation that changes the function's arguments."""

    def wrap(original: Callable) -> Callable:
        @functools.wraps(original)
        def mutated(*args, **kwargs):
            args, kwargs = change(args, kwargs)
            return original(*args, **kwargs)

        return mutated

    return wrap


def _roll_last(values, args, kwargs):
    import numpy as np

    return np.roll(values, 1, axis=-1)


def _reverse_exposures(args, kwargs):
    import numpy as np

    if "exposure_s" in kwargs:
        kwargs = {**kwargs, "exposure_s": np.asarray(kwargs["exposure_s"])[::-1]}
    else:
        args = (args[0], np.asarray(args[1])[::-1], *args[2:])
    return args, kwargs


def _double_merge_time(args, kwargs):
    energies, weights, exposure_s = args
    return (energies, weights, 2 * exposure_s), kwargs


def _add_dark(values, args, kwargs):
    import numpy as np

    frames = np.asarray(kwargs.get("frames", args[0]), dtype=np.float64)
    return 2 * frames - values  # frames + dark instead of frames - dark


def _ignore_exposure_time(args, kwargs):
    self, t0_s = args[0], args[1]
    return (self, t0_s, 1.0), {}


def _flip_dynamic_exponent(values, args, kwargs):
    import numpy as np

    p_dyn = kwargs.get("p_dyn", args[1] if len(args) > 1 else None)
    if not p_dyn:
        return values
    # f_i = (sum V)^(+p) instead of (sum V)^(-p)
    return np.asarray(values) ** -1.0


def _weak_reweighting(original):
    """Eq. 9.8 with the floor of its denominators at 0.4 of the previous peak (not 0.05): the
    reweighting by the previous response is mostly lost."""

    @functools.wraps(original)
    def mutated(count, previous):
        rows = original(count, None)
        if previous is not None:
            rows /= (previous[:-1] + previous[1:] + 0.4 * max(previous.max(), 1e-12))[:, None]
        return rows

    return mutated


def _moves_in_series(original):
    """Robot and rail one after the other: each axis's time from the original with the other
    axis made instantaneous, summed."""

    @functools.wraps(original)
    def mutated(start, end, config):
        instant = {"start_stop_s": 0.0}
        robot = config.robot.model_copy(update={**instant, "joint_speed_deg_per_s": 1e12})
        rail = config.rail.model_copy(update={**instant, "speed_deg_per_s": 1e12})
        return original(start, end, config.model_copy(update={"robot": robot})) + original(
            start, end, config.model_copy(update={"rail": rail})
        )

    return mutated


def _switching_off_by_one(estimate, args, kwargs):
    from dataclasses import replace

    config = args[0]
    switch = config.timing.switch_and_download_s
    return replace(
        estimate,
        per_pair_capture_s=estimate.per_pair_capture_s - switch,
        total_s=estimate.total_s - estimate.pairs * switch,
    )


def _bands_shifted(table, args, kwargs):
    """Every spectrum read one band off (band k holds band k - 1's value), in the decoded table
    and in the PCA factors alike, so that raw and compressed renderings still agree."""
    from dataclasses import replace

    import numpy as np

    from twin.render.plugins.btf_bsdf import BTFTable

    if isinstance(table, BTFTable):
        values = np.roll(table.values, 1, axis=-1)
        return BTFTable(table.light_dirs, table.view_dirs, values, table.grid)
    pca = table.compressed
    per_band = pca.layout == "per_band"
    shifted = replace(
        pca,
        spectral_scores=np.roll(pca.spectral_scores, 1, axis=1),
        spectral_mean=np.roll(pca.spectral_mean, 1, axis=0) if per_band else pca.spectral_mean,
        spectral_components=(
            np.roll(pca.spectral_components, 1, axis=0) if per_band else pca.spectral_components
        ),
    )
    return replace(table, compressed=shifted)


MUTATIONS = (
    Mutation(
        "relative_error x2",
        "recon.metrics:relative_error",
        "Eq. 6.8 error twice too large",
        ("tests/recon/test_metrics.py",),
        _result(lambda values, args, kwargs: 2 * values),
    ),
    Mutation(
        "delta_e94 x0.5",
        "recon.metrics:delta_e94",
        "Delta E94 half of the CIE 1994 value",
        ("tests/recon/test_metrics_spectral.py", "tests/recon/test_metrics.py"),
        _result(lambda values, args, kwargs: 0.5 * values),
    ),
    Mutation(
        "band_integrals off by one band",
        "recon.spectra:band_integrals",
        "each band's integral reported in the next band",
        ("tests/recon/test_spectra.py",),
        _result(_roll_last),
    ),
    Mutation(
        "robertson exposures reversed",
        "recon.radiometric.response_curve:robertson",
        "exposure times paired with the wrong frames",
        ("tests/recon/radiometric/test_response_curve.py",),
        _arguments(_reverse_exposures),
    ),
    Mutation(
        "subtract_dark sign flip",
        "recon.radiometric.dark_frames:subtract_dark",
        "dark frame added instead of subtracted (Eq. 3.2)",
        ("tests/recon/radiometric/test_dark_frames.py",),
        _result(_add_dark),
    ),
    Mutation(
        "drift_factors inverted",
        "recon.calibration.spectral:drift_factors",
        "F_i,long (Eq. 3.6) maps the reference onto the point instead of back",
        ("tests/recon/calibration/test_spectral_calibration.py",),
        _result(lambda values, args, kwargs: 1.0 / values),
    ),
    Mutation(
        "merge_hdr exposure x2",
        "recon.radiometric.hdr:_merge_flat",
        "Eq. 10.3 with every exposure time doubled",
        ("tests/recon/radiometric/test_response_curve.py",),
        _arguments(_double_merge_time),
    ),
    Mutation(
        "dynamic_scale exponent sign",
        "recon.spectralize.solve:dynamic_scale",
        "Eq. 10.2 f_i = (sum V)^(+p_dyn)",
        ("tests/recon/spectralize/test_spectralize.py",),
        _result(_flip_dynamic_exponent),
    ),
    Mutation(
        "sensor electrons x2",
        "twin.sensor.model:Sensor.mean_electrons",
        "twice the photo-electrons per radiant exposure",
        ("tests/twin/sensor/test_sensor.py",),
        _result(lambda values, args, kwargs: 2 * values),
    ),
    Mutation(
        "camchar smoothness floor 0.4",
        "recon.camera_char:_smoothness_rows",
        "Eq. 9.8's reweighting floored at 0.4 of the previous peak instead of 0.05",
        (
            "tests/integration/test_camera_char.py"
            "::test_extended_method_survives_specularity_and_shading_where_basic_fails",
        ),
        _weak_reweighting,
    ),
    Mutation(
        "gonio moves in series",
        "twin.gonio.capture_time:move_seconds",
        "robot and rail move one after the other instead of in parallel (4.1.1)",
        ("tests/twin/rigs/test_rig_geometry.py",),
        _moves_in_series,
    ),
    Mutation(
        "gonio switching for 32 bands",
        "twin.gonio.capture_time:estimate_gonio",
        "filter switching and download counted for 32 of the 33 bands",
        (
            "tests/twin/rigs/test_rig_geometry.py",
            "tests/e2e/test_cli_smoke.py::test_estimate_gonio_reports_a_total_that_is_the_sum_of_its_printed_parts",
        ),
        _result(_switching_off_by_one),
    ),
    Mutation(
        "validate reads spectra one band off",
        "twin.render.plugins.btf_bsdf:store_table",
        "the BTF store read for rendering with every spectrum one band off (raw and PCA alike)",
        ("tests/e2e/test_gonio_pipeline.py",),
        _result(_bands_shifted),
    ),
    Mutation(
        "lamp ignores exposure time",
        "twin.components.lamps:_SteadyLamp.part_exposure_s",
        "a steady lamp's integral is one second's whatever the exposure",
        ("tests/twin/components/test_components.py",),
        _arguments(_ignore_exposure_time),
    ),
)


def apply(mutation: Mutation) -> None:
    """Replace the mutation's target by its mutated version."""
    module_name, attribute = mutation.target.split(":")
    owner = importlib.import_module(module_name)
    *path, name = attribute.split(".")
    for part in path:
        owner = getattr(owner, part)
    setattr(owner, name, mutation.wrap(getattr(owner, name)))


def _pytest(tests: list[str], mutation: str | None) -> subprocess.CompletedProcess:
    env = {key: value for key, value in os.environ.items() if key != "SPECTWIN_MUTATION"}
    if mutation:
        env["SPECTWIN_MUTATION"] = mutation
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider"]
        + (["-p", "benchmarks.mutation_check"] if mutation else [])
        + tests,
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
    )


def control() -> dict:
    """The named test files without any mutation: they must all pass."""
    tests = sorted({test for mutation in MUTATIONS for test in mutation.tests})
    start = time.perf_counter()
    completed = _pytest(tests, None)
    return {
        "tests": tests,
        "passed": completed.returncode == 0,
        "summary": completed.stdout.strip().splitlines()[-1] if completed.stdout.strip() else "",
        "seconds": round(time.perf_counter() - start, 1),
    }


def run(mutation: Mutation) -> dict:
    """Run the mutation's tests with it applied; the first failing test caught it."""
    start = time.perf_counter()
    completed = _pytest(list(mutation.tests), mutation.name)
    failed = re.findall(r"^FAILED (\S+)", completed.stdout, flags=re.MULTILINE)
    return {
        "mutation": mutation.name,
        "function": mutation.target,
        "description": mutation.description,
        "tests": list(mutation.tests),
        "caught": completed.returncode == 1 and bool(failed),
        "caught_by": failed[0] if failed else None,
        "pytest_exit": completed.returncode,
        "seconds": round(time.perf_counter() - start, 1),
    }


def main(names: list[str]) -> None:
    with_control = "--control" in names
    names = [name for name in names if name != "--control"]
    chosen = [m for m in MUTATIONS if not names or m.name in names]
    results = [run(mutation) for mutation in chosen]
    print(
        json.dumps(
            {
                "machine": f"{platform.machine()} {platform.processor() or ''}".strip(),
                "cpus": os.cpu_count(),
                "python": platform.python_version(),
                "date": time.strftime("%Y-%m-%d", time.gmtime()),
                "caught": sum(r["caught"] for r in results),
                "mutations": results,
                **({"control": control()} if with_control else {}),
            },
            indent=2,
        )
    )


# Loaded as a pytest plugin with SPECTWIN_MUTATION set: patch before any test module imports.
if os.environ.get("SPECTWIN_MUTATION") and __name__ != "__main__":
    apply(next(m for m in MUTATIONS if m.name == os.environ["SPECTWIN_MUTATION"]))

if __name__ == "__main__":
    main(sys.argv[1:])
