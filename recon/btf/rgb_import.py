"""An RGB BTF (a folder of images with a direction table, or a Bonn database archive or file)
upsampled into a spectral store.

Most measured BTFs are RGB: one photograph per light and view direction. Three kinds of source
are read (:func:`open_rgb_images`):

- a folder of images (8- or 16-bit sRGB-encoded PNG, JPEG or TIFF, all of one size, rectified to
  the sample's square) with ``directions.csv`` with the header
  ``file,light_theta_deg,light_phi_deg,view_theta_deg,view_phi_deg`` (polar angle from the
  sample's normal, azimuth from its +x axis towards +y, degrees; one row per image);
- a UBO2003 or ATRIUM zip archive (``.zip``) and a UBO2014 file (``.btf``) of the Bonn BTF
  database (:mod:`recon.btf.bonn_formats`), read as linear sRGB.

A decoded, linear value ``v`` of an image is read as the reflectance factor ``scale * v`` (a
white Lambertian reads 1), i.e. the BRDF ``scale * v / pi``.

The spectral pipelines take spectra, so the import upsamples every texel by a named method
(:mod:`recon.rgb_upsampling`; ``"jakob2019"``, brightness above 1 carried by scaling a colour
into the table's range and back) and records in the store's ``rgb_source`` attribute that it
came from RGB: the colour space, the source's format and encoding, the method, the scale, the
texel reduction and the source, so anything rendered from it can say so. The
upsampled spectra have the images' sRGB colours under D65; under other lights they are one
metamer among many.
"""

from __future__ import annotations

import csv
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from recon.btf.bonn_formats import read_image_archive, read_ubo2014
from recon.btf.reading_spectralization import (
    MeasuringSpot,
    is_reading_csv,
    read_reading_csv,
    reading_pair,
    spectralize_from_reading,
)
from recon.btf.rgb_images import RGBImageSet
from recon.btf.rgb_spectralization import (
    PRIOR,
    SpectralizedBTF,
    check_spots,
    read_btf_spots,
    spectralize_rgb_btf,
)
from recon.btf.schema import RgbSource
from recon.btf.staging import staged
from recon.btf.store import BTFStore
from recon.errors import InputError
from recon.image_spectralization import camera_response
from recon.image_spectralization.camera_fit import MAX_DEGREE
from recon.image_spectralization.run import solve_grid
from recon.progress import progress_steps
from recon.rgb_upsampling import read_srgb_image, reduce_image, upsample_srgb
from recon.spectra import DEFAULT_GRID, WavelengthGrid

__all__ = [
    "DIRECTION_TABLE",
    "RGB_COLUMNS",
    "import_rgb_images",
    "is_rgb_source",
    "is_spectralized",
    "open_rgb_images",
    "rgb_source",
]

DIRECTION_TABLE = "directions.csv"
RGB_COLUMNS = ("file", "light_theta_deg", "light_phi_deg", "view_theta_deg", "view_phi_deg")
"""The header of :data:`DIRECTION_TABLE`."""

_READERS = {".zip": read_image_archive, ".btf": read_ubo2014}


def rgb_source(store: BTFStore) -> RgbSource | None:
    """The store's ``rgb_source`` attribute (module docstring), ``None`` for a spectral BTF."""
    return store.metadata.rgb_source


def is_spectralized(store: BTFStore) -> bool:
    """Whether the store was spectralized from an RGB BTF and spot spectra (not upsampled)."""
    source = store.metadata.rgb_source
    return source is not None and source.spectralized is not None


def is_rgb_source(path: Path) -> bool:
    """Whether ``path`` is an RGB BTF that :func:`open_rgb_images` reads: a Bonn archive or
    file, or a folder with :data:`DIRECTION_TABLE`."""
    return path.suffix.lower() in _READERS or (path / DIRECTION_TABLE).is_file()


def open_rgb_images(path: str | Path) -> RGBImageSet:
    """The images of the RGB BTF at ``path`` (module docstring), not yet decoded."""
    path = Path(path)
    if path.suffix.lower() in _READERS:
        if not path.is_file():
            raise InputError(
                f"{path}: no such file; expected a UBO2003/ATRIUM .zip or a UBO2014 .btf"
            )
        return _READERS[path.suffix.lower()](path)
    if not path.is_dir():
        raise InputError(
            f"{path}: not a folder, .zip or .btf; expected images with {DIRECTION_TABLE}, a "
            "UBO2003/ATRIUM archive or a UBO2014 file"
        )
    rows = _read_table(path)
    return RGBImageSet(
        angles_deg=np.array([[float(row[c]) for c in RGB_COLUMNS[1:]] for row in rows]),
        names=tuple(row["file"] for row in rows),
        read=lambda pair: read_srgb_image(path / rows[pair]["file"]),
        encoding="sRGB",
        layout="image folder",
        source=path,
    )


def _read_table(folder: Path) -> list[dict[str, str]]:
    path = folder / DIRECTION_TABLE
    if not path.is_file():
        raise InputError(
            f"{folder}: no {DIRECTION_TABLE}; expected a table with the header "
            f"{','.join(RGB_COLUMNS)}"
        )
    with path.open(newline="") as handle:
        reader = csv.DictReader(handle)
        if tuple(reader.fieldnames or ()) != RGB_COLUMNS:
            raise InputError(
                f"{path}: header {reader.fieldnames}; expected {','.join(RGB_COLUMNS)}"
            )
        rows = list(reader)
    if not rows:
        raise InputError(f"{path}: no rows; expected one row per image")
    for number, row in enumerate(rows, start=2):
        try:
            [float(row[column]) for column in RGB_COLUMNS[1:]]
        except (TypeError, ValueError):
            raise InputError(
                f"{path}, line {number}: expected four angles in degrees after the file name"
            ) from None
    return rows


def import_rgb_images(
    source: str | Path,
    out_path: str | Path,
    *,
    upsampling: str = "jakob2019",
    scale: float = 1.0,
    material: str | None = None,
    texels: int | None = None,
    spectra: str | Path | None = None,
    response: str | None = None,
    measuring_spot: MeasuringSpot | None = None,
    camera_degree: int = MAX_DEGREE,
    neutral: bool = True,
    progress: bool = False,
) -> BTFStore:
    """Read an RGB BTF into a new spectral BTF store, upsampled or, given spot spectra,
    spectralized (:mod:`recon.btf.rgb_spectralization`; thesis section 10.1, Eq. 6.10).

    Parameters
    ----------
    source
        A folder of images with ``directions.csv``, a UBO2003/ATRIUM ``.zip`` or a UBO2014
        ``.btf`` (module docstring).
    out_path
        The new store (must not exist).
    upsampling
        How RGB becomes spectra (``"jakob2019"``).
    scale
        Reflectance factor of a linear image value of 1.
    material
        The store's material name (default: the source's name); the twin's colour checker
        (``colorchecker16``) makes the store one that the twin's validation compares.
    texels
        Largest side of the stored texture: images are reduced by area averaging
        (:func:`recon.rgb_upsampling.reduce_image`); ``None`` keeps them whole.
    spectra
        A spots CSV ``pair,x,y,<nm>,...`` (:func:`recon.btf.rgb_spectralization.read_btf_spots`;
        texels of the stored texture), or one 45/0 reading ``wavelength_nm,reflectance``
        (:func:`recon.btf.reading_spectralization.read_reading_csv`, told apart by the
        header): the BTF is spectralized from them instead of upsampled, its images' linear
        values taken as the camera's, and ``rgb_source.spectralized`` says so.
    response
        With ``spectra``: the camera's response, a shipped camera's name or a CSV
        ``wavelength_nm,R,G,B`` (:func:`recon.image_spectralization.camera_response`).
    measuring_spot
        With a reading: its measuring spot on the stored texture; None: the whole texture.
    camera_degree, neutral
        With spots: the camera term's highest degree and the neutral highlight of
        :func:`recon.btf.rgb_spectralization.spectralize_rgb_btf` (0 and False: a gain per
        channel and a free base).

    Returns
    -------
    BTFStore
        The new, complete store. It is built under a temporary name beside ``out_path`` and
        renamed to it once complete (:func:`recon.btf.staging.staged`): an import that fails
        or is cut short leaves nothing behind.
    """
    if upsampling != "jakob2019":
        raise InputError(
            f"upsampling: {upsampling!r}; expected 'jakob2019' (the spectralization needs known "
            "spectra, which a BTF's images do not carry)"
        )
    if not np.isfinite(scale) or scale <= 0:
        raise InputError(f"scale: expected a positive number, got {scale}")
    if texels is not None and texels < 1:
        raise InputError(f"texels: expected a positive side in texels, got {texels}")
    if (spectra is None) != (response is None):
        raise InputError(
            "spectra, response: expected both (spot spectra and the camera's response) or neither"
        )
    if spectra is not None and scale != 1.0:
        raise InputError(f"scale: {scale}; a spectralized import takes its scale from the spots")
    images = open_rgb_images(source)
    first, factor = _reduced(images.read(0), texels)
    spectralize = _spectralizer(
        spectra, response, measuring_spot, images, first.shape[:2], camera_degree, neutral
    )
    source_attrs: dict[str, Any] = {
        "colour_space": "sRGB" if spectralize is None else "camera RGB",
        "layout": images.layout,
        "encoding": images.encoding,
        "upsampling": upsampling if spectralize is None else "spectralization",
        "scale": float(scale),
        "texel_reduction": factor,
        "images": str(images.source.resolve()),
    }
    with staged(out_path) as building:
        if spectralize is None:
            pairs: Iterator[tuple[np.ndarray, WavelengthGrid]] = (
                ((upsample_srgb(scale * linear, "jakob2019").values / np.pi), DEFAULT_GRID)
                for linear in _linear_pairs(images, first, texels, progress)
            )
            grid = DEFAULT_GRID
        else:
            stack = np.stack(list(_linear_pairs(images, first, texels, progress)))
            result, source_attrs["spectralized"] = spectralize(stack)
            pairs = ((cube / np.pi, result.grid) for cube in result.cube)
            grid = result.grid
        store = BTFStore.create(
            building,
            light_dirs=images.light_dirs(),
            view_dirs=images.view_dirs(),
            texels=first.shape[:2],
            grid=grid,
            material=material or _name(Path(source)),
        )
        store.set_attribute("rgb_source", source_attrs)
        for pair, (values, on_grid) in enumerate(pairs):
            store.write_pair(pair, values.astype(np.float32), grid=on_grid)
    return BTFStore.open(out_path)


def _linear_pairs(
    images: RGBImageSet, first: np.ndarray, texels: int | None, progress: bool
) -> Iterator[np.ndarray]:
    """Each pair's linear image (reduced to ``texels``), refusing one of another size."""
    with progress_steps(f"import {images.layout}", images.n_pairs, enabled=progress) as advance:
        for pair in range(images.n_pairs):
            linear = first if pair == 0 else _reduced(images.read(pair), texels)[0]
            if linear.shape != first.shape:
                raise InputError(
                    f"{images.source}: {images.names[pair]} is {linear.shape[0]} x "
                    f"{linear.shape[1]} px, expected {first.shape[0]} x {first.shape[1]} like "
                    f"{images.names[0]}"
                )
            yield linear
            advance()


_Spectralizer = Callable[[np.ndarray], tuple[SpectralizedBTF, dict[str, Any]]]


def _spectralizer(
    spectra: str | Path | None,
    response: str | None,
    measuring_spot: MeasuringSpot | None,
    images: RGBImageSet,
    shape: tuple[int, int],
    camera_degree: int,
    neutral: bool,
) -> _Spectralizer | None:
    """What spectralizes the stacked linear images from the spots or the 45/0 reading and
    gives the ``rgb_source.spectralized`` attribute (``recon.btf.schema.SpotSource``), after
    the checks that need no images beyond the first (of texture ``shape``); None without
    ``spectra``."""
    if spectra is not None and not Path(spectra).is_file():
        raise InputError(
            f"spectra {spectra}: no such file; expected spots (a CSV pair,x,y,<nm>,...) or a "
            "45/0 reading (a CSV wavelength_nm,reflectance)"
        )
    reading = None if spectra is None or not is_reading_csv(spectra) else read_reading_csv(spectra)
    if measuring_spot is not None and reading is None:
        raise InputError(
            "measuring_spot: only with a 45/0 reading (a CSV wavelength_nm,reflectance), not "
            "with spots or without spectra"
        )
    if spectra is None or response is None:
        return None
    curves = camera_response(response)
    record: dict[str, Any] = {"response": response}
    if reading is None:
        spots = read_btf_spots(spectra)
        check_spots(spots, curves, (images.n_pairs, *shape))
        record |= {
            "spots": str(Path(spots.source).resolve()),
            "n_spots": len(spots.where),
            "spot_pairs": sorted({int(pair) for pair in spots.where[:, 0]}),
            "prior": PRIOR,
        }
        return lambda stack: _recorded(
            spectralize_rgb_btf(stack, spots, curves, camera_degree=camera_degree, neutral=neutral),
            record,
        )
    pair, _ = reading_pair(images.light_dirs(), images.view_dirs())
    spot = measuring_spot or MeasuringSpot(0, 0, shape[1], shape[0])
    spot.texels(shape)
    solve_grid(reading.spectrum, curves)
    record |= {
        "spots": str(Path(reading.source).resolve()),
        "n_spots": 1,
        "spot_pairs": [pair],
        "prior": "regression (from the reading)",
        "measuring_spot": [spot.x, spot.y, spot.width, spot.height],
    }
    return lambda stack: _recorded(
        spectralize_from_reading(stack, reading, curves, pair=pair, spot=spot), record
    )


def _recorded(
    result: SpectralizedBTF, record: dict[str, Any]
) -> tuple[SpectralizedBTF, dict[str, Any]]:
    """``result`` and the ``rgb_source.spectralized`` attribute: ``record`` and the design,
    gains and fit of ``result``."""
    return result, {
        **record,
        "design": result.design,
        "gains": [float(gain) for gain in result.gains],
        "fit_residual_pct": [float(value) for value in result.fit_residual_pct],
    }


def _name(source: Path) -> str:
    return source.stem if source.suffix.lower() in _READERS else source.name


def _reduced(linear: np.ndarray, texels: int | None) -> tuple[np.ndarray, int]:
    return (linear, 1) if texels is None else reduce_image(linear, texels)
