"""A linear RGB image from a file: 16-bit PNG or TIFF, floating-point TIFF or OpenEXR.

Spectralization (Eq. 6.10) needs camera values proportional to the light that reached the
sensor. 16-bit and floating-point images are taken as linear. An 8-bit image is almost always
gamma-encoded (sRGB) and is refused unless its encoding is given: ``"srgb"`` decodes the sRGB
curve with colour's ``cctf_decoding`` (an approximation of the camera's own tone curve, said so
in the result's ``note``), ``"linear"`` takes its values as they are. Values are scaled to
[0, 1] by the format's largest value (none for floating point).

References
----------
- IEC 61966-2-1:1999 (sRGB), via ``colour.cctf_decoding``.
- OpenEXR (Academy Software Foundation), via its ``OpenEXR`` Python bindings.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import colour
import numpy as np

from recon.errors import InputError
from recon.image_files import ENCODINGS, Encoding, read_png_or_tiff

__all__ = ["ENCODINGS", "IMAGE_SUFFIXES", "LinearRGB", "read_linear_rgb", "write_rgb_exr"]

IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".exr")


@dataclass(frozen=True, eq=False)
class LinearRGB:
    """``values`` ``(H, W, 3)`` float64 linear camera values of ``source``; ``note``: what was
    done to make them linear beyond reading them, if anything."""

    values: np.ndarray
    source: str
    note: str | None = None


def _read_exr(path: Path) -> np.ndarray:
    import OpenEXR

    try:
        with OpenEXR.File(str(path), separate_channels=True) as exr:
            channels = {name: np.asarray(c.pixels) for name, c in exr.channels().items()}
    except (RuntimeError, OSError) as error:
        raise InputError(f"image {path}: not a readable OpenEXR file ({error})") from None
    if not {"R", "G", "B"} <= set(channels):
        raise InputError(f"image {path}: OpenEXR channels {sorted(channels)}; expected R, G and B")
    return np.stack([channels[name] for name in "RGB"], axis=-1)


def write_rgb_exr(path: str | Path, image: np.ndarray) -> Path:
    """Write ``image`` ``(H, W, 3)`` as a float32 OpenEXR file of channels R, G, B (ZIP
    compressed), as :func:`read_linear_rgb` reads it back."""
    import OpenEXR

    pixels = np.asarray(image, np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    channels = {name: np.ascontiguousarray(pixels[..., i]) for i, name in enumerate("RGB")}
    with OpenEXR.File(header, channels) as exr:
        exr.write(str(path))
    return Path(path)


def read_linear_rgb(path: str | Path, *, encoding: Encoding | None = None) -> LinearRGB:
    """Read an RGB image as linear camera values (module description).

    Parameters
    ----------
    path
        A PNG, TIFF or OpenEXR file of three channels (a PNG's or TIFF's alpha channel, a
        fourth, is refused: it is not a camera value).
    encoding
        Required for 8-bit images: ``"srgb"`` to decode the sRGB curve, ``"linear"`` to take the
        values as they are; for other images ``"srgb"`` decodes too.

    Returns
    -------
    LinearRGB
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"image {path}: no such file")
    suffix = path.suffix.lower()
    if suffix not in IMAGE_SUFFIXES:
        raise InputError(
            f"image {path}: a {suffix or 'suffix-less'} file; expected a linear 16-bit PNG or "
            "TIFF, a floating-point TIFF or an OpenEXR file (JPEG is lossy and gamma-encoded)"
        )
    if encoding is not None and encoding not in ENCODINGS:
        raise InputError(f"encoding {encoding!r}: expected one of {ENCODINGS}")
    image = _read_exr(path) if suffix == ".exr" else read_png_or_tiff(path, "image")
    channels = 1 if image.ndim == 2 else image.shape[2] if image.ndim == 3 else 0
    if channels != 3:
        raise InputError(
            f"image {path}: {channels or 'no'} channel(s) of shape {image.shape}; expected an "
            "RGB image of three channels"
        )
    if image.dtype.kind not in "uf":
        raise InputError(f"image {path}: {image.dtype} values; expected unsigned or float")
    if image.dtype == np.uint8 and encoding is None:
        raise InputError(
            f"image {path}: an 8-bit image, most likely gamma-encoded (sRGB); expected a linear "
            "16-bit or floating-point image, or the image's encoding: 'srgb' to decode it, "
            "'linear' if its values are linear"
        )
    top = float(np.iinfo(image.dtype).max) if image.dtype.kind == "u" else 1.0
    values = image.astype(np.float64) / top
    if not np.all(np.isfinite(values)):
        raise InputError(f"image {path}: holds NaN or infinite values; expected finite ones")
    note = None
    if encoding == "srgb":
        values = np.asarray(colour.cctf_decoding(values, function="sRGB"), np.float64)
        note = "decoded from sRGB (an approximation of the camera's tone curve)"
    elif image.dtype == np.uint8:
        note = "8-bit values taken as linear"
    return LinearRGB(values, str(path), note)
