"""``spectwin sweep`` end to end at tiny size: the table, the front and the page; a sweep killed
(SIGKILL to its process group) at three seeded random moments within its points and continued
ends with the uninterrupted sweep's table, and no point is finished twice. A dome sweep on a
cluster's workers: tests/twin/devices/test_cluster.py."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
TINY = {
    "name": "tiny lamp sweep",
    "rig": "gonio",
    "material": "colorchecker16",
    "seed": 3,
    # 3 directions at 4 samples per pixel (the capture's 16 by default): 6 pairs, every one
    # registered at 128 px (at 96 px only 10 of the 20 pairs of 5 directions were).
    "plan": {"pixels": 128, "texels": 16, "rings": [[0, 1], [30, 2]], "spp": 4},
    "parameters": {"rig.lamps.*.spectrum": ["hmi", "qth"], "rig.camera.filter": ["VS-10"]},
}
# Measures that are the same whenever the same design is run: everything but the wall time and
# the compressed size of the stores (their index holds wall-clock timestamps).
_TIMING = ("point_s", "storage_mb")


def _start(sweep: Path, out: Path, *extra: str) -> subprocess.Popen:
    command = "from twin.cli.app import app; app()"
    return subprocess.Popen(
        [sys.executable, "-c", command, "sweep", str(sweep), "--out", str(out), "--json", *extra],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group: the kill reaches any worker it starts
    )


def _table(out: Path) -> list[dict]:
    rows = json.loads((out / "table.json").read_text())
    for row in rows:
        for name in _TIMING:
            row["measures"].pop(name)
    return rows


def _events(history: Path) -> list[str]:
    """The events of a point's ``history.jsonl`` (its whole lines: one may be being written)."""
    text = history.read_text()
    return [json.loads(line)["event"] for line in text[: text.rfind("\n") + 1].splitlines()]


def _counts(out: Path, event: str) -> dict[str, int]:
    """How often each point of the sweep in ``out`` has had ``event`` so far."""
    return {
        history.parent.name: _events(history).count(event)
        for history in (out / "points").glob("*/history.jsonl")
    }


def _wait_for_start(
    process: subprocess.Popen, out: Path, before: dict[str, int], point: str | None
) -> bool:
    """Wait until the sweep ``process`` starts ``point`` (None: any point) in ``out``, which held
    ``before`` starts per point; False when the process ends first."""
    while True:
        now = _counts(out, "started")
        if point is None and sum(now.values()) > sum(before.values()):
            return True
        if point is not None and now.get(point, 0) > before.get(point, 0):
            return True
        if process.poll() is not None:
            return False
        time.sleep(0.05)


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("sweep")
    sweep = folder / "tiny.yaml"
    sweep.write_text(yaml.safe_dump(TINY, sort_keys=False))
    process = _start(sweep, folder / "out")
    _, stderr = process.communicate(timeout=600)
    assert process.returncode == 0, stderr
    return sweep, folder / "out"


def test_a_tiny_sweep_writes_its_table_front_and_page(uninterrupted):
    _, out = uninterrupted
    rows = json.loads((out / "table.json").read_text())
    assert [row["label"] for row in rows] == ["hmi, VS-10", "qth, VS-10"]
    hmi, qth = (row["measures"] for row in rows)
    # A 3000 K QTH lamp starves the blue bands: its equalized exposures are several times the
    # HMI lamp's (lamp_choice notebook: 2-10x per pair), so is the run's capture time.
    assert 2 < qth["exposure_per_pair_s"] / hmi["exposure_per_pair_s"] < 10
    assert qth["capture_time_h"] > hmi["capture_time_h"]
    # 3 directions: 6 reachable pairs, every one registered; errors are finite percentages.
    assert hmi["pairs"] == qth["pairs"] == 6 and hmi["pairs_registered"] == 6
    for measures in (hmi, qth):
        assert 0 < measures["error_matte_pct"] < measures["error_glossy_pct"]
        assert 0 < measures["delta_e94_matte"] < 5
    # Both objectives are lower with the HMI lamp here (errors 8.6 and 15.0 %): it alone is on
    # the front.
    assert [row["on_front"] for row in rows] == [True, False]
    csv_lines = (out / "table.csv").read_text().splitlines()
    assert len(csv_lines) == 3 and csv_lines[0].startswith("point,label,rig.lamps.*.spectrum")
    for name in ("front.png", "effects.png", "index.html"):
        assert (out / name).stat().st_size > 1000, name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["points"] == summary["points_run_now"] == 2 and summary["front"] == [
        "hmi, VS-10"
    ]
    assert "Pareto front" in (out / "index.html").read_text()


def test_a_sweep_killed_three_times_resumes_to_the_uninterrupted_table(uninterrupted, tmp_path):
    sweep, reference = uninterrupted
    out = tmp_path / "killed"
    # Each kill comes at a seeded random moment within a point the run has started, within a
    # point's wall time of the uninterrupted sweep: the first cuts the first point short, the last
    # cuts the second point short, after the first is finished.
    rows = json.loads((reference / "table.json").read_text())
    point_s = max(row["measures"]["point_s"] for row in rows)
    rng = np.random.default_rng(22)
    kills = 0
    while kills < 3:
        starts_before = _counts(out, "started")
        process = _start(sweep, out)
        if not _wait_for_start(process, out, starts_before, rows[1]["key"] if kills == 2 else None):
            break
        time.sleep(rng.uniform(0.2, 0.8) * point_s)
        if process.poll() is not None:  # finished before the kill: not a kill
            break
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()
        kills += 1
    assert kills == 3, f"the sweep ended before three kills: {process.communicate()[1]}"
    process = _start(sweep, out)
    _, stderr = process.communicate(timeout=600)
    assert process.returncode == 0, stderr
    assert _table(out) == _table(reference)
    assert _counts(out, "finished") == {key: 1 for key in _counts(reference, "finished")}
    # The kills did cut points short: some point was started more than once.
    starts = _counts(out, "started")
    assert sum(starts.values()) > len(starts)
