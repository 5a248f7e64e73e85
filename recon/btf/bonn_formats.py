"""Measured RGB BTFs in the formats of the University of Bonn's BTF database.

The database publishes its BTFs in three layouts; each is read into an
:class:`recon.btf.rgb_images.RGBImageSet` for :func:`recon.btf.rgb_import.import_rgb_btf`:

- **UBO2003** and ATRIUM's low dynamic range archives (:func:`read_image_archive`): a zip
  archive of 8-bit sRGB JPEGs, one per direction pair, named
  ``tl{θl:03} pl{φl:03} tv{θv:03} pv{φv:03}.jpg`` (light and view polar angles and azimuths in
  whole degrees), rectified to the sample's square.
- **ATRIUM HDR** (the same function): the same names ending ``.hdr``, linear Radiance RGBE
  images. Their resolution line reads ``+X W -Y H``, yet the pixels lie in the usual
  ``-Y H +X W`` order, bottom row first; they are read so.
- **UBO2014** (:func:`read_ubo2014`): one ``.btf`` file in the DFMF layout, little-endian:

  1. ``!DFMF08FC``, then ``R`` if the file carries rotations;
  2. a header of ``Size`` bytes: ``Size``, ``Version`` (uint32), measurement setup, image sensor
     and light source (80 characters each), pixels per mm and an RGB scale (4 float32); from
     version 2 a cosine flag (uint32), from 3 an XML block (uint32 length, text), from 4 the
     channel names (uint32 count, then uint32 length and text each);
  3. the directions: a uint32 view count; per view its polar angle and azimuth (2 float32,
     radians), a uint32 light count and, per light, its angles; every view lists the same
     lights, and views and lights are the same set;
  4. the texture's width and height (uint32); with ``R``, a uint32 count of 3 x 3 float32
     rotations and the rotations;
  5. the factorization: a uint32 component count, the colour model (uint32; 0 is RGB, 11 is
     Bonn's logarithmic YUV), a colour mean (3 float32) and transform (9 float32), then per
     channel: the scalar size (uint8: 2, 4 or 8 for half, single, double), its component count
     ``C``, the row count ``L**2`` and column count ``W * H`` (uint32), ``C`` singular values,
     ``U`` (``L**2 x C``, row ``view * L + light``) and ``SxV`` (``W * H x C``, row
     ``y * W + x``, bottom row first). A channel's value is the product of the pair's ``U`` row
     and the texel's ``SxV`` row; the file ends with the last channel.

  In colour model 11 the channels are ``ln(Y + 1e-5)``, ``U / Y`` and ``V / Y``; they are
  turned back (each chroma plus 1e-5) and converted by the YUV-to-RGB matrix below, clipped to
  [0, 1]. Values are linear.

Pairs come in the order lights x views (UBO2014) or of the sorted angles (archives). Every
count and size a UBO2014 header gives is checked against the bytes left in the file before
anything is read or decoded, and a channel has between 1 and ``min(L**2, W * H)`` components,
so a header cannot make the reader decode an image larger than the file holds.

References
----------
- Müller, G., Meseth, J., Klein, R. (2003). Compression and real-time rendering of measured
  BTFs using local PCA. Proc. VMV (the UBO2003 archives).
- Weinmann, M., Gall, J., Klein, R. (2014). Material classification based on training data
  synthesized using a BTF database. Proc. ECCV (the UBO2014 files).
- The layouts above were read from the Bonn database's pages and the free BTF loader
  (Z. Velinov, MIT) that the btf-extractor package (1.7.0) wraps. spectwin's readers were
  checked against btf-extractor on files written to these layouts (``scripts/bonn_btf_files.py``
  writes them and compares).
"""

from __future__ import annotations

import mmap
import re
import zipfile
from pathlib import Path

import numpy as np

from recon.btf.rgb_images import RGBImageSet
from recon.errors import InputError
from recon.rgb_upsampling import read_srgb_image

__all__ = ["ARCHIVE_NAME", "YUV_TO_RGB", "read_image_archive", "read_ubo2014"]

ARCHIVE_NAME = re.compile(r"tl(\d{3}) pl(\d{3}) tv(\d{3}) pv(\d{3})\.(jpg|hdr)", re.IGNORECASE)
"""An archive entry's file name: light and view angles in whole degrees."""

YUV_TO_RGB = np.array([[1.0, 0.0, 1.13983], [1.0, -0.39465, -0.5806], [1.0, 2.03211, 0.0]])
"""Colour model 11's YUV to RGB matrix (rows: R, G, B)."""

_LOG_OFFSET = 1e-5  # colour model 11's offset of the logarithm and of the chroma
_SIGNATURE = b"!DFMF08FC"
_SCALARS = {2: "<f2", 4: "<f4", 8: "<f8"}
_RADIANCE_FLIPPED = re.compile(rb"\n\+X (\d+) -Y (\d+)\n")


def read_image_archive(path: str | Path) -> RGBImageSet:
    """The images of a UBO2003 or ATRIUM zip archive (module docstring)."""
    path = Path(path)
    try:
        archive = zipfile.ZipFile(path)
    except (OSError, zipfile.BadZipFile) as error:
        raise InputError(
            f"{path}: not a readable zip archive ({error}); expected a UBO2003 or ATRIUM archive"
        ) from None
    entries: dict[tuple[int, ...], str] = {}
    suffixes = set()
    for name in archive.namelist():
        match = ARCHIVE_NAME.fullmatch(name.rsplit("/", 1)[-1])
        if match is None:
            continue
        angles = tuple(int(value) for value in match.groups()[:4])
        if angles in entries:
            raise InputError(
                f"{path}: {entries[angles]} and {name} have the same angles; expected one image "
                "per direction pair"
            )
        entries[angles] = name
        suffixes.add(match.group(5).lower())
    if not entries:
        raise InputError(
            f"{path}: no images named like 'tl000 pl000 tv000 pv000.jpg' (or .hdr); expected a "
            "UBO2003 or ATRIUM archive"
        )
    if len(suffixes) > 1:
        raise InputError(f"{path}: both JPEG and HDR images; expected one kind")
    keys = sorted(entries)
    hdr = suffixes == {"hdr"}

    def read(pair: int) -> np.ndarray:
        name = entries[keys[pair]]
        data = archive.read(name)
        return (
            _decode_flipped_radiance(data, f"{path}:{name}")
            if hdr
            else read_srgb_image(f"{path}:{name}", data)
        )

    return RGBImageSet(
        angles_deg=np.array(keys, dtype=float),
        names=tuple(entries[key] for key in keys),
        read=read,
        encoding="linear" if hdr else "sRGB",
        layout="ATRIUM HDR" if hdr else "UBO2003",
        source=path,
    )


def _decode_flipped_radiance(data: bytes, label: str) -> np.ndarray:
    """Linear RGB of an ATRIUM Radiance image (module docstring)."""
    import cv2

    match = _RADIANCE_FLIPPED.search(data)
    if match is None:
        raise InputError(
            f"{label}: no '+X W -Y H' resolution line; expected an ATRIUM Radiance image"
        )
    width, height = match.groups()
    usual = data[: match.start()] + b"\n-Y " + height + b" +X " + width + b"\n"
    pixels = cv2.imdecode(
        np.frombuffer(usual + data[match.end() :], np.uint8), cv2.IMREAD_UNCHANGED
    )
    if pixels is None or pixels.ndim != 3:
        raise InputError(f"{label}: not a readable Radiance image")
    return pixels[::-1, :, ::-1].astype(np.float64)


class _Cursor:
    """Reads little-endian values one after another from a UBO2014 file's bytes."""

    def __init__(self, data: mmap.mmap, path: Path, start: int) -> None:
        self.data, self.path, self.position = data, path, start

    def require(self, size: int, what: str) -> None:
        """Refuse a file with fewer than ``size`` bytes left for ``what``."""
        if self.position + size > len(self.data):
            raise InputError(
                f"{self.path}: ends at byte {len(self.data)} inside {what}; expected a complete "
                "UBO2014 file"
            )

    def take(self, dtype: str, count: int, what: str) -> np.ndarray:
        size = np.dtype(dtype).itemsize * count
        self.require(size, what)
        values = np.frombuffer(self.data, dtype, count, self.position)
        self.position += size
        return values

    def number(self, what: str) -> int:
        return int(self.take("<u4", 1, what)[0])

    def skip(self, size: int, what: str) -> None:
        self.take("u1", size, what)


def read_ubo2014(path: str | Path) -> RGBImageSet:
    """The images of a UBO2014 ``.btf`` file in the DFMF layout (module docstring), decoded
    one pair at a time from the factors (``U`` memory-mapped, ``SxV`` read once)."""
    path = Path(path)
    try:
        with path.open("rb") as handle:
            data = mmap.mmap(handle.fileno(), 0, access=mmap.ACCESS_READ)
    except (OSError, ValueError) as error:
        raise InputError(f"{path}: not readable ({error}); expected a UBO2014 .btf file") from None
    if data[: len(_SIGNATURE)] != _SIGNATURE:
        raise InputError(
            f"{path}: starts {bytes(data[:9])!r}; expected {_SIGNATURE!r} (a UBO2014 file in the "
            "DFMF layout)"
        )
    rotations = data[len(_SIGNATURE) : len(_SIGNATURE) + 1] == b"R"
    cursor = _Cursor(data, path, len(_SIGNATURE) + rotations)
    lights_deg, views_deg, width, height = _read_header(cursor, rotations)
    channels = _read_factors(cursor, len(lights_deg) ** 2, width * height)
    if cursor.position != len(data):
        raise InputError(
            f"{path}: {len(data) - cursor.position} bytes after the last channel; expected the "
            "file to end there"
        )
    model, factors = channels
    count = len(lights_deg)

    def read(pair: int) -> np.ndarray:
        light, view = divmod(pair, count)
        row = view * count + light
        values = np.stack([sxv @ u[row].astype(np.float32) for u, sxv in factors], axis=-1)
        image = values.reshape(height, width, 3)[::-1]
        if model == 11:
            luminance = np.exp(image[..., 0]) - _LOG_OFFSET
            yuv = np.stack(
                [
                    luminance,
                    image[..., 1] * luminance + _LOG_OFFSET,
                    image[..., 2] * luminance + _LOG_OFFSET,
                ],
                axis=-1,
            )
            image = np.clip(yuv @ YUV_TO_RGB.T.astype(np.float32), 0.0, 1.0)
        return image

    pairs = [(light, view) for light in range(count) for view in range(count)]
    return RGBImageSet(
        angles_deg=np.array([[*lights_deg[light], *views_deg[view]] for light, view in pairs]),
        names=tuple(f"light {light}, view {view}" for light, view in pairs),
        read=read,
        encoding="linear",
        layout="UBO2014",
        source=path,
    )


def _read_header(cursor: _Cursor, rotations: bool) -> tuple[np.ndarray, np.ndarray, int, int]:
    """The lights' and views' directions (polar angle, azimuth in degrees) and the texture's
    width and height."""
    start = cursor.position
    size, version = (int(value) for value in cursor.take("<u4", 2, "the header"))
    cursor.skip(3 * 80 + 4 * 4, "the header")
    if version > 1 and cursor.number("the header"):
        raise InputError(
            f"{cursor.path}: cosine-weighted values; expected plain reflectance (cosine flag 0)"
        )
    if version > 2:
        cursor.skip(cursor.number("the header's XML"), "the header's XML")
    if version > 3:
        channel_count = cursor.number("the channel names")
        for _ in range(channel_count):
            cursor.skip(cursor.number("the channel names"), "the channel names")
        if channel_count != 3:
            raise InputError(f"{cursor.path}: {channel_count} channels; expected 3 (RGB or YUV)")
    if cursor.position - start != size:
        raise InputError(
            f"{cursor.path}: header of {cursor.position - start} bytes, declared {size}; "
            "expected a UBO2014 header"
        )
    view_count = cursor.number("the directions")
    cursor.require(view_count * 12, f"{view_count} views")  # two angles and a count each
    lights, views = None, []
    for view in range(view_count):
        views.append(cursor.take("<f4", 2, "the directions"))
        count = cursor.number("the directions")
        angles = cursor.take("<f4", 2 * count, "the directions").reshape(count, 2)
        if lights is None:
            lights = angles
        elif count != len(lights):
            raise InputError(
                f"{cursor.path}: view {view} lists {count} lights, view 0 {len(lights)}; "
                "expected the same lights for every view"
            )
    if lights is None or len(lights) != view_count:
        raise InputError(
            f"{cursor.path}: {view_count} views and {0 if lights is None else len(lights)} "
            "lights; expected the same, non-empty set of directions for both"
        )
    width, height = cursor.number("the texture size"), cursor.number("the texture size")
    if width == 0 or height == 0:
        raise InputError(f"{cursor.path}: a texture of {width} x {height} texels; expected texels")
    if rotations:
        cursor.skip(36 * cursor.number("the rotations"), "the rotations")
    degrees = np.degrees(np.concatenate([lights, np.stack(views)]).astype(np.float64))
    degrees[:, 1] %= 360.0
    return degrees[:view_count], degrees[view_count:], width, height


def _read_factors(
    cursor: _Cursor, rows: int, columns: int
) -> tuple[int, list[tuple[np.ndarray, np.ndarray]]]:
    """The colour model and each channel's ``U`` (memory-mapped) and ``SxV`` (as float32)."""
    cursor.number("the factorization")
    model = cursor.number("the colour model")
    if model not in (0, 11):
        raise InputError(
            f"{cursor.path}: colour model {model}; expected 0 (RGB) or 11 (logarithmic YUV)"
        )
    cursor.skip(12 * 4, "the colour transform")
    factors = []
    for channel in range(3):
        what = f"channel {channel}"
        scalar = int(cursor.take("u1", 1, what)[0])
        if scalar not in _SCALARS:
            raise InputError(
                f"{cursor.path}: {what} stores {scalar}-byte numbers; expected 2, 4 or 8"
            )
        components = cursor.number(what)
        stored_rows, stored_columns = cursor.number(what), cursor.number(what)
        if (stored_rows, stored_columns) != (rows, columns):
            raise InputError(
                f"{cursor.path}: {what} is {stored_rows} x {stored_columns}; expected {rows} "
                f"direction pairs x {columns} texels"
            )
        if not 1 <= components <= min(rows, columns):
            raise InputError(
                f"{cursor.path}: {what} has {components} components; expected 1 to "
                f"{min(rows, columns)} (at most one per direction pair and per texel)"
            )
        # The factors must be in the file before an image of ``columns`` texels is decoded.
        cursor.require(scalar * components * (1 + rows + columns), what)
        dtype = _SCALARS[scalar]
        cursor.take(dtype, components, what)
        u = cursor.take(dtype, rows * components, what).reshape(rows, components)
        sxv = cursor.take(dtype, columns * components, what).reshape(columns, components)
        factors.append((u, sxv.astype(np.float32)))  # every pair's decode reads all of SxV
    return model, factors
