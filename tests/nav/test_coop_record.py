"""TeamRecord refuses malformed input with one line naming the field."""

import numpy as np
import pytest

from nav.cooperative import TeamRecord
from nav.errors import NavInputError


def small_record(**change):
    n, v, k, f, m = 2, 3, 5, 1, 2
    fields = dict(
        t_s=np.arange(k) * 0.5,
        dr_step_m=np.zeros((n, v, k - 1, 2)),
        dr_step_cov_m2=np.broadcast_to(np.eye(2) * 1e-3, (n, v, k - 1, 2, 2)).copy(),
        depth_m=np.ones((n, v, k)),
        start_m=np.zeros((n, v, 2)),
        start_cov_m2=np.broadcast_to(np.eye(2), (n, v, 2, 2)).copy(),
        fix_tick=np.array([2]),
        fix_vehicle=np.array([0]),
        fix_m=np.zeros((n, f, 2)),
        fix_cov_m2=np.broadcast_to(np.eye(2), (n, f, 2, 2)).copy(),
        fix_present=np.ones((n, f), dtype=bool),
        range_sender=np.array([0, 1]),
        range_receiver=np.array([1, 2]),
        range_tx_tick=np.array([1, 2]),
        range_rx_tick=np.array([1, 3]),
        range_m=np.full((n, m), 10.0),
        range_tx_local_s=np.zeros((n, m)),
        range_rx_local_s=np.full((n, m), 10.0 / 1500.0),
        range_present=np.ones((n, m), dtype=bool),
    )
    fields.update(change)
    return TeamRecord(**fields)


def test_a_valid_record_reports_its_sizes():
    r = small_record()
    assert (r.n_runs, r.n_vehicles, r.n_samples) == (2, 3, 5)
    assert r.velocity_m_s().shape == (2, 3, 4, 2)


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (dict(dr_step_m=np.zeros((2, 3, 5, 2))), "dr_step_m"),
        (dict(range_m=np.zeros((2, 3))), "range_m"),
        (dict(t_s=np.array([0.0, 1.0, 1.0, 2.0, 3.0])), "t_s"),
        (dict(kind="usbl"), "kind"),
        (dict(sound_speed_m_s=0.0), "sound_speed_m_s"),
        (dict(sigma_range_m=float("nan")), "sigma_range_m"),
        (dict(range_receiver=np.array([0, 2])), "range_receiver"),
        (dict(range_sender=np.array([0, 3])), "range_sender"),
        (dict(range_rx_tick=np.array([0, 3])), "range_rx_tick"),
        (dict(fix_tick=np.array([5])), "fix_tick"),
        (dict(range_present=np.ones((2, 2))), "range_present"),
        (dict(fix_tick=np.array([1.5])), "fix_tick"),
        (dict(depth_m=np.full((2, 3, 5), np.nan)), "depth_m"),
        (dict(fix_cov_m2=np.zeros((2, 1, 2, 2))), "fix_cov_m2"),
        (dict(start_cov_m2=-np.ones((2, 3, 2, 2))), "start_cov_m2"),
    ],
)
def test_bad_fields_are_named(change, field):
    with pytest.raises(NavInputError, match=f"TeamRecord.{field} "):
        small_record(**change)


def test_absent_values_may_hold_anything():
    rm = np.full((2, 2), np.nan)
    pres = np.zeros((2, 2), dtype=bool)
    small_record(range_m=rm, range_present=pres)
    with pytest.raises(NavInputError, match="range_m"):
        small_record(range_m=rm)
