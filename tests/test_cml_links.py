"""The rain medium against measured rain attenuation on real commercial microwave links
(pycomlink's example data: RADOLAN radar rain along each link; rainuav.cml), beside ITU-R P.838-3
from the independent ``itur`` package. The full comparison (500 links) is
``python experiments/cml_links.py`` on the validation page; this runs its first 20 links."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.slow


@pytest.mark.timeout(120)
def test_the_medium_is_as_close_to_real_links_as_p838() -> None:
    from rainuav.cml import compare

    res = compare(links=20)
    ours, p838 = res["all"]["rainuav"], res["all"]["p838"]
    # The pipeline sees the rain: thousands of wet five-minute intervals, and both predictions
    # follow the measurements (r 0.68 on these links; 0.5 would mean the radar's rain and the
    # links' attenuation have come apart: a broken alignment, resampling or processing).
    assert res["intervals"] > 5000
    assert ours["r"] > 0.5 and p838["r"] > 0.5
    # The goal: at least as close as P.838. Measured on these links: bias +0.52 against +0.68
    # dB, RMSE 2.38 against 2.39 dB, r 0.684 against 0.680. Tolerance 0.05 dB on the RMSE and
    # 0.01 on r: the two differ by less than that on these links, far below what the radar
    # reference resolves; a medium that drifted from its published values fails it.
    assert abs(ours["bias_db"]) <= abs(p838["bias_db"])
    assert ours["rmse_db"] <= p838["rmse_db"] + 0.05
    assert ours["r"] >= p838["r"] - 0.01
    # By band and polarisation the same holds for the bias, group by group.
    for g in res["groups"]:
        assert abs(g["rainuav"]["bias_db"]) <= abs(g["p838"]["bias_db"]) + 0.05, g
    meas = res["_arrays"][0]
    assert np.all(meas >= 0) and np.isfinite(meas).all()
    # The shipped spread of a rain loss (measured on the even links of all 500) on these
    # links' odd ones, which it never saw: 71% within one sigma and 97% within two here (68.0%
    # and 96.5% on the 250 odd links of 500); held to 55-80% and 88-99%.
    from rainuav.radio.measured.prior import rain_spread_scores

    meas, ours, _, _, link = res["_arrays"]
    held = rain_spread_scores(meas, ours, link)["held_out"]
    assert 0.55 <= held["within_one_sigma"] <= 0.80, held
    assert 0.88 <= held["within_two_sigma"] <= 0.99, held
    assert held["crps_db"] < held["crps_no_spread_db"]
