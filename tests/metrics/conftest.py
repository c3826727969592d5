"""Fresh random inputs for every run, with the seed reported in every failure message."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

# Small images keep the oracle comparisons cheap on two shared CPU cores.
H, W = 48, 64


@dataclass
class Seeded:
    rng: np.random.Generator
    seed: int

    def pair(self, shape=(H, W, 3), noise=0.1, dtype=np.float64):
        """A random image in [0, 1] and a noisy copy of it (clamped), like a render and its
        reference."""
        a = self.rng.random(shape)
        b = np.clip(a + noise * self.rng.standard_normal(shape), 0.0, 1.0)
        return a.astype(dtype), b.astype(dtype)

    def msg(self, what: str) -> str:
        return f"{what} (seed {self.seed})"


@pytest.fixture
def seeded() -> Seeded:
    seed = int(np.random.SeedSequence().entropy % (2**32))
    return Seeded(np.random.default_rng(seed), seed)
