"""EMVA 1288 measurements on disk: the descriptor file and its images, read with clear errors and
written in the same format.

A measurement is a folder with a descriptor text file (``EMVA1288_Data.txt``) and the images it
lists. After ``#`` comments, the descriptor holds::

    v 3.0                        # the release of EMVA 1288 the measurement follows
    n BITS WIDTH HEIGHT          # once: bit depth and size of every image
    b EXPOSURE_NS PHOTONS        # an illuminated step: exposure time in ns, photons per pixel,
    i images/b_000_snap_001.png  #   then its images, one per line (at least two)
    d EXPOSURE_NS                # a dark step at that exposure time, then its images

Steps with two images make the temporal measurement (photon transfer, sensitivity, linearity,
dark current); one illuminated and one dark step with more than two images, at one exposure
time, make the spatial measurement (DSNU, PRNU). An exposure time may be 0: the official
reference set 002 starts both series there (``b 000.00 000.35``), a camera's shortest exposure
with the light it lets through. A measurement may also vary the photons at one exposure time
(reference set 003: one dark step for all bright ones). This is the format that the ``emva1288``
package reads; :func:`read_descriptor` checks a file completely, naming the line and what was
expected, before any analysis starts.

References
----------
- EMVA Standard 1288, Release 3.0 (2010), European Machine Vision Association: sections 6-8
  (temporal, spatial and dark-current measurements).
- The ``emva1288`` package (EMVA1288/emva1288 on GitHub): the descriptor format
  (``emva1288.process.parser``).
- EMVA1288/datasets on GitHub: the reference sets 001 (Basler CCD), 002 (STEMMER IMAGING CMOS)
  and 003 (HCI Heidelberg simulation).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, replace
from pathlib import Path, PureWindowsPath
from typing import Any, Literal

import numpy as np
from PIL import Image

from recon.errors import InputError

__all__ = [
    "DESCRIPTOR_NAME",
    "EMVADescriptor",
    "EMVAStep",
    "read_descriptor",
    "read_frame",
    "write_descriptor",
    "write_frame",
]

DESCRIPTOR_NAME = "EMVA1288_Data.txt"
_FORMS = {
    "v": ("v VERSION", (str,)),
    "n": ("n BITS WIDTH HEIGHT (whole numbers)", (int, int, int)),
    "b": ("b EXPOSURE_NS PHOTONS (numbers)", (float, float)),
    "d": ("d EXPOSURE_NS (a number)", (float,)),
    "i": ("i IMAGE_FILE", (str,)),
}


@dataclass(frozen=True)
class EMVAStep:
    """One step of the measurement: its images at one exposure time and photon count.

    ``photons`` is the mean number of photons per pixel (0 for a dark step); ``images`` are the
    file names as the descriptor writes them (relative to its folder); ``line`` is the line of
    the ``b`` or ``d`` entry (0 for a step planned in memory).
    """

    kind: Literal["bright", "dark"]
    exposure_ns: float
    photons: float
    images: tuple[str, ...]
    line: int = 0

    @property
    def exposure_s(self) -> float:
        return self.exposure_ns / 1e9

    @property
    def spatial(self) -> bool:
        """Part of the spatial measurement (more than two images)."""
        return len(self.images) > 2


@dataclass(frozen=True)
class EMVADescriptor:
    """A measurement: bit depth, image size and its steps in the order of the file.

    ``path`` is the descriptor file (``None`` for a measurement planned in memory); image names
    are relative to its folder.
    """

    bit_depth: int
    width: int
    height: int
    steps: tuple[EMVAStep, ...]
    path: Path | None = None
    version: str = "3.0"

    def image_path(self, name: str) -> Path:
        """The file of an image name (``/`` or ``\\`` separated) beside the descriptor."""
        return _beside(self.path, name)

    @property
    def exposure_range_s(self) -> tuple[float, float]:
        """Shortest and longest exposure time a camera needs to repeat the measurement, s.

        A step at 0 ns (the official reference set 002 starts its series with one) is not an
        exposure a camera can make: it is the camera's shortest, so it does not count here.
        """
        times = [step.exposure_s for step in self.steps if step.exposure_ns > 0]
        return min(times), max(times)

    @property
    def frame_count(self) -> int:
        return sum(len(step.images) for step in self.steps)


def _beside(descriptor_path: Path | None, name: str) -> Path:
    folder = descriptor_path.parent if descriptor_path is not None else Path()
    return folder.joinpath(*PureWindowsPath(name).parts)


def _fail(path: Path, line: int, message: str) -> InputError:
    return InputError(f"{path}: line {line}: {message}")


def _parse_line(path: Path, number: int, text: str) -> tuple[str, tuple[Any, ...]]:
    tokens = text.split()
    form = _FORMS.get(tokens[0])
    if form is None:
        raise _fail(
            path, number, f"{text!r}: unknown entry; expected a line starting with v, n, b, d or i"
        )
    expected, types = form
    if len(tokens) != 1 + len(types):
        raise _fail(path, number, f"{text!r}: expected '{expected}'")
    try:
        # The emva1288 parser accepts a decimal comma; so does this check.
        values = tuple(
            kind(token.replace(",", ".")) if kind is float else kind(token)
            for kind, token in zip(types, tokens[1:], strict=True)
        )
    except ValueError:
        raise _fail(path, number, f"{text!r}: expected '{expected}'") from None
    return tokens[0], values


def _read_lines(path: Path) -> list[tuple[int, str]]:
    if not path.is_file():
        raise InputError(
            f"{path}: no such descriptor file; expected an EMVA 1288 descriptor ({DESCRIPTOR_NAME})"
        )
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise InputError(
            f"{path}: not a readable text file ({error}); expected an EMVA 1288 descriptor"
        ) from error
    return [
        (number, line.strip())
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.strip().startswith("#")
    ]


def _check_size(path: Path, line: int, bits: int, width: int, height: int) -> None:
    if not 1 <= bits <= 16:
        raise _fail(path, line, f"bit depth {bits}: expected 1 to 16 bits")
    if width <= 0 or height <= 0:
        raise _fail(path, line, f"image size {width}x{height}: expected positive sizes")


def _check_step(path: Path, step: EMVAStep) -> None:
    if not np.isfinite(step.exposure_ns) or step.exposure_ns < 0:
        raise _fail(path, step.line, f"exposure time {step.exposure_ns} ns: expected >= 0")
    if step.kind == "bright" and not (np.isfinite(step.photons) and step.photons > 0):
        raise _fail(path, step.line, f"photon count {step.photons}: expected > 0")
    if len(step.images) < 2:
        raise _fail(
            path, step.line, f"{len(step.images)} image line(s) after it; expected at least two"
        )


def _check_structure(path: Path, steps: list[EMVAStep]) -> None:
    """The rules of the emva1288 analysis, checked here to name the offending line."""
    if all(step.exposure_ns == 0 for step in steps):
        raise InputError(
            f"{path}: every step at exposure time 0 ns; expected at least one step with a "
            "positive exposure time"
        )
    sets = Counter((step.spatial, step.exposure_ns, step.photons) for step in steps)
    for step in steps:
        if sets[(step.spatial, step.exposure_ns, step.photons)] > 1:
            raise _fail(
                path,
                step.line,
                f"a second {step.kind} step at {step.exposure_ns:g} ns and {step.photons:g} "
                "photons; expected one set of images per exposure time and photon count",
            )
    for spatial in (False, True):
        kinds = {(step.exposure_ns, step.kind): step for step in steps if step.spatial == spatial}
        for (exposure_ns, kind), step in kinds.items():
            other = "dark" if kind == "bright" else "bright"
            if (exposure_ns, other) not in kinds:
                raise _fail(
                    path,
                    step.line,
                    f"no {other} step with {'more than two' if spatial else 'two'} images at "
                    f"{exposure_ns:g} ns; expected a bright and a dark step at every exposure time",
                )
    spatial_times = {step.exposure_ns for step in steps if step.spatial}
    spatial_bright = [step for step in steps if step.spatial and step.kind == "bright"]
    if len(spatial_times) != 1 or len(spatial_bright) != 1:
        raise InputError(
            f"{path}: {len(spatial_bright)} spatial bright step(s) at {len(spatial_times)} "
            "exposure time(s); expected one bright and one dark step with more than two images "
            "each, at one exposure time (the spatial measurement)"
        )
    temporal_bright = [step for step in steps if not step.spatial and step.kind == "bright"]
    if len(temporal_bright) < 3:
        raise InputError(
            f"{path}: {len(temporal_bright)} bright step(s) with two images; expected at least "
            "3 (the temporal measurement, up to saturation)"
        )


def read_descriptor(path: str | Path) -> EMVADescriptor:
    """Read and check an EMVA 1288 descriptor and the presence of every image it lists.

    Parameters
    ----------
    path
        The descriptor file (``EMVA1288_Data.txt``).

    Returns
    -------
    EMVADescriptor
        Bit depth, image size and the steps in the order of the file.

    Raises
    ------
    InputError
        A malformed or unknown line, a missing ``n`` line, a negative exposure time or every one
        0, a step with fewer than two images, a bright step without a dark one, no spatial
        measurement, a missing image: one line
        naming the file, the line and what was expected. The images' contents are checked when
        they are read (:func:`read_frame`).
    """
    path = Path(path)
    size: tuple[int, int, int] | None = None
    version = "3.0"
    steps: list[EMVAStep] = []
    images: list[tuple[int, str]] = []

    def close_step() -> None:
        if steps:
            steps[-1] = replace(steps[-1], images=tuple(name for _, name in images))
            _check_step(path, steps[-1])
            for number, name in images:
                if not _beside(path, name).is_file():
                    raise _fail(path, number, f"image {name} does not exist")
        images.clear()

    for number, text in _read_lines(path):
        entry, values = _parse_line(path, number, text)
        if entry == "i":
            if not steps:
                raise _fail(path, number, f"{text!r}: an image before any b or d line")
            images.append((number, values[0]))
        elif entry in ("b", "d"):
            close_step()
            photons = values[1] if entry == "b" else 0.0
            kind: Literal["bright", "dark"] = "bright" if entry == "b" else "dark"
            steps.append(EMVAStep(kind, values[0], photons, (), number))
        elif entry == "n":
            if size is not None:
                raise _fail(path, number, "a second n line; expected one 'n BITS WIDTH HEIGHT'")
            _check_size(path, number, *values)
            size = values
        else:
            version = values[0]
    close_step()
    if size is None:
        raise InputError(f"{path}: no 'n BITS WIDTH HEIGHT' line; expected one before the steps")
    if not steps:
        raise InputError(f"{path}: no b or d lines; expected the measurement's steps")
    _check_structure(path, steps)
    bits, width, height = size
    return EMVADescriptor(bits, width, height, tuple(steps), path, version)


def read_frame(path: Path, *, bit_depth: int, shape: tuple[int, int]) -> np.ndarray:
    """One image of a measurement, checked against the descriptor's ``n`` line.

    Parameters
    ----------
    path
        A greyscale image file (PNG or TIFF).
    bit_depth
        The descriptor's bit depth: the image must hold whole numbers in ``[0, 2**bit_depth)``
        in a container at least that deep (a 12-bit measurement in 16-bit images).
    shape
        ``(height, width)`` of the descriptor.

    Raises
    ------
    InputError
        An unreadable file, a colour or floating-point image, a wrong size, values or a
        container that do not fit the bit depth.
    """
    try:
        with Image.open(path) as image:
            bands = image.getbands()
            frame = np.asarray(image)
    except (OSError, ValueError, Image.DecompressionBombError) as error:
        reason = str(error).replace(f" '{path}'", "")  # PIL repeats the path
        raise InputError(
            f"{path}: unreadable image ({reason}); expected a greyscale PNG or TIFF"
        ) from error
    if len(bands) != 1 or frame.ndim != 2:
        raise InputError(f"{path}: {len(bands)} channels; expected one greyscale channel")
    if frame.dtype.kind not in "ui":
        raise InputError(f"{path}: {frame.dtype} pixels; expected whole numbers")
    if frame.dtype.itemsize * 8 < bit_depth:
        raise InputError(
            f"{path}: {frame.dtype.itemsize * 8}-bit image for a {bit_depth}-bit measurement "
            f"(n line); expected images of at least {bit_depth} bits"
        )
    if frame.shape != tuple(shape):
        raise InputError(
            f"{path}: {frame.shape[1]}x{frame.shape[0]} px; the n line says {shape[1]}x{shape[0]}"
        )
    top = 2**bit_depth - 1
    if frame.size and (frame.max() > top or frame.min() < 0):
        raise InputError(
            f"{path}: values up to {int(frame.max())} do not fit the measurement's {bit_depth} "
            f"bits (n line); expected 0 to {top}"
        )
    return frame


def write_frame(descriptor: EMVADescriptor, name: str, frame: np.ndarray) -> Path:
    """Write one image of a measurement as a 16-bit greyscale PNG (``name`` as in the
    descriptor, relative to its folder)."""
    path = descriptor.image_path(name)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.asarray(frame, dtype=np.uint16)).save(path, compress_level=1)
    return path


def write_descriptor(descriptor: EMVADescriptor, header: Iterable[str] = ()) -> Path:
    """Write the descriptor text of ``descriptor`` to its ``path``, after ``#`` header lines.

    The images are written separately (:func:`write_frame`), step by step as they are made.
    """
    if descriptor.path is None:
        raise InputError("write_descriptor: the descriptor needs a path to write to")
    lines = [f"# {line}".rstrip() for line in header]
    lines += [
        f"v {descriptor.version}",
        f"n {descriptor.bit_depth} {descriptor.width} {descriptor.height}",
    ]
    for step in descriptor.steps:
        if step.kind == "bright":
            lines.append(f"b {float(step.exposure_ns)!r} {float(step.photons)!r}")
        else:
            lines.append(f"d {float(step.exposure_ns)!r}")
        lines += [f"i {name}" for name in step.images]
    descriptor.path.parent.mkdir(parents=True, exist_ok=True)
    descriptor.path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return descriptor.path
