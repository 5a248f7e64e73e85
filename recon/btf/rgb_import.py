"""An RGB BTF from a folder of images with a direction table, upsampled into a spectral store.

Most measured BTFs are RGB: one photograph per light and view direction. The folder holds the
images (8- or 16-bit sRGB-encoded PNG, JPEG or TIFF, all of one size, rectified to the sample's
square) and ``directions.csv`` with the header
``file,light_theta_deg,light_phi_deg,view_theta_deg,view_phi_deg`` (polar angle from the sample's
normal, azimuth from its +x axis towards +y, degrees; one row per image). A decoded, linear value
``v`` of an image is read as the reflectance factor ``scale * v`` (a white Lambertian reads 1),
i.e. the BRDF ``scale * v / pi``.

The spectral pipelines take spectra, so the import upsamples every texel by a named method
(:mod:`recon.rgb_upsampling`; ``"jakob2019"``, brightness above 1 carried by scaling a colour
into the table's range and back) and records in the store's ``rgb_source`` attribute that it
came from RGB: the colour space, the method, the scale and the folder. Anything rendered from it
(``spectwin validate``) says so. The upsampled spectra have the images' sRGB colours under D65;
under other lights they are one metamer among many.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from recon.btf.store import BTFStore
from recon.errors import SpectwinInputError
from recon.progress import progress_steps
from recon.rgb_upsampling import read_srgb_image, upsample_srgb
from recon.spectra import DEFAULT_GRID

__all__ = ["DIRECTION_TABLE", "RGB_COLUMNS", "import_rgb_images", "rgb_source"]

DIRECTION_TABLE = "directions.csv"
RGB_COLUMNS = ("file", "light_theta_deg", "light_phi_deg", "view_theta_deg", "view_phi_deg")
"""The header of :data:`DIRECTION_TABLE`."""


def rgb_source(store: BTFStore) -> dict | None:
    """The store's ``rgb_source`` attribute (module docstring), ``None`` for a spectral BTF."""
    return store.attrs.get("rgb_source")


def _direction(theta_deg: float, phi_deg: float) -> np.ndarray:
    theta, phi = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def _read_table(folder: Path) -> list[dict[str, str]]:
    path = folder / DIRECTION_TABLE
    if not path.is_file():
        raise SpectwinInputError(
            f"{folder}: no {DIRECTION_TABLE}; expected a table with the header "
            f"{','.join(RGB_COLUMNS)}"
        )
    with path.open(newline="") as handle:
        reader = csv.DictReader(handle)
        if tuple(reader.fieldnames or ()) != RGB_COLUMNS:
            raise SpectwinInputError(
                f"{path}: header {reader.fieldnames}; expected {','.join(RGB_COLUMNS)}"
            )
        rows = list(reader)
    if not rows:
        raise SpectwinInputError(f"{path}: no rows; expected one row per image")
    for number, row in enumerate(rows, start=2):
        try:
            angles = [float(row[column]) for column in RGB_COLUMNS[1:]]
        except (TypeError, ValueError):
            raise SpectwinInputError(
                f"{path}, line {number}: expected four angles in degrees after the file name"
            ) from None
        if not (0 <= angles[0] < 90 and 0 <= angles[2] < 90):
            raise SpectwinInputError(
                f"{path}, line {number}: polar angles {angles[0]:g}, {angles[2]:g} deg; expected "
                "0 to below 90 (above the sample)"
            )
    return rows


def import_rgb_images(
    folder: str | Path,
    out_path: str | Path,
    *,
    upsampling: str = "jakob2019",
    scale: float = 1.0,
    material: str | None = None,
    progress: bool = False,
) -> BTFStore:
    """Read a folder of RGB images with ``directions.csv`` into a new spectral BTF store.

    Parameters
    ----------
    folder
        The images and their direction table (module docstring).
    out_path
        The new store (must not exist).
    upsampling
        How RGB becomes spectra (``"jakob2019"``).
    scale
        Reflectance factor of a linear image value of 1.
    material
        The store's material name (default: the folder's name); the twin's colour checker
        (``colorchecker16``) makes the store one that ``spectwin validate`` compares.

    Returns
    -------
    BTFStore
        The new, complete store; an import cut short leaves an incomplete one.
    """
    folder = Path(folder)
    if upsampling != "jakob2019":
        raise SpectwinInputError(
            f"upsampling: {upsampling!r}; expected 'jakob2019' (the spectralization needs known "
            "spectra, which a BTF's images do not carry)"
        )
    if not np.isfinite(scale) or scale <= 0:
        raise SpectwinInputError(f"scale: expected a positive number, got {scale}")
    if not folder.is_dir():
        raise SpectwinInputError(f"{folder}: not a folder; expected images with {DIRECTION_TABLE}")
    rows = _read_table(folder)
    first = read_srgb_image(folder / rows[0]["file"])
    angles = np.array([[float(row[c]) for c in RGB_COLUMNS[1:]] for row in rows])
    store = BTFStore.create(
        out_path,
        light_dirs=np.stack([_direction(*pair[:2]) for pair in angles]),
        view_dirs=np.stack([_direction(*pair[2:]) for pair in angles]),
        texels=first.shape[:2],
        grid=DEFAULT_GRID,
        material=material or folder.name,
    )
    store.set_attribute(
        "rgb_source",
        {
            "colour_space": "sRGB",
            "upsampling": upsampling,
            "scale": float(scale),
            "images": str(folder.resolve()),
        },
    )
    with progress_steps("import RGB images", len(rows), enabled=progress) as advance:
        for pair, row in enumerate(rows):
            linear = first if pair == 0 else read_srgb_image(folder / row["file"])
            if linear.shape != first.shape:
                raise SpectwinInputError(
                    f"{folder / row['file']}: {linear.shape[0]} x {linear.shape[1]} px, expected "
                    f"{first.shape[0]} x {first.shape[1]} like {rows[0]['file']}"
                )
            spectra = upsample_srgb(scale * linear, "jakob2019").values
            store.write_pair(pair, (spectra / np.pi).astype(np.float32), grid=DEFAULT_GRID)
            advance()
    return BTFStore.open(out_path)
