"""Real benches the twin predicts frame by frame: the schema of ``scenes/benches/*.yaml``.

A bench file describes a real capture that ships as data: where its frames are and how they map
into a capture store (an ``ingest`` mapping of :mod:`hwbridge.replay`), the camera (a file of
``scenes/cameras``) and its lens, how the stored frames were reduced from the raw ones, the chart
(a patch label image and the patches' measured reflectances), the filters in front of the lamp
(their measured transmissions), where the lamp stands, and which frames the twin may fit its free
parameters on. A second bench of the same kind is a data folder and such a file, no new code.
Paths are relative to the bench's ``data`` folder, itself beside the bench file or inside
spectwin's measured data (``recon/data``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

from pydantic import Field, model_validator

from recon.errors import InputError, MissingDataError
from recon.measured_data import data_path
from twin.rigs.yaml_config import (
    Positive,
    StrictModel,
    read_yaml_mapping,
    resolve_scene_file,
    scene_folder,
    scene_names,
    validate_document,
)

__all__ = ["BENCH_DIR", "BenchConfig", "available_benches", "load_bench"]

BENCH_DIR = scene_folder("benches")


class ReductionConfig(StrictModel):
    """How the stored frames were made from the raw Bayer frames: bilinear demosaicing, resizing
    by ``1 / factor`` to ``height x width`` (with anti-aliasing), re-mosaicing and quantization of
    the raw range to ``bit_depth`` bits. ``factor`` 1 and the sensor's bit depth: raw frames."""

    factor: Annotated[int, Field(ge=1, le=64)] = 1
    height: Annotated[int, Field(gt=0)]
    width: Annotated[int, Field(gt=0)]
    bit_depth: Annotated[int, Field(ge=8, le=16)]


class ChartConfig(StrictModel):
    """The chart: ``labels`` (an image, 0 off the patches, ``i`` on patch ``i``), ``spectra``
    (a CSV with a ``Wavelength`` column and one reflectance column per patch), ``patches`` (the
    columns, in label order), its layout (``columns`` patches per row), its distance from the lens
    to its centre, the fraction of a patch cell the patch fills, and how far (pixels) the masks
    are eroded before averaging (chromatic aberration shifts the bands)."""

    labels: str
    spectra: str
    patches: tuple[str, ...] = Field(min_length=1)
    columns: Annotated[int, Field(gt=0)]
    distance_m: Positive
    patch_fill: Annotated[float, Field(gt=0, le=1)] = 0.85
    erode_px: Annotated[int, Field(ge=0, le=20)] = 3


class FiltersConfig(StrictModel):
    """Filters in front of the lamp: ``spectra`` (CSV as the chart's), ``columns`` (the frames'
    nominal band in nm to the filter's column) and the half-width around each filter's peak that
    is its passband (outside it the measured transmission is the spectrometer's floor)."""

    spectra: str
    columns: dict[int, str] = Field(min_length=1)
    main_lobe_nm: Positive = 20.0


class LampConfig(StrictModel):
    """The lamp: a point light at ``position_m`` in the camera frame (x right, y down, z
    forward, origin at the lens). Its spectrum inside each filter's passband is unknown: one
    power per filter is fitted. With ``fit_position`` the position is fitted too (where the
    notes do not say where the lamp stood), starting from ``position_m``."""

    position_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    fit_position: bool = True


class FitConfig(StrictModel):
    """What the twin may fit, and on which frames.

    ``patches``: the patches whose frames fit the lamp (its power per filter and, where asked,
    its position), at one exposure per filter (the longest at which most of their channel means
    lie in ``[min_dn, max_dn]``); ``dark_exposures_ms``: the dark frames that fit the dark
    current and its spread. Everything else is evaluated, never fitted.
    """

    patches: tuple[str, ...] = Field(min_length=1)
    dark_exposures_ms: tuple[int, ...] = Field(min_length=1)
    min_dn: Positive = 10.0
    max_dn: Positive = 240.0


class BenchConfig(StrictModel):
    """One real bench (see the module docstring)."""

    name: str
    data: str
    mapping: str
    camera: str
    focal_length_mm: Positive
    reduction: ReductionConfig
    chart: ChartConfig
    filters: FiltersConfig
    lamp: LampConfig = LampConfig()
    fit: FitConfig

    @model_validator(mode="after")
    def _consistent(self) -> BenchConfig:
        unknown = [name for name in self.fit.patches if name not in self.chart.patches]
        if unknown:
            raise ValueError(f"fit.patches: {unknown} are not among chart.patches")
        if self.fit.min_dn >= self.fit.max_dn:
            raise ValueError("fit: expected min_dn below max_dn")
        return self

    def data_folder(self) -> Path:
        """The folder of the bench's frames and measurements: an absolute path, or a path inside
        spectwin's measured data (``recon/data``); :func:`load_bench` makes a path relative to
        the bench file absolute."""
        path = Path(self.data)
        if path.is_absolute():
            return path
        try:
            return data_path(path)
        except MissingDataError as error:
            raise InputError(
                f"bench {self.name}: data folder {self.data} is neither beside the bench file nor "
                "in spectwin's measured data"
            ) from error

    def file(self, relative: str) -> Path:
        """A file of the bench's data folder."""
        return self.data_folder() / relative

    def require_files(self) -> None:
        """Raise one line naming the first file of the bench that is missing."""
        folder = self.data_folder()
        if not folder.is_dir():
            raise InputError(f"bench {self.name}: data folder {folder} does not exist")
        for what, relative in (
            ("chart.labels", self.chart.labels),
            ("chart.spectra", self.chart.spectra),
            ("filters.spectra", self.filters.spectra),
        ):
            if not self.file(relative).is_file():
                raise InputError(f"bench {self.name}: {what} {self.file(relative)} does not exist")


def available_benches() -> list[str]:
    """Names of the bench files in ``scenes/benches`` (without ``.yaml``)."""
    return scene_names(BENCH_DIR)


def load_bench(name_or_path: str | Path) -> BenchConfig:
    """Load a bench by name in ``scenes/benches`` (e.g. ``"llanos2019"``) or by path."""
    path = resolve_scene_file(name_or_path, BENCH_DIR, "bench")
    bench = validate_document(BenchConfig, read_yaml_mapping(path), path)
    beside = path.parent / bench.data
    if not Path(bench.data).is_absolute() and beside.is_dir():
        bench = bench.model_copy(update={"data": str(beside.resolve())})
    return bench
