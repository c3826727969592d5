"""One published number beside ours, and the verdict that compares them."""

from __future__ import annotations

import math
from dataclasses import dataclass

REPRODUCED = "reproduced"
DIRECTION = "direction reproduced"
NOT_REPRODUCED = "not reproduced"
NOT_MEASURED = "not measured"


@dataclass(frozen=True)
class Claim:
    """A quantity a source published and the same quantity measured by a study.

    ``tolerance`` is relative: ours within ``tolerance * |published|`` of the published value is
    reproduced. ``baseline`` is the value meaning "no effect" (1.0 for a ratio, 0.0 for a
    difference): when it is set and ours lies on the same side of it as the published value,
    the direction is reproduced even if the magnitude is not. ``reason`` says why a claim is
    not (or not fully) reproduced, or why it could not be measured (``ours`` None or NaN; an
    infinite ``ours`` is compared like any other)."""

    source: str
    figure: str
    quantity: str
    published: float
    ours: float | None
    conditions: str
    tolerance: float
    baseline: float | None = None
    reason: str = ""

    def __post_init__(self):
        if not self.tolerance >= 0:
            raise ValueError(f"{self.quantity}: tolerance must be >= 0, got {self.tolerance}")

    @property
    def verdict(self) -> str:
        # An infinite value is a measurement (the PSNR of an exact image); only a missing or
        # NaN one is not.
        if self.ours is None or math.isnan(self.ours):
            return NOT_MEASURED
        # The edge counts as inside; float rounding of the difference must not decide it.
        if abs(self.ours - self.published) <= self.tolerance * abs(self.published) * (1 + 1e-12):
            return REPRODUCED
        if self.baseline is not None:
            side_ours = math.copysign(1.0, self.ours - self.baseline)
            side_published = math.copysign(1.0, self.published - self.baseline)
            if self.ours != self.baseline and side_ours == side_published:
                return DIRECTION
        return NOT_REPRODUCED

    def as_row(self) -> dict:
        """The claim as a table row, the verdict spelled out with its tolerance."""
        verdict = self.verdict
        if verdict == REPRODUCED:
            verdict = f"{REPRODUCED} within {self.tolerance:.0%}"
        return {
            "source": self.source, "figure": self.figure, "quantity": self.quantity,
            "published": self.published, "ours": self.ours, "conditions": self.conditions,
            "verdict": verdict, "reason": self.reason,
        }
