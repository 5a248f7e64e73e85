"""The 45/0 spectrophotometer comparison (thesis 4.2, Figs. 4.3 and 4.4) on a BTF of known truth."""

import numpy as np
import pytest

from recon.btf.store import BTFStore
from recon.spectra import DEFAULT_GRID
from twin.materials import load_material
from twin.render.truth import truth_btf
from twin.rigs.hemisphere import sattler_directions
from twin.rigs.rig_config import load_rig
from twin.sensor.band_weights import instrument_passbands
from twin.validate.spectrophotometer import compare_45_0, field_spots, write_45_0_figure

pytestmark = pytest.mark.render


def test_btf_integrated_over_the_45_degree_ring_matches_the_instrument_on_matte_fields(tmp_path):
    # A BTF of the true colour checker lit from the twin's 13 reduced directions (rings at 0, 30
    # and 60 degrees), seen from the top: the 45 degree ring lies between measured lights.
    material = load_material("colorchecker16")
    lights = sattler_directions(((0.0, 1), (30.0, 4), (60.0, 8)))
    views = np.tile([0.0, 0.0, 1.0], (len(lights), 1))
    passbands = instrument_passbands(load_rig("gonio"))
    texels = 48
    btf = BTFStore.create(
        tmp_path / "truth.btf.zarr",
        light_dirs=lights,
        view_dirs=views,
        texels=texels,
        grid=DEFAULT_GRID,
        material="colorchecker16",
    )
    values = truth_btf(material, lights, views, texels=texels, passbands=passbands, spp=64)
    for pair, texture in enumerate(values):
        btf.write_pair(pair, texture)
    result = compare_45_0(btf, material, azimuths=8)
    summary = result.summary()
    # Lambertian fields: any light ring gives the same reflectance factor, pi f_r = rho.
    assert summary["mean_error_matte_fields_pct"] < 1.0
    assert summary["max_error_matte_fields_pct"] < 3.0
    white = result.field_names.index("field_12")  # white 9.5: reflectance factor about 0.9
    assert 0.8 < result.instrument[white][10:25].mean() < 0.95
    assert field_spots(material, texels).sum(axis=(1, 2)).min() > 20
    write_45_0_figure(result, DEFAULT_GRID.wavelengths_nm, tmp_path / "45_0.png")
    assert (tmp_path / "45_0.png").stat().st_size > 30_000
