"""Rig definitions: the pydantic schema of ``scenes/rigs/*.yaml`` and its loader.

Two kinds of rig, told apart by the ``rig`` key: the spectral gonioreflectometer (thesis chapter
3 and 4.1.1) and the LED dome with one spectral camera (thesis 10.2). A new rig is a new or edited
YAML file; unknown keys, missing keys and out-of-range values are rejected with the field named.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal, overload

from pydantic import Field, model_validator

from recon.errors import InputError
from twin.rigs.camera_config import available_cameras
from twin.rigs.yaml_config import (
    NonNegative,
    Positive,
    StrictModel,
    read_yaml_mapping,
    resolve_scene_file,
    scene_folder,
    scene_names,
    validate_document,
)

__all__ = ["RIG_DIR", "DomeConfig", "GonioConfig", "available_rigs", "load_rig"]

RIG_DIR = scene_folder("rigs")


class RailConfig(StrictModel):
    """Half-circle rail in the horizontal plane through the sample, camera looking at its centre."""

    radius_m: Positive
    azimuth_range_deg: tuple[float, float]
    speed_deg_per_s: Positive
    start_stop_s: NonNegative

    @model_validator(mode="after")
    def _ordered(self) -> RailConfig:
        low, high = self.azimuth_range_deg
        if not low < high <= low + 360:
            raise ValueError(f"azimuth_range_deg: expected low < high, got {low}, {high}")
        return self


class LampPlacement(StrictModel):
    """One lamp position (thesis 4.1.1: the lamp is moved by hand between two runs)."""

    id: str
    spectrum: Literal["hmi", "qth"]
    azimuth_deg: float
    elevation_deg: Annotated[float, Field(ge=-90, le=90)] = 0.0
    distance_m: Positive


class GonioCameraConfig(StrictModel):
    definition: str
    filter: Literal["VS-07", "VS-10", "VS-20"]
    field_of_view_m: Positive

    @model_validator(mode="after")
    def _known_camera(self) -> GonioCameraConfig:
        if self.definition not in available_cameras():
            raise ValueError(f"definition: expected one of {available_cameras()}")
        return self


class RobotConfig(StrictModel):
    """Sample-holding robot: orientation as yaw (base), tilt (normal from +z) and roll (wrist)."""

    model: str
    tilt_range_deg: tuple[
        Annotated[float, Field(ge=0, le=180)], Annotated[float, Field(ge=0, le=180)]
    ]
    joint_speed_deg_per_s: Positive
    start_stop_s: NonNegative
    repeatability_deg: NonNegative
    repeatability_mm: NonNegative


class GonioTimingConfig(StrictModel):
    """Per direction pair: settle after moving; per image: filter switch and download (4.1.1)."""

    settle_s: NonNegative
    switch_and_download_s: NonNegative


class ExposureConfig(StrictModel):
    """Band exposure times equalized on the white standard (thesis Eq. 3.4)."""

    white_fill: Annotated[float, Field(gt=0, le=1)]
    round_to_flicker_period: bool = True


class GonioConfig(StrictModel):
    """The spectral gonioreflectometer."""

    rig: Literal["gonioreflectometer"]
    name: str
    rail: RailConfig
    lamps: Annotated[list[LampPlacement], Field(min_length=1)]
    minimum_lamp_camera_separation_deg: Positive
    camera: GonioCameraConfig
    robot: RobotConfig
    sampling: Literal["sattler81"]
    timing: GonioTimingConfig
    exposure: ExposureConfig


class DomeRing(StrictModel):
    """A ring of LEDs at one polar angle, ``count`` azimuths starting at ``azimuth_offset_deg``."""

    polar_deg: Annotated[float, Field(ge=0, lt=90)]
    count: Annotated[int, Field(ge=1)]
    azimuth_offset_deg: float = 0.0


class DomeTimingConfig(StrictModel):
    """What the dome spends besides exposing (the exposures come from the capture plans,
    :mod:`hwbridge.dome_plans`): turning the stage to the next position, switching LEDs, and per
    frame the RGB camera's read-out and the spectral camera's filter switch and download."""

    rotation_s: NonNegative
    led_switch_s: NonNegative
    rgb_frame_overhead_s: NonNegative
    spectral_frame_overhead_s: NonNegative


class DomeConfig(StrictModel):
    """The LED dome with RGB cameras on an arc and one spectral camera (thesis 10.2)."""

    rig: Literal["dome"]
    name: str
    radius_m: Positive
    led_rings: Annotated[list[DomeRing], Field(min_length=1)]
    led_spectrum: Literal["phosphor_white"]
    rgb_camera: str
    rgb_camera_polar_deg: Annotated[list[Annotated[float, Field(ge=0, lt=90)]], Field(min_length=1)]
    rgb_camera_azimuth_deg: float
    spectral_camera: GonioCameraConfig
    spectral_camera_polar_deg: Annotated[float, Field(ge=0, lt=90)]
    spectral_camera_azimuth_offset_deg: float
    rotation_stage_positions: Annotated[int, Field(ge=1)]
    rotation_stage_step_deg: Positive
    led_count: Annotated[int, Field(ge=1)]
    timing: DomeTimingConfig

    @model_validator(mode="after")
    def _led_count(self) -> DomeConfig:
        total = sum(ring.count for ring in self.led_rings)
        if total != self.led_count:
            raise ValueError(f"led_count: the rings hold {total} LEDs, not {self.led_count}")
        if self.rgb_camera not in available_cameras():
            raise ValueError(f"rgb_camera: expected one of {available_cameras()}")
        return self


def available_rigs() -> list[str]:
    """Names of the rig files in ``scenes/rigs`` (without ``.yaml``)."""
    return scene_names(RIG_DIR)


@overload
def load_rig(name_or_path: Literal["gonio"]) -> GonioConfig: ...
@overload
def load_rig(name_or_path: Literal["dome"]) -> DomeConfig: ...
@overload
def load_rig(name_or_path: str | Path) -> GonioConfig | DomeConfig: ...
def load_rig(name_or_path: str | Path) -> GonioConfig | DomeConfig:
    """Load a rig by file name in ``scenes/rigs`` (``"gonio"``, ``"dome"``) or by path."""
    path = resolve_scene_file(name_or_path, RIG_DIR, "rig")
    document = read_yaml_mapping(path)
    kinds: dict[str, type[GonioConfig] | type[DomeConfig]] = {
        "gonioreflectometer": GonioConfig,
        "dome": DomeConfig,
    }
    if document.get("rig") not in kinds:
        raise InputError(f"{path}: rig: expected 'gonioreflectometer' or 'dome'")
    config = validate_document(kinds[document["rig"]], document, path)
    assert isinstance(config, GonioConfig | DomeConfig)
    return config
