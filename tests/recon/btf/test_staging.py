"""A store built under a temporary name (recon.btf.staging): renamed into place when the build
ends, removed when it raises or is interrupted, never over an existing path."""

from __future__ import annotations

import pytest

from recon.btf.staging import staged
from recon.errors import InputError


def test_a_finished_build_is_renamed_into_place_and_nothing_else_is_left(tmp_path):
    target = tmp_path / "a.btf.zarr"
    with staged(target) as building:
        assert building.parent == tmp_path and building.name.startswith(".a.btf.zarr.")
        building.mkdir()
        (building / "zarr.json").write_text("{}")
        assert not target.exists()
    assert (target / "zarr.json").read_text() == "{}"
    assert [path.name for path in tmp_path.iterdir()] == ["a.btf.zarr"]


@pytest.mark.parametrize("stop", [InputError("a bad slice"), KeyboardInterrupt()])
def test_a_build_that_raises_or_is_interrupted_leaves_nothing(tmp_path, stop):
    with pytest.raises(type(stop)), staged(tmp_path / "a.btf.zarr") as building:
        building.mkdir()
        (building / "zarr.json").write_text("{}")
        raise stop
    assert list(tmp_path.iterdir()) == []


def test_an_existing_target_is_refused_before_and_after_the_build(tmp_path):
    target = tmp_path / "a.btf.zarr"
    target.mkdir()
    with pytest.raises(InputError, match="exists"), staged(target):
        pass
    other = tmp_path / "b.btf.zarr"
    with pytest.raises(InputError, match="exists"), staged(other) as building:
        building.mkdir()
        other.mkdir()  # another writer made it meanwhile
    assert sorted(path.name for path in tmp_path.iterdir()) == ["a.btf.zarr", "b.btf.zarr"]
