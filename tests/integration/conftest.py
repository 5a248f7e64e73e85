"""Fixtures of the integration tests: capture processes to interrupt."""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

# A driver process that imports the command line and the capture programs once, then forks a
# fresh `spectwin capture` for every request: each capture is a real process of its own (killed,
# interrupted, refused like any other) that starts in milliseconds instead of seconds of imports,
# so the tests spend their time capturing and interrupting. Requests on stdin, one JSON per line:
# {"args": [...], "stderr": path} starts a capture and answers {"pid": ...}; {"wait": pid}
# reaps it and answers {"code": exit code, or -signal}.
DRIVER = r"""
import json, os, sys, traceback
from twin.cli.app import app
import twin.gonio.sim_session  # noqa: F401 (the demo program's imports)
import twin.dome.programs  # noqa: F401 (the dome programs' imports)
import twin.kinds.dome  # noqa: F401 (the rig registry of the capture programs)
import twin.kinds.gonio  # noqa: F401

for line in sys.stdin:
    request = json.loads(line)
    if "wait" in request:
        _, status = os.waitpid(request["wait"], 0)
        print(json.dumps({"code": os.waitstatus_to_exitcode(status)}), flush=True)
        continue
    pid = os.fork()
    if pid == 0:
        os.dup2(os.open(request["stderr"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC), 2)
        os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
        code = 0
        try:
            app(request["args"], prog_name="spectwin")
        except SystemExit as end:
            code = end.code if isinstance(end.code, int) else 1
        except BaseException:
            traceback.print_exc()
            code = 99
        sys.stderr.flush()
        os._exit(code)
    print(json.dumps({"pid": pid}), flush=True)
"""


class CaptureProcesses:
    """`spectwin capture` processes forked by the driver."""

    def __init__(self, folder: Path):
        environment = os.environ | {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
        self._driver = subprocess.Popen(
            [sys.executable, "-c", DRIVER],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            cwd=ROOT,
            env=environment,
        )
        self._folder, self._count, self._live = folder, 0, set()

    def _ask(self, request: dict) -> dict:
        self._driver.stdin.write(json.dumps(request) + "\n")
        self._driver.stdin.flush()
        return json.loads(self._driver.stdout.readline())

    def start(self, args: list[str]) -> tuple[int, Path]:
        self._count += 1
        stderr = self._folder / f"capture{self._count}.stderr"
        pid = self._ask({"args": args, "stderr": str(stderr)})["pid"]
        self._live.add(pid)
        return pid, stderr

    def wait(self, pid: int) -> int:
        self._live.discard(pid)
        return self._ask({"wait": pid})["code"]

    def close(self) -> None:
        for pid in self._live:  # left running (or stopped) by a failed check
            os.kill(pid, signal.SIGKILL)
        self._live.clear()
        if not self._driver.stdin.closed:
            self._driver.stdin.close()
        self._driver.wait(timeout=30)


def lock_names(path: Path, pid: int, inside: bool = False) -> bool:
    """Whether the store's lock file (inside it, or beside it while it is created, unless
    ``inside``) names pid."""
    lock_files = [path / ".writer.lock"]
    if not inside:
        lock_files.append(path.with_name(f".{path.name}.writer.lock"))
    for lock_file in lock_files:
        try:
            if json.loads(lock_file.read_text())["pid"] == pid:
                return True
        except (OSError, ValueError, KeyError):
            pass
    return False


def running(pid: int) -> bool:
    """Whether process ``pid`` runs (has not ended; a child not yet reaped is a zombie)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, IndexError):
        return False
    return state not in ("Z", "X")


class CaptureKit:
    """What the interruption tests use: the driver's processes and the lock helpers."""

    root = ROOT
    lock_names = staticmethod(lock_names)
    running = staticmethod(running)

    def __init__(self, folder: Path):
        self._folder = folder
        self._processes: CaptureProcesses | None = None

    @property
    def processes(self) -> CaptureProcesses:
        if self._processes is None:
            self._processes = CaptureProcesses(self._folder)
        return self._processes

    def close(self) -> None:
        if self._processes is not None:
            self._processes.close()


@pytest.fixture
def capture_kit(tmp_path):
    kit = CaptureKit(tmp_path)
    yield kit
    kit.close()
