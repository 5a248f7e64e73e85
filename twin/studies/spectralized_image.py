"""``spectwin spectralize``: a user's image spectralized from spot spectra, written out.

The reconstruction is ``recon.image_spectralization.spectralize_image`` (thesis Eq. 6.10); this
module writes what a user needs from it into one folder:

- ``spectra.exr``: the spectral OpenEXR of Fichet et al. (2021) (``recon.spectral_exr``),
  reflective (``T.<nm>`` channels) or emissive (``S0.<nm>``) as the spots' unit says;
- ``spectra.hdr`` and ``spectra.raw``: the same cube as ENVI float32 (``recon.envi``), band
  sequential or band interleaved by line, wavelengths in nanometres;
- ``preview.png``: an sRGB preview (a reflectance under CIE D65; a radiance as it is);
- ``spots.json``: per spot its pixel and its error (Eq. 6.8, %) predicted while held out in the
  cross-validation, and the summary (prior, cross-validated errors per prior, gains, timings).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

import colour
import numpy as np
from skimage import io

from recon.envi import write_envi
from recon.image_spectralization.run import ImageSpectralization
from recon.image_spectralization.spots import SpotSpectra
from recon.preview import spectral_to_srgb
from recon.spectra import SampledSpectra, from_colour, resample
from recon.spectral_exr import write_spectral_exr
from twin.output_format import dumps

__all__ = ["OUTPUTS", "spot_error_summary", "write_spectralized_image"]

OUTPUTS = ("spectra.exr", "spectra.hdr", "spectra.raw", "preview.png", "spots.json")


def spot_error_summary(errors: np.ndarray | None) -> dict[str, float]:
    """Mean, median, 90th percentile and largest held-out error of the spots (Eq. 6.8, %),
    over those that have one (a large image's spots outside its cross-validation window have
    none, NaN)."""
    if errors is None:
        return {}
    held_out = errors[np.isfinite(errors)]
    return {
        "spot_error_mean_pct": float(np.mean(held_out)),
        "spot_error_median_pct": float(np.median(held_out)),
        "spot_error_p90_pct": float(np.percentile(held_out, 90)),
        "spot_error_max_pct": float(np.max(held_out)),
    }


def _preview(result: ImageSpectralization, radiance: bool) -> np.ndarray:
    if radiance:
        return spectral_to_srgb(result.cube, result.grid)
    light = resample(from_colour(colour.SDS_ILLUMINANTS["D65"]), result.grid, out_of_range="clamp")
    white = SampledSpectra(result.grid, light.values)
    return spectral_to_srgb(result.cube * light.values, result.grid, white=white, percentile=99.5)


def write_spectralized_image(
    result: ImageSpectralization,
    spots: SpotSpectra,
    out_dir: Path,
    *,
    inputs: dict[str, Any],
    radiance: bool = False,
    interleave: Literal["bsq", "bil"] = "bsq",
) -> dict[str, Any]:
    """Write the outputs of the module description into ``out_dir``; return the summary.

    Parameters
    ----------
    result
        The spectralization.
    spots
        The spots it was made from (their pixels are written with their errors).
    out_dir
        The folder (made if missing).
    inputs
        What was given (image, spots, response, ...), recorded as it is in the summary.
    radiance
        The spots are radiance (emissive EXR, preview as it is), not reflectance.
    interleave
        Of the ENVI raster.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    kind: Literal["emissive", "reflective"] = "emissive" if radiance else "reflective"
    write_spectral_exr(
        out_dir / "spectra.exr",
        result.cube,
        result.grid,
        kind=kind,
        attributes={"spectwinPrior": result.prior, "spectwinSource": str(inputs["image"])},
    )
    write_envi(
        out_dir / "spectra",
        result.cube,
        result.grid,
        interleave=interleave,
        description=f"spectwin spectralize of {inputs['image']} ({kind}, prior {result.prior})",
    )
    io.imsave(out_dir / "preview.png", _preview(result, radiance), check_contrast=False)
    height, width, bands = result.cube.shape
    summary: dict[str, Any] = {
        **inputs,
        "image_px": [height, width],
        "bands": bands,
        "grid_nm": [float(w) for w in result.grid.wavelengths_nm],
        "spots": int(spots.xy.shape[0]),
        "appearance": result.appearance,
        "appearance_cross_validated_error_pct": result.appearance_errors,
        "prior": result.prior,
        "prior_chosen_by": "cross-validation" if result.cross_validated else "fixed (--fast)",
        "kriging_weight": result.kriging_weight,
        "cross_validated_error_pct": result.held_out_errors,
        **spot_error_summary(result.spot_errors),
        "channel_gains": dict(zip("RGB", result.gains.tolist(), strict=True)),
        "spot_fit_residual_pct": dict(zip("RGB", result.fit_residual_pct.tolist(), strict=True)),
        "seconds": result.timings_s,
        "notes": list(result.notes),
        "outputs": list(OUTPUTS),
    }
    per_spot = [
        {
            "x": int(x),
            "y": int(y),
            "cross_validated_error_pct": (
                None if error is None or not np.isfinite(error) else float(error)
            ),
        }
        for (x, y), error in zip(
            spots.xy,
            result.spot_errors if result.spot_errors is not None else [None] * len(spots.xy),
            strict=True,
        )
    ]
    (out_dir / "spots.json").write_text(dumps({"summary": summary, "spots": per_spot}))
    return summary
