"""Chart photographs as linear camera signal: 16-bit TIFF and PNG, and camera raw files.

Characterization (thesis 9.4) needs device values proportional to the light: no white balance,
no colour matrix, no tone curve. What is read:

- camera raw files (DNG, CR2, CR3, NEF, ARW, RAF, ORF, RW2, PEF, SRW) through LibRaw
  (``rawpy``): the visible raw mosaic as the sensor wrote it, the file's black level subtracted
  per colour filter, nothing else (no demosaicing: a patch's value is the mean of its sites of
  each colour); the file's white level marks clipped sites.
- TIFF and PNG, 16-bit or floating point, taken as linear: one channel is a raw mosaic (its Bayer
  pattern given), three channels linear RGB (e.g. ``dcraw -4 -T`` or ``-4 -D``).
- 8-bit TIFF and PNG only with their encoding given: almost every 8-bit image is gamma-encoded
  (sRGB), which a linear model of Eq. 9.4 cannot use. ``"srgb"`` decodes the sRGB curve (an
  approximation: cameras apply their own tone curves), ``"linear"`` takes the values as they
  are (e.g. reduced copies of raw frames, such as ``recon/data/real/llanos2019``).

JPEG and other formats are refused: lossy and tone-mapped.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import colour
import numpy as np

from recon.errors import InputError
from recon.image_files import ENCODINGS, Encoding, read_png_or_tiff

__all__ = [
    "BAYER_PATTERNS",
    "ENCODINGS",
    "RAW_SUFFIXES",
    "Encoding",
    "LinearPhoto",
    "read_photo",
]

RAW_SUFFIXES = (".dng", ".cr2", ".cr3", ".nef", ".arw", ".raf", ".orf", ".rw2", ".pef", ".srw")
_IMAGE_SUFFIXES = (".tif", ".tiff", ".png")
BAYER_PATTERNS = ("rggb", "bggr", "grbg", "gbrg")


@dataclass(frozen=True, eq=False)
class LinearPhoto:
    """A photograph as linear signal.

    Attributes
    ----------
    values
        ``(H, W)`` a raw mosaic or ``(H, W, 3)`` RGB, float64, black level subtracted.
    channel_index
        ``(H, W)`` the colour of each site of a mosaic (0 = R, 1 = G, 2 = B); None for RGB.
    white_level
        The value at and above which a site is clipped (after the black level); infinity if
        the format has none (floating point).
    source
        The file.
    note
        What was done to make the values linear, if anything beyond reading them.
    """

    values: np.ndarray
    channel_index: np.ndarray | None
    white_level: float
    source: str
    note: str | None = None

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)`` in pixels."""
        return int(self.values.shape[0]), int(self.values.shape[1])

    def channel(self, channel: int, window: tuple[slice, slice]) -> tuple[np.ndarray, np.ndarray]:
        """``(values, sites)`` of one colour in a ``window`` (row and column slices) of the
        photograph: its values and where the sites of that colour are, bool; for a mosaic or
        RGB alike."""
        if self.channel_index is None:
            values = self.values[window][:, :, channel]
            return values, np.ones(values.shape, bool)
        return self.values[window], self.channel_index[window] == channel

    def rgb(self) -> tuple[np.ndarray, int]:
        """``(rgb, factor)``: the photograph as ``(H', W', 3)`` RGB and its size's divisor.
        RGB as it is (factor 1); a mosaic by superpixels (factor 2): every 2 x 2 block of sites
        one pixel, the mean of its sites of each colour (no interpolation)."""
        if self.channel_index is None:
            return self.values, 1
        height, width = (size // 2 * 2 for size in self.shape)

        def blocks(values: np.ndarray) -> np.ndarray:
            return values[:height, :width].reshape(height // 2, 2, width // 2, 2).sum(axis=(1, 3))

        rgb = np.stack(
            [
                blocks(np.where(self.channel_index == c, self.values, 0.0))
                / np.maximum(blocks((self.channel_index == c).astype(float)), 1)
                for c in range(3)
            ],
            axis=-1,
        )
        return rgb, 2


def read_photo(
    path: str | Path,
    *,
    bayer: str | None = None,
    encoding: Encoding | None = None,
    black_level: float | None = None,
    white_level: float | None = None,
) -> LinearPhoto:
    """Read a chart photograph as linear signal (module description).

    Parameters
    ----------
    path
        A camera raw file, or a TIFF or PNG image.
    bayer
        The Bayer pattern of a single-channel image (``"rggb"``, ``"bggr"``, ``"grbg"``,
        ``"gbrg"``: the colours of the top-left 2 x 2 sites row by row); raw files carry their
        own.
    encoding
        Of an image's values: required for 8-bit images, ``"srgb"`` to decode the sRGB curve,
        ``"linear"`` to take them as they are; 16-bit and floating-point images are linear
        unless ``"srgb"`` is given.
    black_level, white_level
        Values of a dark site and of a clipped one: by default the file's (raw files), else 0
        and the format's largest value (255, 65535; none for floating point).

    Returns
    -------
    LinearPhoto
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"photo {path}: no such file")
    suffix = path.suffix.lower()
    if suffix in RAW_SUFFIXES:
        if encoding == "srgb":
            raise InputError(
                f"photo {path}: a camera raw file is linear; expected no sRGB decoding"
            )
        return _read_raw(path, black_level, white_level)
    if suffix not in _IMAGE_SUFFIXES:
        raise InputError(
            f"photo {path}: a {suffix or 'suffix-less'} file; expected a camera raw file "
            f"({', '.join(s[1:].upper() for s in RAW_SUFFIXES[:4])}, ...) or a linear 16-bit "
            "TIFF or PNG (JPEG is lossy and gamma-encoded)"
        )
    return _linear_image(
        path, read_png_or_tiff(path, "photo"), bayer, encoding, black_level, white_level
    )


def _linear_image(
    path: Path,
    image: np.ndarray,
    bayer: str | None,
    encoding: Encoding | None,
    black_level: float | None,
    white_level: float | None,
) -> LinearPhoto:
    """Check an image's layout and number type and make its values linear."""
    if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] != 3):
        raise InputError(
            f"photo {path}: pixels of shape {image.shape[2:]}; expected one channel (a raw "
            "mosaic) or three (RGB)"
        )
    if encoding is not None and encoding not in ENCODINGS:
        raise InputError(f"encoding {encoding!r}: expected one of {ENCODINGS}")
    top = _format_top(path, image.dtype)
    if image.dtype == np.uint8 and encoding is None:
        raise InputError(
            f"photo {path}: an 8-bit image, most likely gamma-encoded (sRGB); expected a linear "
            "16-bit TIFF or PNG or a camera raw file, or the image's encoding: 'srgb' to decode "
            "it, 'linear' if its values are linear"
        )
    values = image.astype(np.float64)
    note = None
    if encoding == "srgb":
        scale = top if np.isfinite(top) else 1.0
        values = scale * np.asarray(colour.models.eotf_sRGB(values / scale), np.float64)
        note = "decoded from sRGB (an approximation of the camera's tone curve)"
    elif image.dtype == np.uint8:
        note = "8-bit values taken as linear"
    black = 0.0 if black_level is None else float(black_level)
    white = (top if white_level is None else float(white_level)) - black
    if not white > 0:
        raise InputError(f"photo {path}: white level {white + black:g} not above black {black:g}")
    channels = None
    if image.ndim == 2:
        if bayer is None or bayer.lower() not in BAYER_PATTERNS:
            raise InputError(
                f"photo {path}: a single-channel image, a raw mosaic; expected its Bayer pattern, "
                f"one of {', '.join(BAYER_PATTERNS)}, got {bayer!r}"
            )
        channels = _bayer_channels(bayer.lower(), image.shape)
    return LinearPhoto(values - black, channels, white, str(path), note)


def _format_top(path: Path, dtype: np.dtype) -> float:
    """The largest value of the number type: 255, 65535, infinity for floating point."""
    if dtype in (np.uint8, np.uint16):
        return float(np.iinfo(dtype).max)
    if np.issubdtype(dtype, np.floating):
        return float("inf")
    raise InputError(
        f"photo {path}: {dtype} pixels; expected 16-bit (or 8-bit) unsigned integers or floats"
    )


def _bayer_channels(pattern: str, shape: tuple[int, ...]) -> np.ndarray:
    """``(H, W)`` channel of every site of a Bayer mosaic (0 = R, 1 = G, 2 = B)."""
    tile = np.array(["rgb".index(letter) for letter in pattern]).reshape(2, 2)
    height, width = shape[:2]
    return np.tile(tile, (height // 2 + 1, width // 2 + 1))[:height, :width]


def _read_raw(path: Path, black_level: float | None, white_level: float | None) -> LinearPhoto:
    """A camera raw file's visible mosaic, its black level subtracted per colour filter."""
    import rawpy

    try:
        with rawpy.imread(str(path)) as raw:
            if raw.raw_type != rawpy.RawType.Flat:
                raise InputError(
                    f"photo {path}: a raw file of demosaiced data; expected a colour filter array"
                )
            description = raw.color_desc.decode()
            if set(description) - set("RGB"):
                raise InputError(
                    f"photo {path}: colour filters {description}; expected red, green and blue"
                )
            colours = np.asarray(raw.raw_colors_visible)
            values = np.asarray(raw.raw_image_visible, dtype=np.float64)
            blacks = np.asarray(raw.black_level_per_channel, dtype=np.float64)
            file_white = float(raw.white_level)
    except rawpy.LibRawError as error:
        raise InputError(f"photo {path}: not a raw file LibRaw reads ({error})") from None
    channels = np.array(["RGB".index(letter) for letter in description])[colours]
    black = blacks[colours] if black_level is None else np.full(values.shape, float(black_level))
    white = (file_white if white_level is None else float(white_level)) - float(black.max())
    if not white > 0:
        raise InputError(f"photo {path}: white level not above the black level {black.max():g}")
    note = f"raw mosaic, black level {_levels(blacks) if black_level is None else black_level}"
    return LinearPhoto(values - black, channels, white, str(path), note)


def _levels(blacks: np.ndarray) -> str:
    unique = np.unique(blacks)
    return f"{unique[0]:g}" if unique.size == 1 else "/".join(f"{b:g}" for b in blacks)
