"""What a processed BTF store was made from, so that a resumed processing is given the same.

Processing writes a BTF store pair by pair, and an interrupted one resumes with the pairs still
pending. The pairs written before and after the interruption are one BTF only when both were made
from the same inputs: the same capture store, the same calibration file and the same texture
size. The store records them at its creation (its ``inputs`` attribute,
:class:`recon.btf.schema.BTFInputs`) as content hashes:

- the capture store: SHA-256 of its attributes (plan, rig, seed, backend, software version),
  without the ``complete`` flag, which changes as it is captured (:func:`capture_sha256`);
- the calibration: SHA-256 of the calibration file's bytes (:func:`file_sha256`);
- the texture's size in texels per side.

:func:`require_same_inputs` refuses a resume that names other inputs, naming each difference.
A store made before the inputs were recorded (no ``inputs``) is compared by its texture size only.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from hwbridge.store import CaptureStore
from recon.btf.schema import BTFInputs
from recon.btf.store import BTFStore
from recon.errors import InputError, MissingDataError

__all__ = ["InputDigests", "capture_sha256", "file_sha256", "input_digests", "require_same_inputs"]

_BLOCK = 1 << 20


@dataclass(frozen=True)
class InputDigests:
    """The content hashes of a processing's capture store and calibration file.

    Attributes
    ----------
    capture_sha256
        :func:`capture_sha256` of the capture store.
    calibration_sha256
        :func:`file_sha256` of the calibration file.
    """

    capture_sha256: str
    calibration_sha256: str

    def recorded(self, texels: int) -> BTFInputs:
        """The ``inputs`` attribute of a store made from these inputs at ``texels`` per side."""
        return BTFInputs(
            capture_sha256=self.capture_sha256,
            calibration_sha256=self.calibration_sha256,
            texels=texels,
        )


def capture_sha256(capture: CaptureStore) -> str:
    """SHA-256 (hex) of a capture store's attributes without its ``complete`` flag.

    Parameters
    ----------
    capture
        An open capture store.

    Returns
    -------
    str
        64 hex digits; equal for two stores whose plan, rig and seed are equal.
    """
    attributes = {name: value for name, value in capture.attrs.items() if name != "complete"}
    text = json.dumps(attributes, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def file_sha256(path: str | Path) -> str:
    """SHA-256 (hex) of a file's bytes, read in blocks of 1 MiB."""
    path = Path(path)
    digest = hashlib.sha256()
    try:
        with path.open("rb") as handle:
            for block in iter(lambda: handle.read(_BLOCK), b""):
                digest.update(block)
    except FileNotFoundError:
        raise MissingDataError(f"{path}: no such file; expected a calibration file") from None
    except OSError as error:
        raise InputError(f"{path}: not readable ({error.strerror})") from None
    return digest.hexdigest()


def input_digests(capture: CaptureStore, calibration: str | Path) -> InputDigests:
    """The content hashes of the inputs of a processing (module docstring).

    Parameters
    ----------
    capture
        The capture store processed.
    calibration
        The calibration file it is processed with.

    Returns
    -------
    InputDigests
        Both hashes.
    """
    return InputDigests(capture_sha256(capture), file_sha256(calibration))


def require_same_inputs(btf: BTFStore, digests: InputDigests | None, texels: int | None) -> None:
    """Refuse to resume ``btf`` with inputs other than those it was made from.

    Parameters
    ----------
    btf
        The store to resume.
    digests
        The hashes of the capture store and calibration file given now; ``None``: not known
        (a caller with calibration data but no file), not compared.
    texels
        The texture size asked for now; ``None``: the store's own.

    Raises
    ------
    InputError
        Naming every input that differs from the one the store records.
    """
    recorded = btf.metadata.inputs
    differences = []
    if texels is not None and btf.texels != (texels, texels):
        differences.append(f"texels {texels}, the store has {btf.texels[0]}")
    if recorded is not None and digests is not None:
        if digests.capture_sha256 != recorded.capture_sha256:
            differences.append(
                f"another capture store (attributes sha256 {digests.capture_sha256[:12]}, the "
                f"store was made from {recorded.capture_sha256[:12]})"
            )
        if digests.calibration_sha256 != recorded.calibration_sha256:
            differences.append(
                f"another calibration file (sha256 {digests.calibration_sha256[:12]}, the store "
                f"was made with {recorded.calibration_sha256[:12]})"
            )
    if differences:
        raise InputError(
            f"{btf.path}: cannot resume with {'; '.join(differences)}: its pairs would mix "
            "inputs; expected the capture store, calibration file and texels it was made from"
        )
