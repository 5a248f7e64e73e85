"""The example user materials (``spectwin material examples``) through the gonio twin at the
reduced 13 x 13 direction sampling: calibration, capture, processing into a BTF and the
texel-wise evaluation against the truth (Eq. 6.8, Delta E94), with the time of each step.

Run: .venv/bin/python -m benchmarks.user_materials OUT_DIR
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

from benchmarks.common import machine_description

_SPECTWIN = str(Path(sys.executable).with_name("spectwin"))


def _run(*arguments) -> tuple[dict, float]:
    started = time.perf_counter()
    output = subprocess.run(
        [_SPECTWIN, *map(str, arguments), "--json"], check=True, capture_output=True, text=True
    ).stdout
    return json.loads(output), round(time.perf_counter() - started, 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="a new folder for the stores")
    out = parser.parse_args().out
    out.mkdir(parents=True)
    results: dict[str, object] = {"machine": machine_description()}
    written, _ = _run("material", "examples", "--out", out / "materials")
    _, results["calibration_s"] = _run("capture", "gonio-calibration", out / "cal.capture.zarr")
    _run("calibrate", out / "cal.capture.zarr", "--out", out / "cal.json")
    for path in written["materials"]:
        name = Path(path).stem
        capture, btf = out / f"{name}.capture.zarr", out / f"{name}.btf.zarr"
        captured, capture_s = _run(
            "capture", "gonio-run", capture, "--calibration", out / "cal.json",
            "--material", path,
        )  # fmt: skip
        processed, process_s = _run(
            "process", capture, "--calibration", out / "cal.json", "--out", btf, "--texels", 64
        )
        evaluated, evaluate_s = _run("evaluate", btf, "--figure", out / f"{name}.png")
        results[name] = {
            "pairs": processed["shape"][0],
            "sample_frames": captured["frames"]["sample"],
            "capture_s": capture_s,
            "process_s": process_s,
            "evaluate_s": evaluate_s,
            **{
                key: round(value, 3) if isinstance(value, float) else value
                for key, value in evaluated.items()
            },
        }
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
