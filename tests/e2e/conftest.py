"""Fixtures of the end-to-end tests."""

import json

import pytest
from typer.testing import CliRunner

from twin.cli.app import app


@pytest.fixture(scope="session")
def invoke_json():
    """Run ``spectwin`` with the given arguments (``--json`` among them), assert success and
    return its parsed output."""
    runner = CliRunner()

    def invoke(*arguments):
        result = runner.invoke(app, [str(argument) for argument in arguments])
        assert result.exit_code == 0, result.output
        return json.loads(result.output)

    return invoke
