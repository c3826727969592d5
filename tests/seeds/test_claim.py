import pytest

from jaxrender.seeds.claim import (DIRECTION, NOT_MEASURED, NOT_REPRODUCED, REPRODUCED,
                                   Claim)


def claim(ours, published=0.40, tolerance=0.10, baseline=None):
    return Claim("Decima", "slide 1", "waves ratio", published, ours, "foliage", tolerance,
                 baseline)


@pytest.mark.parametrize("ours,baseline,expected", [
    (0.40, None, REPRODUCED),
    (0.44, None, REPRODUCED),          # exactly at the 10% edge
    (0.36, None, REPRODUCED),
    (0.45, None, NOT_REPRODUCED),
    (0.70, 1.0, DIRECTION),            # fewer waves than forward, not by as much
    (1.20, 1.0, NOT_REPRODUCED),       # the opposite side of "no effect"
    (1.00, 1.0, NOT_REPRODUCED),       # no effect at all is not a direction
    (None, 1.0, NOT_MEASURED),
    (float("nan"), None, NOT_MEASURED),
    (float("inf"), None, NOT_REPRODUCED),  # an exact image's PSNR: measured, not the paper's
    (float("inf"), 0.0, DIRECTION),        # published 0.40 > 0, ours on the same side
    (float("-inf"), 0.0, NOT_REPRODUCED),  # the opposite side
])
def test_verdict_against_hand_worked_cases(ours, baseline, expected):
    assert claim(ours, baseline=baseline).verdict == expected, (ours, baseline)


def test_row_names_the_tolerance_of_a_reproduced_claim():
    row = claim(0.41).as_row()
    assert row["verdict"] == "reproduced within 10%", row
    assert claim(0.9, baseline=1.0).as_row()["verdict"] == DIRECTION


def test_negative_tolerance_is_refused():
    with pytest.raises(ValueError, match="tolerance"):
        claim(0.4, tolerance=-0.1)
