"""Write BTFs in the Bonn database's layouts (UBO2003 and ATRIUM archives, UBO2014 files) and
compare spectwin's readers (recon.btf.bonn_formats) with btf-extractor's.

The writers follow the layouts as recon.btf.bonn_formats documents them; the tests use them to
make files, and this script checks both sides against the reference reader:

    python scripts/bonn_btf_files.py write DIR      # spectwin's environment: the files and
                                                    # what spectwin decodes from them
    python scripts/bonn_btf_files.py compare DIR    # an environment with btf-extractor
                                                    # (numpy < 2): its decodes against them

``compare`` prints JSON: per file, the largest difference between the two readers' images and
whether their angles agree. The module needs only numpy at import (btf-extractor's environment
cannot install spectwin), so it spells out the layout's constants itself.
"""

from __future__ import annotations

import io
import json
import struct
import sys
import zipfile
from pathlib import Path

import numpy as np

YUV_TO_RGB = np.array([[1.0, 0.0, 1.13983], [1.0, -0.39465, -0.5806], [1.0, 2.03211, 0.0]])
LOG_OFFSET = 1e-5
SCALARS = {2: "<f2", 4: "<f4", 8: "<f8"}


def archive_name(angles: np.ndarray, suffix: str) -> str:
    """An archive entry's name for whole-degree angles (light theta, phi, view theta, phi)."""
    tl, pl, tv, pv = (round(float(value)) for value in angles)
    return f"tl{tl:03} pl{pl:03} tv{tv:03} pv{pv:03}.{suffix}"


def write_ubo2003(path: Path, angles: np.ndarray, encoded: np.ndarray, folder: str = "") -> None:
    """A UBO2003 archive: ``encoded`` ``(N, H, W, 3)`` uint8 sRGB images as JPEGs (quality 95,
    no chroma subsampling) named by ``angles`` ``(N, 4)`` in whole degrees."""
    from PIL import Image

    with zipfile.ZipFile(path, "w") as archive:
        for pair_angles, image in zip(angles, encoded, strict=True):
            data = io.BytesIO()
            Image.fromarray(image).save(data, format="JPEG", quality=95, subsampling=0)
            archive.writestr(folder + archive_name(pair_angles, "jpg"), data.getvalue())


def write_atrium_hdr(path: Path, angles: np.ndarray, linear: np.ndarray) -> None:
    """An ATRIUM HDR archive: ``linear`` ``(N, H, W, 3)`` RGB as Radiance images whose
    resolution line reads ``+X W -Y H`` while the rows run bottom to top."""
    import cv2

    with zipfile.ZipFile(path, "w") as archive:
        for pair_angles, image in zip(angles, linear, strict=True):
            height, width = image.shape[:2]
            ok, data = cv2.imencode(".hdr", image[::-1, :, ::-1].astype(np.float32))
            assert ok
            usual = f"\n-Y {height} +X {width}\n".encode()
            flipped = f"\n+X {width} -Y {height}\n".encode()
            archive.writestr(
                archive_name(pair_angles, "hdr"), data.tobytes().replace(usual, flipped, 1)
            )


def write_ubo2014(
    path: Path,
    lights_rad: np.ndarray,
    views_rad: np.ndarray,
    linear: np.ndarray,
    *,
    components: int | None = None,
    scalar_size: int = 2,
    colour_model: int = 0,
    rotations: bool = False,
    version: int = 1,
) -> None:
    """A UBO2014 file in the DFMF layout.

    ``linear`` ``(L, L, H, W, 3)`` is indexed [light, view] with row 0 at the top; each channel
    (RGB, or for ``colour_model`` 11 logarithmic luminance and chroma over luminance) is
    factorized by an SVD truncated to ``components`` and stored as ``scalar_size``-byte floats.
    """
    count, _, height, width, _ = linear.shape
    # rows view * L + light; columns y * W + x with the bottom row first
    matrix = linear.transpose(1, 0, 2, 3, 4)[:, :, ::-1].reshape(count * count, height * width, 3)
    if colour_model == 11:
        yuv = matrix @ np.linalg.inv(YUV_TO_RGB).T
        luminance = yuv[..., 0]
        matrix = np.stack(
            [
                np.log(luminance + LOG_OFFSET),
                (yuv[..., 1] - LOG_OFFSET) / luminance,
                (yuv[..., 2] - LOG_OFFSET) / luminance,
            ],
            axis=-1,
        )
    header = struct.pack("<II", 0, version) + b"spectwin".ljust(240, b"\0")
    header += struct.pack("<4f", 1.0, 1.0, 1.0, 1.0)
    if version > 1:
        header += struct.pack("<I", 0)
    if version > 2:
        header += struct.pack("<I", 9) + b"<btf/>\n\n\n"
    if version > 3:
        header += struct.pack("<I", 3) + b"".join(
            struct.pack("<I", 1) + name for name in (b"R", b"G", b"B")
        )
    header = struct.pack("<I", len(header)) + header[4:]
    out = [b"!DFMF08FC" + (b"R" if rotations else b""), header, struct.pack("<I", count)]
    for view in views_rad:
        out.append(np.asarray(view, "<f4").tobytes() + struct.pack("<I", count))
        out.append(np.asarray(lights_rad, "<f4").tobytes())
    out.append(struct.pack("<II", width, height))
    if rotations:
        out.append(struct.pack("<I", 1) + np.eye(3, dtype="<f4").tobytes())
    rank = components or min(matrix.shape[:2])
    out.append(struct.pack("<II", rank, colour_model) + np.zeros(12, "<f4").tobytes())
    for channel in range(3):
        u, s, vt = np.linalg.svd(matrix[..., channel], full_matrices=False)
        dtype = SCALARS[scalar_size]
        out.append(struct.pack("<BIII", scalar_size, rank, count * count, height * width))
        out.append(s[:rank].astype(dtype).tobytes())
        out.append(np.ascontiguousarray(u[:, :rank]).astype(dtype).tobytes())
        out.append(np.ascontiguousarray((s[:rank, None] * vt[:rank]).T).astype(dtype).tobytes())
    path.write_bytes(b"".join(out))


def _examples() -> dict[str, dict]:
    """Small files of every layout: 3 directions, 8 x 6 texels (not square, to catch
    transposed readers), smooth colours that change with the pair."""
    rng = np.random.default_rng(7)
    height, width, count = 6, 8, 3
    rows, columns = np.mgrid[0:height, 0:width]
    base = 0.15 + 0.6 * np.stack(
        [rows / height, columns / width, 0.5 + 0.4 * np.sin(rows + columns)], axis=-1
    )
    gains = 0.4 + 0.6 * rng.random((count, count, 1, 1, 3))
    linear = gains * base  # (light, view, H, W, 3)
    thetas = np.radians([0.0, 30.0, 60.0])
    directions = np.stack([thetas, np.radians([0.0, 90.0, 225.0])], axis=-1)
    angles = np.array(
        [
            [np.degrees(directions[light, 0]), np.degrees(directions[light, 1])]
            + [np.degrees(directions[view, 0]), np.degrees(directions[view, 1])]
            for light in range(count)
            for view in range(count)
        ]
    ).round()
    encoded = np.round(255 * _srgb_encode(linear.reshape(-1, height, width, 3))).astype(np.uint8)
    return {
        "ubo2003.zip": {"kind": "ubo2003", "angles": angles, "images": encoded},
        "atrium_hdr.zip": {"kind": "atrium_hdr", "angles": angles, "images": linear},
        "ubo2014_half_rgb.btf": {"kind": "ubo2014", "directions": directions, "images": linear},
        "ubo2014_float_yuv_rotations_v4.btf": {
            "kind": "ubo2014",
            "directions": directions,
            "images": linear,
            "options": {
                "scalar_size": 4,
                "colour_model": 11,
                "rotations": True,
                "version": 4,
                "components": 5,
            },
        },
    }


def _srgb_encode(linear: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 encoding (numpy only, for the reference's environment)."""
    linear = np.clip(linear, 0.0, 1.0)
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)


def write(folder: Path) -> None:
    """The example files and spectwin's decodes of them (``spectwin.npz``)."""
    from recon.btf.rgb_import import open_rgb_images

    folder.mkdir(parents=True, exist_ok=True)
    decoded = {}
    for name, example in _examples().items():
        path = folder / name
        if example["kind"] == "ubo2003":
            write_ubo2003(path, example["angles"], example["images"])
        elif example["kind"] == "atrium_hdr":
            write_atrium_hdr(path, example["angles"], example["images"].reshape(-1, 6, 8, 3))
        else:
            directions = example["directions"]
            write_ubo2014(
                path, directions, directions, example["images"], **example.get("options", {})
            )
        images = open_rgb_images(path)
        decoded[f"{name}/angles"] = images.angles_deg
        decoded[f"{name}/images"] = np.stack([images.read(p) for p in range(images.n_pairs)])
    np.savez(folder / "spectwin.npz", **decoded)


def compare(folder: Path) -> dict:
    """btf-extractor's decodes of the example files against spectwin's."""
    from btf_extractor import AtriumHdr, Ubo2003, Ubo2014

    ours = np.load(folder / "spectwin.npz")
    report = {}
    for name, example in _examples().items():
        angles, images = ours[f"{name}/angles"], ours[f"{name}/images"]
        path = str(folder / name)
        if example["kind"] == "ubo2014":
            reference = Ubo2014(path)
            inverse = {index: key for key, index in reference.angles_vs_index_dict.items()}
            count = len(example["directions"])
            pairs = [(light, view) for light in range(count) for view in range(count)]
            theirs = [reference._angleindex_to_image_unsafe(*pair)[..., ::-1] for pair in pairs]
            their_angles = np.array([inverse[pair] for pair in pairs])
            difference = np.abs(np.stack(theirs) - images)
            angles_agree = bool(np.allclose(their_angles, angles.round(1), atol=0.051))
            report[name] = {
                "max_abs_difference": float(difference.max()),
                "max_value": float(images.max()),
                "angles_agree": angles_agree,
            }
            continue
        if example["kind"] == "atrium_hdr" and not _freeimage_available():
            report[name] = {"compared": False, "why": "imageio's FreeImage library is missing"}
            continue
        reader = Ubo2003(path) if example["kind"] == "ubo2003" else AtriumHdr(path)
        keys = [tuple(int(v) for v in row) for row in angles]
        theirs = np.stack([reader.angles_to_image(*key)[..., ::-1] for key in keys])
        if example["kind"] == "ubo2003":
            ours_encoded = np.round(255 * _srgb_encode(images))
            difference = np.abs(theirs.astype(float) - ours_encoded)
            unit = "8-bit code values"
        else:
            difference = np.abs(theirs - images)
            unit = "linear"
        report[name] = {
            "max_abs_difference": float(difference.max()),
            "unit": unit,
            "angles_agree": set(keys) == set(reader.angles_set),
        }
    return report


def _freeimage_available() -> bool:
    """btf-extractor reads ATRIUM HDR through imageio's FreeImage plugin, a library imageio
    downloads on first use."""
    try:
        import imageio

        imageio.plugins.freeimage.get_freeimage_lib()
    except Exception:  # noqa: BLE001 - any failure means the plugin cannot run
        return False
    return True


if __name__ == "__main__":
    command, target = sys.argv[1], Path(sys.argv[2])
    if command == "write":
        write(target)
    else:
        print(json.dumps(compare(target), indent=2))
