"""Shared test fixtures."""

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)


def _truncate(file: Path) -> None:
    file.write_bytes(file.read_bytes()[:7])


def _flip_a_bit(file: Path) -> None:
    data = bytearray(file.read_bytes())
    data[len(data) // 2] ^= 0x04
    file.write_bytes(bytes(data))


CHUNK_DAMAGE = {"deleted": Path.unlink, "truncated": _truncate, "flipped": _flip_a_bit}
"""The ways a store's chunk file is damaged on disk: lost, cut short, one bit flipped."""


@dataclass(frozen=True)
class ChunkDamage:
    """One way of damaging a chunk file: ``damage(file)`` does it, ``damage.kind`` names it."""

    kind: str

    def __call__(self, file: Path) -> None:
        CHUNK_DAMAGE[self.kind](file)


@pytest.fixture(params=sorted(CHUNK_DAMAGE))
def damage(request) -> ChunkDamage:
    """Each way a chunk file is damaged, in turn (parametrizes the test)."""
    return ChunkDamage(request.param)


@pytest.fixture
def chunk_damage() -> dict[str, ChunkDamage]:
    """Every way of damaging a chunk file, by name."""
    return {kind: ChunkDamage(kind) for kind in CHUNK_DAMAGE}
