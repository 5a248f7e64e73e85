"""ARCHITECTURE.md's tables of the stores' metadata are those the models make
(``scripts/store_tables.py``): a field added, renamed or described anew in ``hwbridge.schema``
or ``recon.btf.schema`` must reach the file (``python scripts/store_tables.py --write``)."""

import importlib.util
import typing
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def store_tables():
    spec = importlib.util.spec_from_file_location(
        "store_tables", ROOT / "scripts" / "store_tables.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_architecture_holds_the_tables_the_models_make(store_tables):
    text = (ROOT / "ARCHITECTURE.md").read_text()
    assert text.count(store_tables.BEGIN) == 1 and text.count(store_tables.END) == 1
    assert store_tables.with_tables(text) == text, (
        "ARCHITECTURE.md differs from the models: run python scripts/store_tables.py --write"
    )


def test_every_field_of_every_model_has_a_row_and_a_meaning(store_tables):
    for model in store_tables.MODELS:
        rows = store_tables.table(model).splitlines()
        for name, field in model.model_fields.items():
            assert field.description, f"{model.__name__}.{name} has no description"
            assert sum(row.startswith(f"| `{name}` |") for row in rows) == 1


def test_types_are_written_as_json_shapes(store_tables):
    name = store_tables.type_name
    assert name(tuple[tuple[float, float], ...] | None) == "[[float, float], ...] or null"
    assert name(typing.Literal["rgb", "spectral"]) == "'rgb' or 'spectral'"
    assert name(dict[str, typing.Any]) == "{str: any}"
