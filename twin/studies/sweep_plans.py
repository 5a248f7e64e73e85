"""The plans of sweep design points and the measures they report, by kind of rig.

A plan holds the capture and processing settings of a point (the ``plan.`` parameters of a sweep
file); whether the rig can take them is checked by the kind's point module
(:func:`twin.studies.sweep_gonio.check_gonio_point`,
:func:`twin.studies.sweep_dome.check_dome_point`) before a sweep runs.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, field_validator

from recon.dome.processing import TARGET_RELATIVE_NOISE
from twin.rigs.yaml_config import StrictModel

__all__ = ["DOME_MEASURES", "GONIO_MEASURES", "SHARED_MEASURES", "DomePlan", "GonioPlan"]

SHARED_MEASURES = {
    "capture_time_h": "capture time of the measurement run, timing model (h)",
    "storage_mb": "capture and BTF stores on disk (MB)",
    "point_s": "wall time of the point on this machine (s)",
}
"""The measures of every design point, whatever its rig, with their units."""


GONIO_MEASURES = {
    "error_pct": "held-out pairs, mean Eq. 6.8 over the chart fields (%)",
    "error_matte_pct": "held-out pairs, matte fields, mean Eq. 6.8 (%)",
    "error_glossy_pct": "held-out pairs, glossy fields, mean Eq. 6.8 (%)",
    "delta_e94": "held-out pairs, mean Delta E94 over the chart fields",
    "delta_e94_matte": "held-out pairs, matte fields, mean Delta E94",
    "exposure_per_pair_s": "sum of the band exposures of one direction pair (s)",
    "exposure_total_h": "exposure time of all pairs of the run (h)",
    "pairs": "direction pairs measured",
    "pairs_registered": "direction pairs registered and in the BTF",
    **SHARED_MEASURES,
}
"""The measures of a gonioreflectometer design point, with their units."""

DOME_MEASURES = {
    "error_pct": "BTF vs truth, mean Eq. 6.8 (%)",
    "delta_e94": "BTF vs truth, mean Delta E94",
    "per_texel_error_pct": "BTF vs truth, per-texel Eq. 6.8 (%)",
    "spectral_exposure_h": "exposure of the spectral camera's band frames in the run (h)",
    "rgb_exposure_h": "exposure of each RGB camera's HDR sets in the run (h)",
    "pairs": "direction pairs in the BTF",
    **SHARED_MEASURES,
}
"""The measures of a dome design point, with their units."""


class GonioPlan(StrictModel):
    """The capture and processing settings of a point (the ``plan.`` parameters).

    Attributes
    ----------
    rings
        The direction sampling: ``[polar_deg, count]`` rings of directions, every reachable
        light x view combination measured (thesis 4.1.1; the twin's reduced sampling is
        ``[[0, 1], [30, 4], [60, 8]]``).
    pixels
        Pixels across the camera's 20 cm field.
    texels
        Texels across the BTF's texture.
    spp
        Samples per pixel of the renders (default: the capture's, 16 stratified).
    """

    rings: Annotated[list[tuple[float, int]], Field(min_length=1)] = [(0.0, 1), (30.0, 4)]
    pixels: Annotated[int, Field(ge=32, le=4096)] = 128
    texels: Annotated[int, Field(ge=16, le=512)] = 32
    spp: Annotated[int, Field(ge=1, le=65536)] | None = None

    @field_validator("rings")
    @classmethod
    def _rings(cls, rings: list[tuple[float, int]]) -> list[tuple[float, int]]:
        for polar, count in rings:
            if not 0 <= polar < 85 or count < 1 or (polar == 0 and count != 1):
                raise ValueError(
                    f"expected [polar_deg in [0, 85), count >= 1] rings (one direction at 0), "
                    f"got [{polar}, {count}]"
                )
        return rings


class DomePlan(StrictModel):
    """The capture and processing settings of a dome point (the ``plan.`` parameters).

    Attributes
    ----------
    stage_positions, leds, rgb_cameras, texels, spp
        The capture's size (:class:`twin.dome.programs.DomeCaptureSize`; spp by default the
        capture's).
    dark_frames
        Dark frames per spectral exposure time in the calibration (thesis 10.3: 200).
    longest_band_s
        Exposure of the spectral camera's weakest band (s); sets :math:`t_{base}` (10.4).
        Default: the capture's (:data:`twin.dome.setup.THESIS_LONGEST_BAND_S`, 5.48 s).
    schedule_images
        RGB images the 30 bands are packed into, each band once; ``None``: the thesis's 10
        images with the noisiest bands twice.
    target_relative_noise
        What the band images' filters leave (the filter size, Figure 10.5).
    """

    stage_positions: Annotated[int, Field(ge=1, le=24)] = 1
    leds: Annotated[int, Field(ge=1, le=198)] = 10
    rgb_cameras: Annotated[int, Field(ge=1, le=11)] = 3
    texels: Annotated[int, Field(ge=8, le=512)] = 32
    spp: Annotated[int, Field(ge=1, le=65536)] | None = None
    dark_frames: Annotated[int, Field(ge=1, le=10000)] = 16
    longest_band_s: Annotated[float, Field(gt=0, le=600)] | None = None
    schedule_images: Annotated[int, Field(ge=1, le=198)] | None = None
    target_relative_noise: Annotated[float, Field(gt=0, lt=1)] = TARGET_RELATIVE_NOISE
