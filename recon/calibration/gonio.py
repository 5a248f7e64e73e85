"""Calibration of the spectral gonioreflectometer from a calibration capture (thesis 3.3).

From a capture store holding dark frames, an exposure series of a static scene (``oecf``) and
photographs of the white standard through every band (``white``):

1. dark frames averaged per exposure time
(:func:`recon.radiometric.dark_frames.average_dark_frames`);
2. the inverse response :math:`\\hat f^{-1}` by Robertson et al. (2003) on the raw exposure
   series (:func:`recon.radiometric.response_curve.robertson`); the curve absorbs the ADC offset,
   so dark
   signal is removed in the linear domain, :math:`\\hat f^{-1}(p) - \\hat f^{-1}(d)`, which is the
   thesis's :math:`\\hat f^{-1}(p - d)` for a camera whose dark electrons pass the same response
   as the photo-electrons;
3. :math:`F_\\lambda` of Eq. 3.3 per unit lamp, i.e. :math:`F'_\\lambda` (the lamp spectrum
   cancels, Eq. 3.6), from the white standard's frames and its certified reflectance stored with
   the capture: the one spectrum calibration takes from the capture's rig attribute; the
   filter's passbands, the lamp's spectrum and the camera's quantum efficiency are in
   :math:`F'_\\lambda`, measured together;
4. the exposure plan of Eq. 3.4, :math:`t_\\lambda = t_{base} F'_\\lambda`, with :math:`t_{base}`
   bringing the white standard to ``white_fill`` of the camera's range, rounded up to multiples
   of 1/15 s for the HMI lamp (section 3.2.2).

The result, :class:`GonioCalibration`, is a small JSON document (:meth:`GonioCalibration.save`) that
:mod:`recon.btf.processing` and the measurement run use.

References
----------
- The thesis, section 3.3, Eq. 3.3-3.6.
- Robertson, M. A., Borman, S., & Stevenson, R. L. (2003). Estimation-theoretic approach to
  dynamic range enhancement using multiple exposures. Journal of Electronic Imaging, 12(2),
  219-228. doi:10.1117/1.1557695
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hwbridge.schema import GonioRigAttrs
from hwbridge.store import CaptureStore
from recon.calibration.capture_io import select_frames
from recon.calibration.spectral import HMI_FLICKER_PERIOD_S, plan_exposures, run_white_factors
from recon.errors import InputError, Remedy
from recon.radiometric.dark_frames import average_dark_frames, dark_frames_at
from recon.radiometric.hdr import interpolate_curve
from recon.radiometric.response_curve import robertson
from recon.spectra import WavelengthGrid

__all__ = [
    "GonioCalibration",
    "DarkModel",
    "calibrate_gonio",
    "dark_model",
    "extend_curve",
    "lamp_rounding_s",
    "store_white_factors",
    "white_reflectance",
]

_FORMAT = "spectwin-gonio-calibration"
_ARRAY_KEYS = ("bands_nm", "inverse_response", "run_factors", "planned_exposure_s")
_KEYS = (*_ARRAY_KEYS, "base_s", "round_to_s", "white_fill", "source")


@dataclass(frozen=True)
class DarkModel:
    """Mean dark frames per exposure time and the linear-domain dark subtraction."""

    exposure_s: np.ndarray
    mean_frames: np.ndarray

    def linear_signal(
        self, frames: np.ndarray, exposure_s: np.ndarray, inverse_response: np.ndarray
    ) -> np.ndarray:
        """:math:`\\hat f^{-1}(p) - \\hat f^{-1}(d_{x,t})` for frames ``(n, H, W)`` taken at
        ``exposure_s`` ``(n,)`` (dark frames interpolated linearly in time, thesis 3.3)."""
        dark = dark_frames_at(np.asarray(exposure_s), self.exposure_s, self.mean_frames)
        return interpolate_curve(inverse_response, frames) - interpolate_curve(
            inverse_response, dark
        )


def dark_model(store: CaptureStore, camera: str) -> DarkModel:
    """Average the store's dark frames per exposure time."""
    darks = select_frames(store, camera, kind="dark")
    times, means = average_dark_frames(darks.frames, darks.exposure_s)
    return DarkModel(times, means)


def extend_curve(curve: np.ndarray, *, fit_levels: int = 64, trim_levels: int = 0) -> np.ndarray:
    """Fill the NaN ends of an inverse response (levels never observed) by straight lines fitted
    to the ``fit_levels`` outermost observed levels, so dark frames and rare values just
    outside the observed range still linearize; ``trim_levels`` observed levels at each end
    are replaced too (ends that few, noise-selected samples reached)."""
    curve = np.asarray(curve, np.float64).copy()
    observed = np.flatnonzero(np.isfinite(curve))
    if trim_levels:
        curve[observed[:trim_levels]] = np.nan
        curve[observed[-trim_levels:]] = np.nan
        observed = observed[trim_levels:-trim_levels]
    if observed.size < 2 * fit_levels:
        raise InputError(
            f"inverse_response: only {observed.size} levels observed; the exposure series must "
            "span more of the camera's range"
        )
    levels = np.arange(curve.size)
    for side in (observed[:fit_levels], observed[-fit_levels:]):
        slope, intercept = np.polyfit(side, curve[side], 1)
        outside = (levels < side[0]) if side[0] == observed[0] else (levels > side[-1])
        curve[outside] = slope * levels[outside] + intercept
    return curve


def white_reflectance(rig: GonioRigAttrs, bands_nm: np.ndarray) -> np.ndarray:
    """The white standard's reflectance :math:`W_\\lambda` from its calibration certificate
    (stored with the capture) at the band centres."""
    sheet = rig.white_reflectance
    if sheet is None:
        raise InputError(
            f"capture of program {rig.program}: records no white_reflectance (the white "
            "standard's certified reflectance)"
        )
    return np.interp(bands_nm, sheet.wavelengths_nm, sheet.values)


@dataclass(frozen=True)
class GonioCalibration:
    """Calibration of the camera + filter + lamp (thesis 3.3).

    Attributes
    ----------
    bands_nm
        ``(K,)`` band centres.
    inverse_response
        ``(levels,)`` :math:`\\hat f^{-1}` per raw value, 1 at Robertson's reference level.
    run_factors
        ``(K,)`` :math:`F'_\\lambda` (Eq. 3.3 per unit lamp): BRDF per unit linear signal per s.
    planned_exposure_s
        ``(K,)`` :math:`t_\\lambda` of Eq. 3.4.
    base_s
        :math:`t_{base}`.
    round_to_s
        Rounding period of the plan (1/15 s for the HMI lamp) or ``None``.
    white_fill
        Target fraction of the camera range for the white standard.
    source
        The calibration capture.
    """

    bands_nm: np.ndarray
    inverse_response: np.ndarray
    run_factors: np.ndarray
    planned_exposure_s: np.ndarray
    base_s: float
    round_to_s: float | None
    white_fill: float
    source: str

    @classmethod
    def identity(
        cls, planned_exposure_s: np.ndarray, bands_nm: np.ndarray, round_to_s: float | None
    ) -> GonioCalibration:
        """A calibration that leaves the signal as it is: a straight response over 12 bits and
        unit run factors. For timing and comparing the processing (benchmarks, tests), where
        the values do not matter."""
        return cls(
            bands_nm=np.asarray(bands_nm, np.float64),
            inverse_response=np.arange(4096.0),
            run_factors=np.ones(len(bands_nm)),
            planned_exposure_s=np.asarray(planned_exposure_s, np.float64),
            base_s=1.0,
            round_to_s=round_to_s,
            white_fill=0.7,
            source="identity",
        )

    @property
    def grid(self) -> WavelengthGrid:
        return WavelengthGrid(self.bands_nm)

    def to_json(self) -> dict[str, object]:
        return {
            "format": _FORMAT,
            "bands_nm": self.bands_nm.tolist(),
            "inverse_response": self.inverse_response.tolist(),
            "run_factors": self.run_factors.tolist(),
            "planned_exposure_s": self.planned_exposure_s.tolist(),
            "base_s": self.base_s,
            "round_to_s": self.round_to_s,
            "white_fill": self.white_fill,
            "source": self.source,
        }

    def save(self, path: str | Path) -> None:
        """Write the JSON document atomically (a temporary file renamed into place)."""
        path = Path(path)
        temporary = path.with_name(f".{path.name}.writing")
        temporary.write_text(json.dumps(self.to_json(), indent=1))
        os.replace(temporary, path)

    @classmethod
    def load(cls, path: str | Path) -> GonioCalibration:
        path = Path(path)
        try:
            document = json.loads(path.read_text())
        except UnicodeDecodeError:
            raise InputError(
                f"{path}: not a readable calibration file (binary, not JSON text); expected the "
                "JSON calibration of the gonioreflectometer",
                remedy=Remedy.calibrate,
            ) from None
        except (OSError, json.JSONDecodeError) as error:
            raise InputError(f"{path}: not a readable calibration file ({error})") from None
        if not isinstance(document, dict) or document.get("format") != _FORMAT:
            raise InputError(
                f"{path}: expected a calibration of the gonioreflectometer (format {_FORMAT})",
                remedy=Remedy.calibrate,
            )
        missing = [name for name in _KEYS if name not in document]
        if missing:
            raise InputError(f"{path}: calibration lacks {missing}", remedy=Remedy.calibrate)
        arrays: dict[str, np.ndarray] = {}
        numbers: dict[str, float] = {}
        for name in _KEYS:
            try:
                if name in _ARRAY_KEYS:
                    arrays[name] = np.asarray(document[name], np.float64)
                elif name in ("base_s", "white_fill"):
                    numbers[name] = float(document[name])
            except (TypeError, ValueError):
                raise InputError(
                    f"{path}: {name}: expected numbers, got {str(document[name])[:40]!r}"
                ) from None
        bands = arrays["bands_nm"].size
        if arrays["bands_nm"].shape != (bands,) or any(
            arrays[name].shape != (bands,) for name in ("run_factors", "planned_exposure_s")
        ):
            raise InputError(
                f"{path}: bands_nm, run_factors and planned_exposure_s need one value per band"
            )
        return cls(
            bands_nm=arrays["bands_nm"],
            inverse_response=arrays["inverse_response"],
            run_factors=arrays["run_factors"],
            planned_exposure_s=arrays["planned_exposure_s"],
            base_s=numbers["base_s"],
            white_fill=numbers["white_fill"],
            round_to_s=document["round_to_s"],
            source=str(document["source"]),
        )


def store_white_factors(
    store: CaptureStore, camera: str, darks: DarkModel, inverse_response: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Band centres and :math:`F'_\\lambda` (Eq. 3.3/3.6) from the store's white photographs."""
    white = select_frames(store, camera, kind="white")
    order = np.argsort(white.band_nm)
    bands = white.band_nm[order].astype(np.float64)
    exposure = white.exposure_s[order]
    signal = darks.linear_signal(white.frames[order], exposure, inverse_response)
    reflectance = white_reflectance(store.rig_attrs(GonioRigAttrs), bands)
    return bands, run_white_factors(signal, exposure, reflectance)


def _response_series_curve(store: CaptureStore, camera: str, bit_depth: int) -> np.ndarray:
    """Robertson's inverse response from the ``oecf`` frames; the series of each band is one
    scene, all shot with the same exposure times."""
    oecf = select_frames(store, camera, kind="oecf")
    bands = np.unique(oecf.band_nm)
    series = [np.flatnonzero(oecf.band_nm == band) for band in bands]
    times = oecf.exposure_s[series[0]]
    if any(not np.array_equal(oecf.exposure_s[s], times) for s in series):
        raise InputError(
            f"{store.path}: the response series of bands {bands.tolist()} nm need the same "
            "exposure times"
        )
    frames = np.stack([oecf.frames[s] for s in series], axis=1).astype(np.uint16)
    curve, _ = robertson(frames, times, bit_depth=bit_depth)
    return curve


def lamp_rounding_s(store: CaptureStore) -> float | None:
    """The rounding of the exposure plan for the lamp a capture store records (its rig's
    ``lamp``): whole flicker periods, 1/15 s, for the HMI lamp (thesis 3.2.2); ``None`` for a
    steady QTH lamp."""
    return None if store.rig_attrs(GonioRigAttrs).lamp == "qth" else HMI_FLICKER_PERIOD_S


def calibrate_gonio(
    store: str | Path | CaptureStore,
    *,
    white_fill: float = 0.7,
    round_to_s: float | None = HMI_FLICKER_PERIOD_S,
    bit_depth: int = 12,
    exposure_limits_s: tuple[float, float] = (0.001, 600.0),
) -> GonioCalibration:
    """Calibrate from a calibration capture (see the module docstring).

    Parameters
    ----------
    store
        Capture store with ``dark``, ``oecf`` and ``white`` frames of one camera.
    white_fill
        Fraction of the raw range (above the dark level) the white standard should reach.
    round_to_s
        Round planned times up to multiples of this (HMI: 1/15 s); ``None`` for a steady lamp.
    bit_depth
        The camera's bit depth.
    exposure_limits_s
        The camera's exposure range; a plan outside it raises an error.
    """
    store = store if isinstance(store, CaptureStore) else CaptureStore.open(store)
    if not 0 < white_fill < 1:
        raise InputError(f"white_fill: expected a fraction in (0, 1), got {white_fill}")
    rig = store.rig_attrs(GonioRigAttrs)
    camera = rig.camera_id
    if camera not in {step.camera for step in store.metadata.plan}:
        raise InputError(f"{store.path}: no frames of camera {camera!r}")
    kinds = set(store.index(camera, ["kind"])["kind"].tolist())
    missing = [kind for kind in ("dark", "oecf", "white") if kind not in kinds]
    if missing:
        raise InputError(
            f"{store.path}: no {', '.join(missing)} frames; expected a calibration capture "
            "(program gonio-calibration)",
            remedy=Remedy.capture_gonio_calibration,
        )
    darks = dark_model(store, camera)
    curve = extend_curve(_response_series_curve(store, camera, bit_depth))
    bands, factors = store_white_factors(store, camera, darks, curve)
    reflectance = white_reflectance(rig, bands)
    dark_level = float(np.median(darks.mean_frames[0]))
    top = dark_level + white_fill * (2**bit_depth - 1 - dark_level)
    target = float(interpolate_curve(curve, np.array([top]))[0]) - float(
        interpolate_curve(curve, np.array([dark_level]))[0]
    )
    # White standard's linear signal per second is W / (pi F'); t = target pi F' / W (Eq. 3.4).
    base_s = target * np.pi / float(reflectance.max())
    planned = plan_exposures(
        base_s,
        factors,
        np.ones(bands.size),
        round_to_s=round_to_s,
        limits_s=exposure_limits_s,
    )
    return GonioCalibration(
        bands_nm=bands,
        inverse_response=curve,
        run_factors=factors,
        planned_exposure_s=planned,
        base_s=base_s,
        round_to_s=round_to_s,
        white_fill=white_fill,
        source=str(store.path),
    )
