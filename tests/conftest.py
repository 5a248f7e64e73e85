"""Shared test fixtures."""

import json
import shutil
import signal
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest


def pytest_configure(config: pytest.Config) -> None:
    """Ctrl-C as in a terminal: a suite started in the background (``make test &``, a CI
    runner) inherits SIGINT ignored, which the captures, rightly, leave ignored; the tests that
    stop captures with SIGINT, in this process or in the commands it starts, need it handled."""
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)


# A twin camera with known parameters and the plan of an EMVA 1288 measurement for it: the
# second data set of the fit (tests/integration/test_emva_fit.py) and, at a few pixels, the
# source of the bad descriptors (tests/e2e/test_cli_camera_emva.py).
SYNTHETIC_CAMERA = {
    "name": "synthetic 14-bit CCD",
    "serial": "SYNTHETIC-1288",
    "mosaic": "none",
    "width": 128,
    "height": 128,
    "pixel_pitch_um": 5.0,
    "bit_depth": 14,
    "sensor_temperature_c": 25.0,
    "exposure_range_s": [1e-4, 1.0],
    "optics": {"f_number": 8.0},
    # Peak at the measurement's 550 nm: the quantum efficiency there is peak_qe.
    "quantum_efficiency": {
        "model": "ccd",
        "peak_qe": 0.6,
        "peak_nm": 550.0,
        "log_width_blue": 0.25,
        "log_width_red": 0.31,
    },
    "system_gain_dn_per_e": 0.5,
    "read_noise_dn": 4.0,
    "full_well_e": 20000.0,  # 10000 DN above the offset: the full well clips before the ADC
    "adc_offset_dn": 100.0,
    "dark_current": {"e_per_s_at_reference": 2000.0},
    "fixed_pattern": {"prnu_sigma": 0.01, "offset_sigma_dn": 2.0},
    "oecf": {"model": "knee", "strength": 0.05},
}


@pytest.fixture(scope="session")
def synthetic_camera():
    from twin.rigs.camera_config import CameraConfig

    return CameraConfig.model_validate(SYNTHETIC_CAMERA)


@pytest.fixture(scope="session")
def make_emva_measurement(synthetic_camera):
    """``make(folder, size=..., spatial_frames=..., seed=...)``: the synthetic camera's EMVA 1288
    measurement written to ``folder``: constant light, exposure times from 2 % to 110 % of
    saturation (finer above 90 %), every step with its dark step, one spatial pair at half
    saturation."""
    from recon.emva.descriptor import EMVADescriptor, EMVAStep
    from twin.sensor.emva_measurement import simulate_measurement

    eta = SYNTHETIC_CAMERA["quantum_efficiency"]["peak_qe"]
    saturation_photons = SYNTHETIC_CAMERA["full_well_e"] / eta
    photons_per_s = 1.15 * saturation_photons / 0.05  # 115 % of saturation in 50 ms
    fractions = np.concatenate([np.linspace(0.02, 0.9, 20), np.linspace(0.92, 1.1, 16)])

    def step(kind: str, fraction: float, names: tuple[str, ...]) -> EMVAStep:
        exposure_ns = round(fraction * saturation_photons / photons_per_s * 1e9, -3)
        photons = round(photons_per_s * exposure_ns / 1e9) if kind == "bright" else 0.0
        return EMVAStep(kind, exposure_ns, photons, names)

    def make(folder, *, size: int = 128, spatial_frames: int = 16, seed: int = 3):
        steps = []
        for kind, letter in (("bright", "b"), ("dark", "d")):
            steps += [
                step(
                    kind,
                    fraction,
                    (f"images/{letter}_{i:03d}_1.png", f"images/{letter}_{i:03d}_2.png"),
                )
                for i, fraction in enumerate(fractions)
            ]
            names = tuple(f"images/{letter}_s_{k:03d}.png" for k in range(spatial_frames))
            steps.append(step(kind, 0.5, names))
        plan = EMVADescriptor(SYNTHETIC_CAMERA["bit_depth"], size, size, tuple(steps))
        return simulate_measurement(synthetic_camera, plan, folder, wavelength_nm=550.0, seed=seed)

    return make


def _load_script(name: str):
    """A module of ``scripts/`` (not a package: loaded from its file)."""
    import importlib.util

    path = Path(__file__).parents[1] / "scripts" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def emva_reference_sets():
    """``scripts/emva1288_reference_sets.py``: measurements shaped like the official EMVA 1288
    reference sets 002 and 003, written from known parameters."""
    return _load_script("emva1288_reference_sets")


@pytest.fixture(scope="session")
def cmos8_measurement(tmp_path_factory, emva_reference_sets):
    """Reference set 002's plan (exposure-0 steps, 100 spatial frames) taken by a twin 8-bit
    camera with quantization-limited dark frames, 128 x 128 px."""
    return emva_reference_sets.write_cmos8(tmp_path_factory.mktemp("cmos8"))


@pytest.fixture(scope="session")
def heidelberg_measurement(tmp_path_factory, emva_reference_sets):
    """Reference set 003's simulated 12-bit camera and plan (one exposure time), 128 x 128 px."""
    return emva_reference_sets.write_heidelberg(tmp_path_factory.mktemp("heidelberg"))


def _truncate(file: Path) -> None:
    file.write_bytes(file.read_bytes()[:7])


def _flip_a_bit(file: Path) -> None:
    data = bytearray(file.read_bytes())
    data[len(data) // 2] ^= 0x04
    file.write_bytes(bytes(data))


CHUNK_DAMAGE = {"deleted": Path.unlink, "truncated": _truncate, "flipped": _flip_a_bit}
"""The ways a store's chunk file is damaged on disk: lost, cut short, one bit flipped."""


@dataclass(frozen=True)
class ChunkDamage:
    """One way of damaging a chunk file: ``damage(file)`` does it, ``damage.kind`` names it."""

    kind: str

    def __call__(self, file: Path) -> None:
        CHUNK_DAMAGE[self.kind](file)


@pytest.fixture(params=sorted(CHUNK_DAMAGE))
def damage(request) -> ChunkDamage:
    """Each way a chunk file is damaged, in turn (parametrizes the test)."""
    return ChunkDamage(request.param)


@pytest.fixture
def chunk_damage() -> dict[str, ChunkDamage]:
    """Every way of damaging a chunk file, by name."""
    return {kind: ChunkDamage(kind) for kind in CHUNK_DAMAGE}


@pytest.fixture(scope="session")
def bonn_files():
    """``scripts/bonn_btf_files.py``: writers of the Bonn BTF layouts (UBO2003 and ATRIUM
    archives, UBO2014 files) as recon.btf.bonn_formats documents them."""
    return _load_script("bonn_btf_files")


def _swap(store: Path, key: str, other: str, donors: dict[str, Path]) -> None:
    first, second = store / key, store / other
    data = first.read_bytes()
    first.write_bytes(second.read_bytes())
    second.write_bytes(data)


def _move(store: Path, key: str, other: str, donors: dict[str, Path]) -> None:
    shutil.copyfile(store / other, store / key)


def _foreign(store: Path, key: str, other: str, donors: dict[str, Path]) -> None:
    shutil.copyfile(donors["foreign"] / key, store / key)


def _reshaped(store: Path, key: str, other: str, donors: dict[str, Path]) -> None:
    shutil.copyfile(donors["reshaped"] / key, store / key)


CHUNK_MISPLACING = {"swapped": _swap, "moved": _move, "foreign": _foreign, "reshaped": _reshaped}
"""The ways a sound chunk file ends up where it does not belong: swapped with another chunk of
its array, copied over another one, copied from another store of the same layout, or from a
store whose chunks have another shape. Each leaves a chunk whose checksum matches its bytes."""


@dataclass(frozen=True)
class ChunkMisplacing:
    """One way of putting a sound chunk where it does not belong: ``misplace(store, key, other,
    donors)`` replaces ``key`` (``other``: a chunk of the same array; ``donors``: stores named
    ``foreign`` and ``reshaped``); ``misplace.kind`` names it."""

    kind: str

    def __call__(self, store: Path, key: str, other: str, donors: dict[str, Path]) -> None:
        CHUNK_MISPLACING[self.kind](store, key, other, donors)


@pytest.fixture(params=sorted(CHUNK_MISPLACING))
def misplace(request) -> ChunkMisplacing:
    """Each way a sound chunk is misplaced, in turn (parametrizes the test)."""
    return ChunkMisplacing(request.param)


def _edit_metadata(file: Path, edit) -> None:
    document = json.loads(file.read_text())
    edit(document)
    file.write_text(json.dumps(document))


@pytest.fixture
def edit_metadata():
    """``edit_metadata(file, edit)``: a store's ``zarr.json`` edited by hand (``edit(document)``
    changes the parsed document in place)."""
    return _edit_metadata
