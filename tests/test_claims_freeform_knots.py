"""The free-form upper bound of claims 9 and 10: its breaks chosen by cross-validation, crowded toward the
largest X visited (where Model 1's pole acts), with the penalty (calibrate/freeform.py)."""
import numpy as np
import pytest

from calibrate import freeform
from tests.test_calibrate_freeform import FAST, model1_truth  # noqa: F401  (Model 1 truth with a strong pole)


def test_crowded_breaks_span_the_same_range_and_shrink_toward_the_largest_X():
    even = np.array(freeform.breaks_over(-0.1, 0.1, 6, 1.0))
    crowded = np.array(freeform.breaks_over(-0.1, 0.1, 6, 2.0))
    assert np.allclose(np.diff(even), 0.04)
    assert crowded[0] == -0.1 and crowded[-1] == pytest.approx(0.1)
    gaps = np.diff(crowded)
    assert np.all(np.diff(gaps) < 0) and gaps[-1] == pytest.approx(0.2 / 25)   # (1 - 4/5)^2 of the span


def test_default_layouts_offer_even_and_crowded_breaks_and_more_of_them():
    s = freeform.FreeformSettings(n_breaks=5)
    assert s.knot_layouts() == ((5, 1.0), (5, freeform.CROWDING), (7, freeform.CROWDING))
    with pytest.raises(ValueError, match="knot layout"):
        freeform.FreeformSettings(layouts=((1, 1.0),))


def test_cross_validation_chooses_the_layout_and_the_penalty_together(model1_truth):
    res = model1_truth["res"]
    cv = res["cv_all"]
    assert len(cv) == len(FAST.knot_layouts()) * len(FAST.penalties) and cv["chosen"].sum() == 1
    best = cv.loc[cv["chosen"]].iloc[0]
    assert best["cv_score"] == cv["cv_score"].min()
    n, crowd = res["layout"]
    assert (n, crowd) == (best["n_breaks"], best["crowding"]) and res["penalty"] == best["penalty"]
    assert res["spline"].breaks == freeform.breaks_for(model1_truth["replays"], n, crowd)
    rows = res["table"][res["table"]["section"] == "cv"]
    assert len(rows) == len(cv) and rows["detail"].str.contains("crowding").all()
