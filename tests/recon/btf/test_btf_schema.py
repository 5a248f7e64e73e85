"""The BTF store's metadata models (recon.btf.schema): what the store and processing write reads
back as the models; a store of another format version is refused in one line."""

import numpy as np
import pytest
import zarr

from recon.btf.schema import BTF_FORMAT_VERSION, BTFAttrs
from recon.btf.store import BTFStore
from recon.errors import InputError, Remedy
from recon.spectra import DEFAULT_GRID

UP = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])


def _store(path) -> BTFStore:
    return BTFStore.create(
        path,
        light_dirs=UP,
        view_dirs=UP[::-1],
        texels=4,
        grid=DEFAULT_GRID,
        material="lego",
        source_capture="run.capture.zarr",
        rig="dome",
    )


def test_the_attributes_and_what_processing_adds_read_back_as_the_model(tmp_path):
    store = _store(tmp_path / "lego.btf.zarr")
    added = {
        "dome_pairs": [[0, 12, "rgb00"], [0, 12, "rgb06"]],
        "projected_marks": ["rgb06_view0"],
        "marks_offset_px": {"rgb00_view0": 0.25, "rgb06_view0": 1.5},
        "saturated_texels": 3,
        "band_partner": "rgb06",
        "band_shift_texels": {"0": [0.1, -0.2]},
        "unregistered_pairs": [],
        "coarse_corner_pairs": [1],
    }
    for name, value in added.items():
        store.set_attribute(name, value)
    metadata = BTFStore.open(store.path).metadata
    assert metadata == BTFAttrs.model_validate(store.attrs)
    assert (metadata.format_version, metadata.rig, metadata.material) == (3, "dome", "lego")
    assert metadata.dome_pairs == ((0, 12, "rgb00"), (0, 12, "rgb06"))
    assert metadata.band_shift_texels == {"0": (0.1, -0.2)} and metadata.rgb_source is None
    assert store.attrs["dome_pairs"] == added["dome_pairs"]  # stored as written (JSON)


def test_an_attribute_outside_the_model_or_of_the_wrong_type_is_refused(tmp_path):
    store = _store(tmp_path / "lego.btf.zarr")
    with pytest.raises(InputError, match="attribute 'notes': expected one of"):
        store.set_attribute("notes", "looks fine")
    with pytest.raises(InputError, match="attribute 'material': expected one of"):
        store.set_attribute("material", "wool")  # set once, at creation
    with pytest.raises(InputError, match="attribute saturated_texels: saturated_texels: Input"):
        store.set_attribute("saturated_texels", "many")
    assert "notes" not in store.attrs and "saturated_texels" not in store.attrs


@pytest.mark.parametrize(("version", "shown"), [(1, "1"), (None, "none recorded")])
def test_a_store_of_another_format_version_is_refused_in_one_line(tmp_path, version, shown):
    path = _store(tmp_path / "lego.btf.zarr").path
    group = zarr.open_group(str(path), mode="r+")
    if version is None:
        del group.attrs["format_version"]
    else:
        group.attrs["format_version"] = version
    with pytest.raises(InputError) as refused:
        BTFStore.open(path)
    assert str(refused.value) == (
        f"{path}: a BTF store of format version {shown}, expected {BTF_FORMAT_VERSION} (written "
        "by another version of the software)"
    )
    assert refused.value.remedy is Remedy.process
