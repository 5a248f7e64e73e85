"""Help that reads well: every command's help flows as paragraphs (no line broken where its
docstring's source line ends), and the demo's run time is stated once, as BENCHMARKS.md
measured it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import typer

from twin.cli.app import app

ROOT = Path(__file__).resolve().parents[3]


def _commands(group, path: tuple[str, ...] = ()):
    """Every command under ``group``, subcommands included (typer's groups are its own click's,
    not ``click.Group``)."""
    for name, command in group.commands.items():
        yield (*path, name), command
        if getattr(command, "commands", None):
            yield from _commands(command, (*path, name))


COMMANDS = list(_commands(typer.main.get_command(app)))


@pytest.mark.parametrize(
    ("path", "command"), COMMANDS, ids=[" ".join(path) for path, _ in COMMANDS]
)
def test_every_help_paragraph_is_one_line(path, command):
    paragraphs = (command.help or "").split("\n\n")
    assert all("\n" not in paragraph for paragraph in paragraphs), " ".join(path)


@pytest.mark.parametrize(
    ("path", "command"), COMMANDS, ids=[" ".join(path) for path, _ in COMMANDS]
)
def test_no_help_names_a_python_module(path, command):
    """Help speaks of the rigs and files, not of the code: a module path such as
    ``twin.gonio.render.GONIO_SPP`` is also cut short with an ellipsis in an 80-column table."""
    texts = [command.help or "", *(getattr(p, "help", None) or "" for p in command.params)]
    named = [m for text in texts for m in re.findall(r"\b(?:twin|recon|hwbridge)\.[a-z_]\w*", text)]
    assert not named, (" ".join(path), named)


def test_the_capture_group_lists_one_subcommand_per_program_and_resume():
    capture = dict(COMMANDS)[("capture",)]
    assert list(capture.commands) == [
        "demo",
        "gonio-calibration",
        "gonio-run",
        "dome-calibration",
        "dome-run",
        "resume",
    ]
    dome_run = {option for p in capture.commands["dome-run"].params for option in p.opts}
    assert "--leds" in dome_run and "--pixels" not in dome_run and "--resume" not in dome_run


def test_the_demo_time_is_stated_once_as_benchmarks_measured_it():
    benchmarks = (ROOT / "BENCHMARKS.md").read_text()
    section = benchmarks[benchmarks.index("## `make demo` on a cold machine") :]
    measured_s = float(re.search(r"\| now [^|]*\| (\d+) s \|", section).group(1))
    stated = re.search(r"about (\d+) s on 2 cores", dict(COMMANDS)[("demo",)].help)
    assert stated is not None
    assert abs(float(stated.group(1)) - measured_s) <= 0.1 * measured_s
    readme = (ROOT / "README.md").read_text()
    assert f"about {stated.group(1)} s on 2 cores" in readme
