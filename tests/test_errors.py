"""One tree of exceptions (:mod:`hwbridge.errors`): every exception class of ``twin``, ``recon``
and ``hwbridge`` is a :class:`SpectwinError`; the libraries' messages name no command or option
of ``spectwin`` (the command line adds its advice); the command line maps each branch to its
exit code.

The classes and messages are found in the source (``ast``), so no renderer is imported.
"""

from __future__ import annotations

import ast
import builtins
import importlib
import re
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from hwbridge.errors import (
    DamagedDataError,
    DataError,
    DeviceError,
    DeviceTimeout,
    DriverNotInstalled,
    InputError,
    MissingDataError,
    Remedy,
    SessionInterrupted,
    SpectwinError,
    StoreBusy,
)
from twin.cli.errors import ADVICE, INTERRUPTED, RUN_FAILED, USAGE, SpectwinGroup

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("twin", "recon", "hwbridge")
LIBRARIES = ("recon", "hwbridge")
BRANCHES = (InputError, DataError, DeviceError, StoreBusy, SessionInterrupted)
COMMAND_LINE = re.compile(r"\bspectwin\b|(?<![\w-])--[a-z]", re.IGNORECASE)
BUILTIN_EXCEPTIONS = {
    name
    for name, value in vars(builtins).items()
    if isinstance(value, type) and issubclass(value, BaseException)
}


def _sources(packages: tuple[str, ...]):
    for package in packages:
        for path in sorted((ROOT / package).rglob("*.py")):
            yield path, ast.parse(path.read_text(), filename=str(path))


def _base_name(node: ast.expr) -> str:
    return node.attr if isinstance(node, ast.Attribute) else getattr(node, "id", "")


def _exception_classes() -> dict[str, tuple[str, str]]:
    """Name to ``(module, name)`` of every class in the packages that derives, through classes
    of the packages, from a built-in exception."""
    classes = {}
    for path, tree in _sources(PACKAGES):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                classes[node.name] = (module, [_base_name(base) for base in node.bases])
    found = set(BUILTIN_EXCEPTIONS)
    while True:
        more = {name for name, (_, bases) in classes.items() if found & set(bases)} - found
        if not more:
            return {name: (classes[name][0], name) for name in found - BUILTIN_EXCEPTIONS}
        found |= more


EXCEPTIONS = _exception_classes()


def test_the_walk_finds_the_tree_and_the_subclasses_elsewhere():
    assert {"SpectwinError", "DamagedDataError", "DeviceTimeout"} <= set(EXCEPTIONS)
    assert {"MarksNotFoundError", "CornerRefinementError"} <= set(EXCEPTIONS)


@pytest.mark.parametrize("name", sorted(name for name in EXCEPTIONS if not name.startswith("_")))
def test_every_exception_class_is_a_spectwin_error_of_one_branch(name):
    """Private classes (a search's signal that it may stop) never leave their module."""
    module, attribute = EXCEPTIONS[name]
    cls = getattr(importlib.import_module(module), attribute)
    assert issubclass(cls, SpectwinError)
    if cls is not SpectwinError:
        assert sum(issubclass(cls, branch) for branch in BRANCHES) == 1, cls.__mro__


def _messages(tree: ast.Module):
    """``(line, text)`` of the string literals given to an exception: in a ``raise`` or in a
    call of an exception class (e.g. one returned to be raised)."""
    named = set(EXCEPTIONS) | BUILTIN_EXCEPTIONS
    for node in ast.walk(tree):
        if isinstance(node, ast.Raise) and node.exc is not None:
            given = node.exc
        elif isinstance(node, ast.Call) and _base_name(node.func) in named:
            given = node
        else:
            continue
        text = "".join(
            part.value
            for part in ast.walk(given)
            if isinstance(part, ast.Constant) and isinstance(part.value, str)
        )
        yield node.lineno, text


def test_no_library_message_names_a_command_or_option_of_the_command_line():
    found = [
        f"{path.relative_to(ROOT)}:{line}: {text}"
        for path, tree in _sources(LIBRARIES)
        for line, text in _messages(tree)
        if COMMAND_LINE.search(text)
    ]
    assert not found, "\n".join(found)


def test_every_remedy_has_the_command_lines_words():
    assert set(ADVICE) == set(Remedy)
    assert all(COMMAND_LINE.search(words) for words in ADVICE.values())


def _invoke(error: BaseException, command: str):
    """Run ``command`` (``plain``, or ``resumable``, which has ``--resume``) raising ``error``
    under :class:`SpectwinGroup`."""
    app = typer.Typer(cls=SpectwinGroup)

    @app.command()
    def plain() -> None:
        raise error

    @app.command()
    def resumable(resume: bool = typer.Option(False, "--resume")) -> None:
        raise error

    return CliRunner().invoke(app, [command], prog_name="spectwin")


@pytest.mark.parametrize(
    ("error", "code"),
    [
        (InputError("settings: expected x"), USAGE),
        (DriverNotInstalled("the driver needs a library"), USAGE),
        (DamagedDataError("store: a chunk is corrupt"), RUN_FAILED),
        (MissingDataError("data: no such file"), RUN_FAILED),
        (DeviceTimeout("k4: no answer"), RUN_FAILED),
        (StoreBusy("store: being written by PID 1"), RUN_FAILED),
        (SessionInterrupted("store", 3, 10), INTERRUPTED),
    ],
    ids=lambda value: type(value).__name__ if isinstance(value, BaseException) else str(value),
)
def test_the_command_line_maps_each_branch_to_its_exit_code(error, code):
    result = _invoke(error, "plain")
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output
    assert result.stderr.count("\n") == 1
    assert str(error.args[0]) in result.stderr or isinstance(error, SessionInterrupted)


def test_the_advice_follows_the_message():
    result = _invoke(InputError("x: expected a BTF store", remedy=Remedy.process), "plain")
    assert result.stderr == "error: x: expected a BTF store; spectwin process makes one\n"
    result = _invoke(DeviceTimeout("k4: no answer"), "resumable")
    assert result.stderr == "error: a device kept failing (k4: no answer); continue with --resume\n"


def test_resume_is_advised_only_where_the_command_has_it():
    busy = StoreBusy("s is being written by PID 1; wait for it to end, or stop it")
    assert _invoke(busy, "resumable").stderr.endswith("stop it; continue with --resume\n")
    assert _invoke(busy, "plain").stderr.endswith("stop it\n")
    exists = InputError("s exists: expected a new store", remedy=Remedy.resume_or_rename)
    assert _invoke(exists, "resumable").stderr.endswith(
        "; continue it with --resume or choose another name\n"
    )
    assert _invoke(exists, "plain").stderr.endswith("new store; choose another name\n")
