"""One-line errors of the ``spectwin`` command line.

A user error (a bad option, an unknown name, a missing or wrong input file, a damaged store, a
run that failed) never shows a Python traceback: the command prints one line
``error: <what was wrong and what was expected>; <what to do>`` to stderr and exits with

- 2 for usage errors: bad options, unknown names, missing or wrong input files
  (:class:`~hwbridge.errors.InputError`, the option parser's own errors);
- 1 for failed runs: data that turned out damaged or missing
  (:class:`~hwbridge.errors.DataError`), devices that kept failing
  (:class:`~hwbridge.errors.DeviceError`), a store that another writer holds
  (:class:`~hwbridge.errors.StoreBusy`), a check that failed;
- 130 for a run stopped by Ctrl-C (``KeyboardInterrupt``) or, in a capture, SIGTERM
  (:class:`~hwbridge.errors.SessionInterrupted`): one line ``interrupted ...``
  (``spectwin capture`` says how far it got and how to continue).

The commands check their output locations before any work (:func:`require_output_folder`,
:func:`require_output_file`: names and paths the filesystem allows, places this user may
write). An error of the operating system that still reaches the group (an input this user may
not read, a full disk) is one line naming its path: exit 2 for a location that cannot be read or
written, 1 for a disk that filled or failed during the run; any other ``OSError`` is a bug and
keeps its traceback.

The libraries' messages say what is wrong; what to do is the exception's
:class:`~hwbridge.errors.Remedy`, which :data:`ADVICE` words as commands and options of
``spectwin`` (advice to continue with ``--resume`` only where the command has that option).

:class:`SpectwinGroup` applies this to every command registered on the app; anything else is a
bug and keeps its traceback.
"""

from __future__ import annotations

import errno
import inspect
import os
import shutil
from contextvars import ContextVar
from pathlib import Path
from typing import Any, NoReturn

import typer
from typer.core import TyperGroup

from hwbridge.errors import (
    DataError,
    DeviceError,
    InputError,
    Remedy,
    SessionInterrupted,
    StoreBusy,
)

__all__ = [
    "ADVICE",
    "INTERRUPTED",
    "INTERRUPT_REPORT",
    "RUN_FAILED",
    "USAGE",
    "SpectwinGroup",
    "fail",
    "interrupted",
    "one_line",
    "remove_if_interrupted",
    "require_output_file",
    "require_output_folder",
    "run_failed",
]

USAGE = 2
RUN_FAILED = 1
INTERRUPTED = 130

INTERRUPT_REPORT = "spectwin.interrupt_report"
"""Key in a command's ``ctx.meta`` of a callable that says how far the command got and exits
with :data:`INTERRUPTED`: a Ctrl-C that reaches the command group, e.g. one arriving as the
command returns, ends with that line rather than a bare "interrupted"."""


ADVICE: dict[Remedy, str] = {
    Remedy.resume: "continue with --resume",
    Remedy.resume_or_rename: "continue it with --resume or choose another name",
    Remedy.finish_processing: "finish it with spectwin process --resume",
    Remedy.reprocess_pairs: "process the capture again with spectwin process --resume",
    Remedy.process: "spectwin process makes one",
    Remedy.export_btf: "spectwin btf export writes one",
    Remedy.calibrate: "write it with spectwin calibrate",
    Remedy.calibrate_texels: "calibrate with the run's --texels",
    Remedy.calibrate_leds: "calibrate with the run's --leds",
    Remedy.capture_gonio_calibration: "spectwin capture gonio-calibration makes one",
    Remedy.capture_gonio_run: "spectwin capture gonio-run makes one",
    Remedy.capture_dome_calibration: "spectwin capture dome-calibration makes one",
    Remedy.capture_dome_run: "spectwin capture dome-run makes one",
    Remedy.reinstall: "reinstall spectwin",
    Remedy.install_rotation_stage: "pip install 'spectwin[rotation-stage]'",
}
"""The command line's words for each :class:`~hwbridge.errors.Remedy`."""

_WITHOUT_RESUME: dict[Remedy, str | None] = {
    Remedy.resume: None,
    Remedy.resume_or_rename: "choose another name",
}
"""The advice of a command without ``--resume`` (e.g. ``compress``, ``demo``)."""


def one_line(message: object) -> str:
    """``message`` on one line (newlines and runs of spaces become single spaces)."""
    return " ".join(str(message).split())


def fail(message: object, code: int = USAGE) -> NoReturn:
    """Print ``error: message`` (one line) to stderr and exit with ``code``."""
    typer.echo(f"error: {one_line(message)}", err=True)
    raise typer.Exit(code)


def run_failed(message: object) -> NoReturn:
    """A run that failed (exit code 1)."""
    fail(message, RUN_FAILED)


def interrupted(message: object) -> NoReturn:
    """A run stopped by Ctrl-C: print ``interrupted: message`` (what is left and how to
    continue, one line) to stderr and exit with :data:`INTERRUPTED`."""
    typer.echo(f"interrupted: {one_line(message)}", err=True)
    raise typer.Exit(INTERRUPTED)


def remove_if_interrupted(ctx: typer.Context, out: Path) -> None:
    """Have a Ctrl-C that stops the command delete the output ``out`` it writes and say that
    nothing was written. ``out`` is new or an empty folder now, so that what is in it then is the
    command's own; a folder the user filled is left alone (the command refuses it)."""
    if out.is_dir() and any(out.iterdir()):
        return
    was_folder = out.is_dir()

    def report() -> NoReturn:
        if was_folder:
            for path in out.iterdir():
                if path.is_dir():
                    shutil.rmtree(path)
                else:
                    path.unlink()
        elif out.exists():
            shutil.rmtree(out)
        interrupted(f"nothing was written to {out}; run the same command again")

    ctx.meta[INTERRUPT_REPORT] = report


def require_output_folder(path: Path, option: str = "--out") -> None:
    """Refuse an output folder that names an existing file, or that cannot be written (see
    :func:`require_output_file`)."""
    _require_short_names(path, option)
    if path.exists() and not path.is_dir():
        fail(f"{option} {path}: is a file; expected a folder (new or existing)")
    _require_writable(path, option)
    _OUTPUT.set(f"{option} {path}")


def require_output_file(path: Path, option: str = "--out") -> None:
    """Refuse an output file that names a folder or lies below a file, or that cannot be
    written: a name or path longer than the filesystem allows (``NAME_MAX``, ``PATH_MAX``), or
    a place this user may not write (permissions, a read-only filesystem). The commands call it
    before any work, so that a run never fails on its output after the work is done."""
    _require_short_names(path, option)
    if path.is_dir():
        fail(f"{option} {path}: is a folder; expected a file name")
    _require_writable(path, option)
    _OUTPUT.set(f"{option} {path}")


_OUTPUT: ContextVar[str | None] = ContextVar("spectwin_output", default=None)
"""The output location the running command checked last (``--out PATH``): what a full disk
is named by when the system's error names no file."""


def _shown(path: object) -> str:
    """``path`` as a message shows it: a path of thousands of characters is shortened."""
    text = str(path)
    return text if len(text) <= 160 else f"{text[:80]}...{text[-60:]}"


def _existing_above(path: Path) -> Path:
    """The nearest path above the absolute ``path`` that exists (a folder, unless the user
    named a path below a file)."""
    for above in path.parents:
        try:
            if above.exists():
                return above
        except OSError:  # a name too long to look up
            continue
    return Path(path.anchor)


def _limit(folder: Path, name: str, default: int) -> int:
    """The filesystem's ``pathconf`` limit ``name`` at ``folder`` (``default`` if unknown)."""
    try:
        return os.pathconf(folder, name)
    except (OSError, ValueError):
        return default


def _require_short_names(path: Path, option: str) -> None:
    """Refuse ``path`` when one of its names or the whole path is longer than the filesystem
    allows (checked before anything looks the path up, which would fail)."""
    absolute = Path(os.path.abspath(path))
    existing = _existing_above(absolute)
    name_max = _limit(existing, "PC_NAME_MAX", 255)
    for name in absolute.parts[1:]:
        if len(os.fsencode(name)) > name_max:
            fail(
                f"{option} {_shown(path)}: a name of {len(os.fsencode(name))} bytes "
                f"({name[:24]}...); expected names of at most {name_max} bytes"
            )
    path_max = _limit(existing, "PC_PATH_MAX", 4096)
    if len(os.fsencode(absolute)) >= path_max:
        fail(
            f"{option} {_shown(path)}: a path of {len(os.fsencode(absolute))} bytes; expected "
            f"at most {path_max - 1}"
        )


def _require_writable(path: Path, option: str) -> None:
    """Refuse ``path`` when the folders above it hold a file, or when ``path`` (if it exists)
    or the nearest folder above it that exists cannot be written."""
    above = _existing_above(Path(os.path.abspath(path)))
    if not above.is_dir():
        fail(f"{option} {path}: {above} is a file, not a folder")
    target = path if path.exists() else above
    access = os.W_OK | (os.X_OK if target.is_dir() else 0)
    if not os.access(target, access, effective_ids=os.access in os.supports_effective_ids):
        fail(
            f"{option} {path}: {target} is not writable (permission denied or a read-only "
            "filesystem); choose another place"
        )


_RUN_ERRORS = (DataError, DeviceError, StoreBusy)

_PERMITTED = "expected a file or folder this user may read (and, for an output, write)"

_OS_INPUT_ERRORS: dict[int, str] = {
    errno.EACCES: _PERMITTED,
    errno.EPERM: _PERMITTED,
    errno.EROFS: "expected an output on a writable filesystem",
    errno.ENAMETOOLONG: "expected names and a path within the filesystem's limits",
    errno.ELOOP: "expected a path without a loop of symbolic links",
}
"""Errors of the operating system that mean a wrong input or output location (exit 2), and
what was expected."""

_OS_RUN_ERRORS: dict[int, str] = {
    errno.ENOSPC: "free space on it",
    errno.EDQUOT: "free space within the quota",
    errno.EIO: "check the disk",
}
"""Errors of the operating system that stop a run (exit 1), and what to do."""


def _os_error_line(error: OSError) -> str:
    """``<path>: <the system's words>``: the error's file, else the command's output (writing
    to an open file names none), else the words alone."""
    words = error.strerror or str(error)
    if error.filename is not None:
        return f"{_shown(error.filename)}: {words}"
    output = _OUTPUT.get()
    return f"{words} (writing {_shown(output)})" if output is not None else words


def _advised(message: object, advice: str | None) -> str:
    """``message`` followed by ``advice``, if any."""
    return f"{message}; {advice}" if advice else str(message)


def _usage_error(error: typer.TyperException) -> NoReturn:
    """The option parser's error (bad or missing option, out of range, unknown command)."""
    message = error.format_message().replace("Value error, ", "")
    context = getattr(error, "ctx", None)
    if context is not None:
        message += f" (see '{context.command_path} --help')"
    fail(message, getattr(error, "exit_code", USAGE))


def _shows_help(error: typer.TyperException) -> bool:
    """A group called without arguments: click shows its help and exits 2."""
    return type(error).__name__ == "NoArgsIsHelpError"


def reflowed(text: str | None) -> str | None:
    """``text`` (a docstring) with each paragraph on one line, so that the help shows it as
    prose wrapped to the terminal rather than broken where the source breaks it."""
    if text is None:
        return None
    paragraphs = inspect.cleandoc(text).split("\n\n")
    return "\n\n".join(" ".join(paragraph.split()) for paragraph in paragraphs)


class SpectwinGroup(TyperGroup):
    """The command group of ``spectwin``: every error of the user is one line on stderr, and
    every help text flows as paragraphs."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.help = reflowed(self.help)
        for command in self.commands.values():
            command.help = reflowed(command.help)

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
        try:
            return super().parse_args(ctx, args)
        except typer.TyperException as error:
            if _shows_help(error):
                raise
            _usage_error(error)

    def invoke(self, ctx: Any) -> Any:
        _OUTPUT.set(None)
        try:
            return super().invoke(ctx)
        except typer.TyperException as error:
            if _shows_help(error):  # a subgroup (``spectwin store``) without arguments
                raise
            _usage_error(error)
        except InputError as error:
            fail(_advised(error, self.advice(ctx, error.remedy)), USAGE)
        except _RUN_ERRORS as error:
            shown = f"a device kept failing ({error})" if isinstance(error, DeviceError) else error
            fail(_advised(shown, self.advice(ctx, error.remedy)), RUN_FAILED)
        except SessionInterrupted as stop:  # a capture inside another command (the demo)
            line = f"interrupted after {stop.done} of {stop.total} frames of {stop.store}"
            typer.echo(_advised(line, self.advice(ctx, stop.remedy)), err=True)
            raise typer.Exit(INTERRUPTED) from None
        except OSError as error:  # a last resort: the commands check their paths first
            if error.errno in _OS_INPUT_ERRORS:
                fail(f"{_os_error_line(error)}; {_OS_INPUT_ERRORS[error.errno]}", USAGE)
            if error.errno in _OS_RUN_ERRORS:
                line = f"{_os_error_line(error)}; {_OS_RUN_ERRORS[error.errno]}"
                fail(_advised(line, self.advice(ctx, Remedy.resume)), RUN_FAILED)
            raise  # anything else is a bug
        except KeyboardInterrupt:
            report = ctx.meta.get(INTERRUPT_REPORT)
            if report is not None:
                report()
            typer.echo("interrupted", err=True)
            raise typer.Exit(INTERRUPTED) from None

    def advice(self, ctx: Any, remedy: Remedy | None) -> str | None:
        """The command line's words for ``remedy`` after the command that ran: the advice to
        resume only where that command has ``--resume``."""
        if remedy is None:
            return None
        command = self.get_command(ctx, ctx.invoked_subcommand or "")
        if command is not None and any("--resume" in p.opts for p in command.params):
            return ADVICE[remedy]
        return _WITHOUT_RESUME.get(remedy, ADVICE[remedy])
