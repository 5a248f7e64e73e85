"""The capture store's metadata as models: what its attributes hold, typed and versioned.

A capture store (:mod:`hwbridge.store`) records its plan, its rig and its session in the root
group's attributes (JSON). Every reader reads them through these frozen pydantic models, which
refuse unknown fields, so that a field is written and read under one name and type:

- :class:`CaptureAttrs`: the attributes, ``schema_version`` first; a store of another schema
  version is refused on opening (:func:`refuse_other_version`);
- :class:`PlanStep`: one step of the plan (a frame), as :mod:`hwbridge.plans` builds it;
- the ``rig`` attribute, one model per kind of rig, each a :class:`RigAttrs` (the rig's name and
  the program that captured): :class:`GonioRigAttrs` (the gonioreflectometer),
  :class:`DomeRigAttrs` (the LED dome; the layout of its store is in
  :mod:`hwbridge.dome_layout`) and :class:`ReplayRigAttrs` (a real capture replayed from its
  files, :mod:`hwbridge.replay`).

ARCHITECTURE.md ("Stores") shows these models as tables, generated from the fields'
descriptions.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar, Literal, TypeVar, get_args

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from hwbridge.errors import InputError, Remedy

__all__ = [
    "FRAME_KINDS",
    "NO_LIGHT",
    "NO_VIEW",
    "SCHEMA_VERSION",
    "CaptureAttrs",
    "CheckerboardTarget",
    "DomeCamera",
    "DomeChart",
    "DomeGeometry",
    "DomeHolder",
    "DomeRigAttrs",
    "FrameKind",
    "GonioRigAttrs",
    "PlanStep",
    "ReplayRigAttrs",
    "RigAttrs",
    "Spectrum",
    "StoreModel",
    "parse",
    "recorded",
    "refuse_other_version",
]

SCHEMA_VERSION = 3
"""The version of the capture store's attributes that this code writes and reads (2: the store
has an identity, seals its settings and frames, ``hwbridge.integrity.Seal``)."""

NO_LIGHT = -1
"""``light_id`` of frames without light (dark frames)."""

NO_VIEW = -1
"""``view_id`` of frames taken without moving to a view (dark frames; the rig's home)."""

FrameKind = Literal["dark", "white", "chart", "sample", "oecf", "alignment", "geometric"]
FRAME_KINDS: tuple[str, ...] = get_args(FrameKind)
"""The kinds of frame a capture store holds."""


class StoreModel(BaseModel):
    """Base of the stores' metadata models: frozen, unknown fields refused."""

    model_config = ConfigDict(frozen=True, extra="forbid")


Model = TypeVar("Model", bound=BaseModel)
Value = TypeVar("Value")


def parse(model: type[Model], data: object, where: str) -> Model:
    """``data`` validated as ``model``, in one line on a mismatch.

    Parameters
    ----------
    model
        The model.
    data
        The attributes as stored (JSON).
    where
        The store and attribute, for the message.

    Returns
    -------
    Model
        The validated model.

    Raises
    ------
    InputError
        Naming ``where``, the first field that does not fit and what it expected.

    Examples
    --------
    >>> parse(Spectrum, {"wavelengths_nm": [400.0], "values": [0.9]}, "rig").values
    (0.9,)
    """
    try:
        return model.model_validate(data)
    except ValidationError as error:
        first = error.errors()[0]
        location = ".".join(str(part) for part in first["loc"])
        field = f"{location}: " if location else ""
        more = f" (and {error.error_count() - 1} more)" if error.error_count() > 1 else ""
        message = first["msg"].removeprefix("Value error, ")
        raise InputError(f"{where}: {field}{message}{more}") from None


def recorded(value: Value | None, what: str) -> Value:
    """``value``, a field that is optional in its model but that the store at hand records (a
    field of :attr:`RigAttrs.program_fields` for its program, or one that processing sets).

    Parameters
    ----------
    value
        The field's value.
    what
        The store and field, for the message.

    Returns
    -------
    Value
        ``value``, known not to be ``None``.

    Raises
    ------
    InputError
        If ``value`` is ``None``: the store does not record it.

    Examples
    --------
    >>> recorded(64, "rig.sensor_px")
    64
    """
    if value is None:
        raise InputError(f"{what}: not recorded in the store")
    return value


def refuse_other_version(
    path: Path,
    store: str,
    attribute: str,
    found: object,
    expected: int,
    *,
    remedy: Remedy | None = None,
) -> None:
    """Refuse a store whose version is not ``expected``.

    Parameters
    ----------
    path
        The store.
    store
        What it is, for the message (``"a capture store"``).
    attribute
        Its version attribute, in words (``"schema version"``).
    found
        The version it records (``None``: it records none, made before stores recorded it).
    expected
        The version this code reads.
    remedy
        What the user can do about it.

    Raises
    ------
    InputError
        Unless ``found`` is ``expected``: one line naming the store, its version and the
        expected one.
    """
    if found == expected:
        return
    have = "none recorded" if found is None else repr(found)
    raise InputError(
        f"{path}: {store} of {attribute} {have}, expected {expected} (written by another "
        "version of the software)",
        remedy=remedy,
    )


class PlanStep(StoreModel):
    """One step of a capture plan: the frame ``camera`` takes after the rig is set for it.

    The plan builders (:mod:`hwbridge.plans`, :mod:`hwbridge.dome_plans`) write a setting
    only where it applies; an unset ``light_id`` or ``view_id`` reads as :data:`NO_LIGHT`,
    :data:`NO_VIEW`.
    """

    camera: str = Field(description="id of the camera that takes the frame")
    kind: FrameKind = Field(description="frame kind (`FRAME_KINDS`)")
    exposure_s: float = Field(gt=0, description="exposure time")
    light_id: int = Field(
        NO_LIGHT, description="light switched on: lamp position or LED; -1 none, -2 all LEDs"
    )
    view_id: int = Field(
        NO_VIEW, description="view: direction pair or stage position; -1 none (not moved)"
    )
    band_nm: float | None = Field(None, description="band of the tunable filter")
    tilt_deg: float | None = Field(None, description="tilt of the wedge under a geometric target")
    file: str | None = Field(None, description="of a replayed capture: the frame's source file")


Backend = Literal["sim", "real", "replay"]


class CaptureAttrs(StoreModel):
    """The attributes of a capture store's root group."""

    schema_version: int = Field(description="version of these attributes (`SCHEMA_VERSION`)")
    store_id: str = Field(
        min_length=1, description="the store's identity, random, made at creation"
    )
    sealed: dict[str, str] = Field(
        description="digest per setting and array layout that defines the content, at creation"
    )
    rig: dict[str, Any] = Field(
        description="the rig and the program that captured: a `RigAttrs` of the rig's kind"
    )
    backend: Backend = Field(description="`sim`, `real` or `replay`")
    seed: int = Field(ge=0, description="session seed (noise, faults, robot repeatability)")
    software_version: str = Field(description="version of the software that captured")
    plan: tuple[PlanStep, ...] = Field(min_length=1, description="one `PlanStep` per frame")
    complete: bool = Field(description="every step is done")


class RigAttrs(BaseModel):
    """What the ``rig`` attribute of every capture store holds: the kind of rig and the program
    that captured. A kind of rig subclasses it with its own fields, refusing unknown ones;
    :attr:`program_fields` names those that only some programs record and that they must."""

    model_config = ConfigDict(frozen=True, extra="allow")

    program_fields: ClassVar[dict[str, tuple[str, ...]]] = {}

    rig: str = Field(description="the kind of rig (its registry name)")
    program: str = Field(description="the capture program")

    @model_validator(mode="after")
    def _program_fields_set(self) -> RigAttrs:
        missing = [
            name
            for name in self.program_fields.get(self.program, ())
            if getattr(self, name) is None
        ]
        if missing:
            raise ValueError(
                f"program {self.program} records {', '.join(missing)}; they are missing"
            )
        return self

    def stored(self) -> dict[str, Any]:
        """As the store records it (JSON; unset fields left out)."""
        return self.model_dump(mode="json", exclude_none=True)


class Spectrum(StoreModel):
    """A spectrum (or rows of spectra) sampled at ``wavelengths_nm``."""

    wavelengths_nm: tuple[float, ...] = Field(description="sample wavelengths")
    values: tuple[float, ...] | tuple[tuple[float, ...], ...] = Field(
        description="one value per wavelength, or rows of them"
    )


_GONIO_LIT = ("config", "white_reflectance")


class GonioRigAttrs(RigAttrs):
    """The ``rig`` attribute of the gonioreflectometer's captures (``twin.gonio.capture``)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    program_fields: ClassVar[dict[str, tuple[str, ...]]] = {
        "gonio-calibration": _GONIO_LIT,
        "gonio-run": (
            *_GONIO_LIT,
            "sensor_px",
            "material",
            "spp",
            "white_view_id",
            "light_dirs",
            "view_dirs",
            "skipped_pairs",
            "expected_corners_xy",
            "sample_fraction",
        ),
    }

    rig: Literal["gonioreflectometer"] = Field(description="`gonioreflectometer`")
    program: Literal["demo", "gonio-calibration", "gonio-run"] = Field(
        description="`demo`, `gonio-calibration` or `gonio-run`"
    )
    camera: str = Field(description="the camera model (`scenes/cameras`)")
    camera_id: str = Field(description="the camera's id in the store")
    window_px: int = Field(gt=0, description="side of the frames read out")
    lamp: str = Field(description="spectrum of the lamp (`hmi`: flickers)")
    config: dict[str, Any] | None = Field(None, description="the rig model (`scenes/rigs`)")
    white_reflectance: Spectrum | None = Field(
        None, description="the white standard's reflectance factor (its calibration certificate)"
    )
    sensor_px: int | None = Field(None, gt=0, description="pixels across the camera's field")
    material: str | None = Field(None, description="the material on the holder")
    spp: int | None = Field(None, ge=1, description="samples per pixel of the renders")
    rings: tuple[tuple[float, int], ...] | None = Field(
        None, description="(polar angle, directions) per ring of the sampling; unset: given pairs"
    )
    white_view_id: int | None = Field(None, description="`view_id` of the white frames")
    light_dirs: tuple[tuple[float, float, float], ...] | None = Field(
        None, description="light direction per pair (`view_id`), sample frame"
    )
    view_dirs: tuple[tuple[float, float, float], ...] | None = Field(
        None, description="view direction per pair, sample frame"
    )
    skipped_pairs: int | None = Field(None, ge=0, description="pairs of the sampling not reached")
    expected_corners_xy: tuple[tuple[tuple[float, float], ...], ...] | None = Field(
        None, description="per pair the marks' corners in the image, nominal kinematics"
    )
    sample_fraction: float | None = Field(
        None, gt=0, le=1, description="side of the sample over that of the marks' square"
    )


class DomeCamera(StoreModel):
    """One camera of a dome store (OpenCV's conventions: x right, y down, z forward; pixel
    centres at integer coordinates; for the stored window)."""

    role: Literal["rgb", "spectral"] = Field(description="`rgb` or `spectral`")
    definition: str = Field(description="the camera model (`scenes/cameras`)")
    mosaic: Literal["none", "RGGB"] = Field(description="colour filter array of the raw frames")
    arc_index: int | None = Field(None, description="of an RGB camera: its place on the arc")
    bit_depth: int = Field(gt=0, description="bits per raw value")
    position_m: tuple[float, float, float] = Field(description="projection centre, world frame")
    rotation_world_to_camera: tuple[tuple[float, float, float], ...] = Field(
        min_length=3, max_length=3, description="3x3 rotation"
    )
    camera_matrix: tuple[tuple[float, float, float], ...] = Field(
        min_length=3, max_length=3, description="3x3 intrinsics"
    )
    distortion: tuple[float, float, float, float, float] = Field(
        description="OpenCV's five coefficients (zeros: the twin's cameras are pinholes)"
    )
    frame_px: tuple[int, int] = Field(description="rows, columns")
    pixel_pitch_m: float = Field(gt=0, description="pixel pitch at the rig centre")
    marker_corners_xy: dict[str, tuple[tuple[float, float], ...]] = Field(
        description="per stage position used, the marks' four corners as the camera images them"
    )


class DomeHolder(StoreModel):
    """The sample holder's registration print, in the sample frame."""

    registration_corners_m: tuple[tuple[float, float, float], ...] = Field(
        min_length=4,
        max_length=4,
        description="the print's outer corners, in the texture's corner order (0,0) (1,0) (1,1) "
        "(0,1)",
    )
    print_inner_half_m: float = Field(gt=0, description="inner half-size of the print")
    print_outer_half_m: float = Field(gt=0, description="outer half-size of the print")
    opening_half_m: float = Field(gt=0, description="half-size of the opening the material fills")


class CheckerboardTarget(StoreModel):
    """The checkerboard of the geometric calibration."""

    kind: Literal["checkerboard"] = Field(description="`checkerboard`")
    squares: tuple[int, int] = Field(description="squares: columns, rows")
    inner_corners: tuple[int, int] = Field(description="inner corners: columns, rows")
    square_m: float = Field(gt=0, description="side of a square")
    corners_m: tuple[tuple[float, float, float], ...] = Field(
        description="inner corners in the target frame (z = 0), row by row as OpenCV lists them"
    )
    target_to_sample: dict[str, tuple[tuple[float, float, float, float], ...]] = Field(
        description="per `tilt_deg` (as text) the 4x4 pose of the target on its wedge"
    )


class DomeGeometry(StoreModel):
    """The dome in metres, world frame (origin at the sample centre on the stage, z up; the
    sample frame is the world turned about z by the stage angle)."""

    frame: str = Field(description="the frame's definition, in words")
    stage_angles_deg: tuple[float, ...] = Field(description="angle of every stage position")
    led_positions_m: tuple[tuple[float, float, float], ...] = Field(
        description="position of every LED (`light_id`)"
    )
    cameras: dict[str, DomeCamera] = Field(description="every camera by id (`DomeCamera`)")
    holder: DomeHolder = Field(description="the registration print (`DomeHolder`)")
    geometric_target: CheckerboardTarget = Field(
        description="the checkerboard (`CheckerboardTarget`)"
    )


class DomeChart(StoreModel):
    """A colour chart the dome's RGB cameras photograph, on the holder at stage position 0."""

    kind: FrameKind = Field(description="the `kind` of the frames that show it")
    name: str = Field(description="the chart and the source of its reflectances")
    columns: int = Field(gt=0, description="fields per row, in reading order")
    field_centres_m: tuple[tuple[float, float, float], ...] = Field(
        min_length=1, description="centre of every field, sample frame, reading order"
    )
    field_half_m: float = Field(gt=0, description="half the side of a field's coloured square")
    reflectance: Spectrum = Field(
        description="every field's reflectance factor (rows, reading order), from the chart's "
        "certificate"
    )


class DomeRigAttrs(RigAttrs):
    """The ``rig`` attribute of the LED dome's captures (``twin.dome.programs``)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    program_fields: ClassVar[dict[str, tuple[str, ...]]] = {
        "dome-calibration": ("dark_frames", "charts", "spectrometer_wavelengths_nm"),
        "dome-run": ("material", "sample_size_m", "stage_positions"),
    }

    rig: Literal["dome"] = Field(description="`dome`")
    program: Literal["dome-calibration", "dome-run"] = Field(
        description="`dome-calibration` or `dome-run`"
    )
    material: str | None = Field(None, description="of a run: the material on the holder")
    sample_size_m: float | None = Field(
        None, gt=0, description="of a run: side of the material's square, centred on the plate"
    )
    stage_positions: int | None = Field(None, ge=1, description="of a run: stage positions used")
    dark_frames: int | None = Field(
        None, ge=1, description="of a calibration: dark frames per spectral exposure time"
    )
    texels: int = Field(gt=0, description="texels across a nominal 4 cm sample")
    spp: int = Field(ge=1, description="samples per pixel of the renders")
    led_renders: Literal["pose", "single"] = Field(
        description="LEDs of a stage position rendered in passes (`pose`) or one by one"
    )
    pixels: int = Field(gt=0, description="pixels across the 0.2 m field")
    window_px: int = Field(gt=0, description="side of the frames read out")
    leds: int = Field(ge=1, description="LEDs used")
    rgb_cameras: int = Field(ge=1, description="RGB cameras used")
    rgb_exposures_s: tuple[float, ...] = Field(description="the RGB cameras' HDR set")
    bands_nm: tuple[float, ...] = Field(description="the spectral camera's bands")
    band_exposures_s: tuple[float, ...] = Field(description="exposure per band")
    band_schedule: tuple[tuple[int, ...], ...] = Field(
        description="per schedule image, the bands (indices) exposed meanwhile; LED k of the run "
        "gets image k mod length"
    )
    calibration_led: int = Field(
        ge=0, description="LED of the response series and the band-wise white frames"
    )
    led_current_ma: float = Field(gt=0, description="drive current of every lit frame")
    white_reflectance: Spectrum = Field(
        description="the white standard's reflectance factor, from its certificate"
    )
    charts: tuple[DomeChart, ...] | None = Field(
        None, description="of a calibration: the charts the RGB cameras photograph (`DomeChart`)"
    )
    spectrometer_wavelengths_nm: tuple[float, ...] | None = Field(
        None,
        description="of a calibration: the wavelengths of the spectrometer's readings of the "
        "white standard (`lamp_monitor`, one per lit frame)",
    )
    geometry: DomeGeometry = Field(description="cameras, LEDs, stage, targets (`DomeGeometry`)")


class ReplayRigAttrs(RigAttrs):
    """The ``rig`` attribute of a replayed real capture (:mod:`hwbridge.replay`): the mapping's
    description of the rig."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    rig: Literal["replay"] = Field(description="`replay`")
    program: str = Field(description="the mapping's name")
    name: str | None = Field(None, description="what the capture was")
    camera: str | None = Field(None, description="the camera and lens")
    bit_depth: int | None = Field(None, gt=0, description="bits per raw value")
    note: str | None = Field(None, description="anything else about the frames")
