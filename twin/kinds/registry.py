"""The rig registry: one :class:`RigKind` per kind of rig, looked up by the rig name its stores
record.

A capture store records its rig and the program that made it in its ``rig`` attribute
(:class:`hwbridge.schema.RigAttrs`); a BTF store records the rig of the capture it was processed
from in its ``rig`` (:class:`recon.btf.schema.BTFAttrs`). The commands find what to do with a
store by that name here, never by testing strings or types themselves. A new rig is a new
:class:`RigKind` passed to :func:`register` (see ARCHITECTURE.md, "Adding a rig").
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

from pydantic import BaseModel

from hwbridge.schema import RigAttrs
from hwbridge.store import CaptureStore
from recon.btf.store import BTFStore
from recon.errors import InputError
from twin.kinds.kind import Outcome, ProgramKind, ProgramSettings, RigKind
from twin.studies.sweep_file import SweepKind

__all__ = [
    "ProgramKind",
    "Outcome",
    "ProgramSettings",
    "RigKind",
    "btf_rig_kind",
    "capture_program",
    "capture_rig_kind",
    "config_rig_kind",
    "register",
    "rig_kind",
    "rig_kinds",
    "sweep_kind",
    "unregister",
]


_KINDS: dict[str, RigKind] = {}


def register(kind: RigKind) -> RigKind:
    """Add ``kind`` to the registry (a kind of the same name is replaced); returns it."""
    _KINDS[kind.name] = kind
    return kind


def unregister(name: str) -> None:
    """Remove the kind of rig ``name`` from the registry (nothing if it is not there)."""
    _KINDS.pop(name, None)


def rig_kinds() -> tuple[RigKind, ...]:
    """Every registered kind of rig, in the order registered."""
    _load_builtin()
    return tuple(_KINDS.values())


def rig_kind(name: object) -> RigKind:
    """The kind of rig named ``name``."""
    _load_builtin()
    if not isinstance(name, str) or name not in _KINDS:
        raise InputError(f"rig: expected one of {sorted(_KINDS)}, got {name!r}")
    return _KINDS[name]


def sweep_kind(name: str) -> SweepKind:
    """The sweep models and functions of the kind of rig named ``name``."""
    return rig_kind(name).sweep


def capture_rig_kind(capture: CaptureStore) -> RigKind:
    """The kind of rig that captured ``capture`` (the ``rig`` of its rig attribute)."""
    return rig_kind(_recorded(capture).rig)


def capture_program(capture: CaptureStore) -> tuple[RigKind, ProgramKind]:
    """The kind of rig and the capture program that made ``capture``."""
    recorded = _recorded(capture)
    kind = rig_kind(recorded.rig)
    return kind, kind.program(recorded.program)


def _recorded(capture: CaptureStore) -> RigAttrs:
    """The rig and program ``capture`` records."""
    try:
        return capture.rig_attrs(RigAttrs)
    except InputError as error:
        raise InputError(
            f"{error}; expected a capture store of one of {sorted(_names())}"
        ) from None


def btf_rig_kind(btf: BTFStore | Path) -> RigKind:
    """The kind of rig whose capture a BTF store was processed from (its ``rig``)."""
    store = btf if isinstance(btf, BTFStore) else BTFStore.open(btf)
    name = store.metadata.rig
    if name is None:
        raise InputError(
            f"{store.path}: a BTF store that no rig of spectwin processed (imported); expected "
            "one processed from a capture store"
        )
    return rig_kind(name)


def config_rig_kind(config: BaseModel) -> RigKind:
    """The kind of rig that a loaded rig file ``config`` describes (its ``rig`` field)."""
    return rig_kind(getattr(config, "rig", None))


def _names() -> list[str]:
    _load_builtin()
    return list(_KINDS)


@cache
def _load_builtin() -> None:
    """Register the built-in rigs on first use, the spectral gonioreflectometer and the LED dome
    (a kind registered before keeps its place)."""
    from twin.kinds.dome import DOME
    from twin.kinds.gonio import GONIO

    for kind in (GONIO, DOME):
        _KINDS.setdefault(kind.name, kind)
