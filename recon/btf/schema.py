"""The BTF store's metadata as models: what its attributes hold, typed and versioned.

A BTF store (:mod:`recon.btf.store`) records its format, units, material and provenance in the
root group's attributes (JSON), and what processing found as it adds them; its compressed form
(``pca/``) records its own. Every reader reads them through these frozen pydantic models, which
refuse unknown fields:

- :class:`BTFAttrs`: the root attributes; ``format_version`` is the version of these models
  (:data:`BTF_FORMAT_VERSION`): a store of another version is refused on opening;
- :class:`RgbSource`: where a BTF made from RGB images came from, and :class:`SpotSource`:
  the spot spectra it was spectralized from;
- :class:`BTFInputs`: what a processed BTF was made from, as content hashes, so that a resumed
  processing is refused other inputs (:mod:`recon.btf.inputs`);
- :class:`CompressedAttrs`: the attributes of the compressed form.

ARCHITECTURE.md ("Stores") shows these models as tables, generated from the fields'
descriptions.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from hwbridge.schema import StoreModel

__all__ = [
    "BTF_FORMAT",
    "BTF_FORMAT_VERSION",
    "BTF_UNITS",
    "BTFAttrs",
    "BTFInputs",
    "CompressedAttrs",
    "RgbSource",
    "SpotSource",
]

BTF_FORMAT = "spectwin.btf"
"""The ``format`` of every BTF store."""

BTF_FORMAT_VERSION = 3
"""The version of the BTF store's attributes that this code writes and reads (2: the store
records the ``rig`` it was processed from; 3: it has an identity and seals its settings and
pairs, ``hwbridge.integrity.Seal``)."""

BTF_UNITS = "1/sr"
"""Units of every store's reflectance (a BRDF value per texel)."""


class SpotSource(StoreModel):
    """The spot spectra an RGB BTF was spectralized from, not upsampled
    (``recon.btf.rgb_spectralization``; thesis Eq. 6.10, 10.2, section 10.1), or the one 45/0
    reading (``recon.btf.reading_spectralization``; Eq. 6.9)."""

    spots: str = Field(description="the spots CSV or the reading's, as a path")
    n_spots: int = Field(
        ge=1, description="spot spectra, each at one texel of one pair; of a reading, 1"
    )
    spot_pairs: list[int] = Field(description="the pairs that hold spots")
    response: str = Field(description="the camera's response: a shipped camera's name or a CSV")
    design: str = Field(description="how the spots were spread over the pairs")
    prior: str = Field(description="the appearance prior (Eq. 6.3)")
    gains: list[float] = Field(description="gain per channel R, G, B fitted to the spots")
    fit_residual_pct: list[float] = Field(description="relative RMS residual of that fit, %")
    measuring_spot: list[int] | None = Field(
        None,
        description="of one 45/0 reading (`recon.btf.reading_spectralization`): x, y, width, "
        "height of its measuring spot in texels; null: spots at texels",
    )

    def describe(self) -> str:
        """What the BTF was spectralized from, in words."""
        if self.measuring_spot is None:
            return f"{self.n_spots} spot spectra"
        return f"one 45/0 reading at pair {self.spot_pairs[0]}"


class RgbSource(StoreModel):
    """Where a BTF made from an RGB BTF came from (``recon.btf.rgb_import``)."""

    colour_space: Literal["sRGB", "camera RGB"] = Field(
        description="the images' colour space: sRGB, or a camera's (spectralized)"
    )
    layout: str = Field(description="the source's format")
    encoding: str = Field(description="the images' encoding")
    upsampling: str = Field(description="the method of spectral upsampling")
    scale: float = Field(gt=0, description="factor on the upsampled reflectance")
    texel_reduction: int = Field(ge=1, description="source texels per stored texel, per side")
    images: str = Field(description="the source, as a path")
    spectralized: SpotSource | None = Field(
        None, description="of a spectralized import, its spots (`SpotSource`); null: upsampled"
    )


class BTFInputs(StoreModel):
    """What processing made a BTF store from (``recon.btf.inputs``): a resumed processing must
    be given the same."""

    capture_sha256: str = Field(
        description="SHA-256 of the capture store's attributes (plan, rig, seed; `complete` aside)"
    )
    calibration_sha256: str = Field(description="SHA-256 of the calibration file's bytes")
    texels: int = Field(ge=1, description="texels per side of the texture")


class BTFAttrs(StoreModel):
    """The attributes of a BTF store's root group. Processing adds what it found; a dome
    run's processing (``recon.dome``) adds the fields from ``dome_pairs`` on."""

    format: Literal["spectwin.btf"] = Field(description="`spectwin.btf`")
    format_version: int = Field(description="version of these attributes (`BTF_FORMAT_VERSION`)")
    store_id: str = Field(
        min_length=1, description="the store's identity, random, made at creation"
    )
    sealed: dict[str, str] = Field(
        description="digest per setting, direction, band and array layout, at creation"
    )
    units: Literal["1/sr"] = Field(description="units of the reflectance, `1/sr`")
    material: str = Field(min_length=1, description="the material sample")
    rig: str | None = Field(
        description="the kind of rig of the source capture; null: imported from elsewhere"
    )
    source_capture: str | None = Field(description="path of the capture store, or null")
    calibration: dict[str, Any] = Field(description="summary of the calibration applied")
    complete: bool = Field(description="every pair is written")
    inputs: BTFInputs | None = Field(
        None, description="what processing read (`BTFInputs`); null: imported, or not recorded"
    )
    coarse_corner_pairs: tuple[int, ...] | None = Field(
        None, description="pairs registered at the coarse corners (refinement failed)"
    )
    unregistered_pairs: tuple[int, ...] | None = Field(
        None, description="pairs left unwritten: no registration marks found"
    )
    rgb_source: RgbSource | None = Field(None, description="of an RGB import (`RgbSource`)")
    dome_pairs: tuple[tuple[int, int, str], ...] | None = Field(
        None, description="per pair `[view_id, light_id, camera]` of the dome run"
    )
    projected_marks: tuple[str, ...] | None = Field(
        None, description="views (`<camera>_view<k>`) whose marks were projected, not found"
    )
    marks_offset_px: dict[str, float] | None = Field(
        None, description="per view, the marks found off the calibrated camera's projection"
    )
    saturated_texels: int | None = Field(None, ge=0, description="RGB texels saturated")
    band_partner: str | None = Field(
        None, description="the RGB camera whose texture the band data is shifted onto"
    )
    band_shift_texels: dict[str, tuple[float, float]] | None = Field(
        None, description="per stage position, that shift (rows, columns)"
    )


class CompressedAttrs(StoreModel):
    """The attributes of the compressed form (``pca/``, ``recon.btf.compression``)."""

    method: str = Field(description="the compression, in words")
    layout: Literal["per_band", "joint"] = Field(
        description="spectral components per band (`per_band`) or shared by all (`joint`)"
    )
    shape: tuple[int, int, int, int] = Field(description="`(n_pairs, H, W, K)` of the BTF")
    n_brightness_requested: int = Field(ge=1, description="brightness components asked for")
    n_spectral_requested: int = Field(ge=1, description="spectral components asked for")
    brightness_floor: float = Field(
        ge=0, description="texels darker than this times the brightest get the flat spectrum"
    )
    svd: dict[str, Any] = Field(description="the SVD used and its settings")
    compression_ratio: float = Field(gt=0, description="raw bytes over compressed bytes")
    arrays: tuple[str, ...] = Field(description="the arrays of the compressed form")
    complete: bool = Field(description="every array is written")
