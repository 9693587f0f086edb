"""nav.trn.DvlAidedTrn: DR on the DVL and the filters on one clock, against the same steps
driven by hand (the held velocity's displacement, its covariance, an update every period)."""

from __future__ import annotations

import numpy as np
import pytest

from nav.errors import NavInputError
from nav.trn import DvlAidedOptions, DvlAidedTrn, ParticleTrn, PointMassTrn

from .toy import options, ping, toy_map

OPTS = DvlAidedOptions(
    update_period_s=1.0, sigma_bottom_m_s=0.05, sigma_water_m_s=0.2, sounding_sigma_m=0.3
)


def _pings(n: int, rng: np.random.Generator):
    """Times at 5 Hz with jitter, velocities, bottom-lock flags (one in five on water track)."""
    t = np.cumsum(rng.uniform(0.15, 0.25, n))
    v = np.column_stack([1.2 + 0.1 * rng.standard_normal(n), 0.4 + 0.1 * rng.standard_normal(n)])
    lock = rng.uniform(size=n) > 0.2
    return t, v, lock


def test_the_clock_equals_the_filters_driven_by_hand_bit_for_bit():
    rng = np.random.default_rng(5)
    tmap = toy_map()
    x0, P0 = np.array([150.0, 150.0]), np.diag([4.0, 9.0])
    opts = options(particles=2000, grid_points=32)
    t, v, lock = _pings(60, rng)
    truth = x0 + np.cumsum(v * np.diff(np.concatenate([[0.0], t]))[:, None], axis=0)

    pf_a, pmf_a = ParticleTrn(opts, x0, P0, 3), PointMassTrn(opts, x0, P0)
    aided = DvlAidedTrn(OPTS, 0.0, x0, P0, (pf_a, pmf_a))
    pf_b, pmf_b = ParticleTrn(opts, x0, P0, 3), PointMassTrn(opts, x0, P0)
    t_prev, due_at, acc, dr = 0.0, OPTS.update_period_s, np.zeros((2, 2)), x0.copy()
    q_dr = P0.copy()
    updates = 0
    noise = np.random.default_rng(9)
    for k in range(len(t)):
        q_a = aided.advance(t[k], np.array([*v[k - 1 if k else 0], 0.0]), bool(lock[k]))
        # by hand: the velocity held since the previous ping, its sigma by the lock
        dt = t[k] - t_prev
        t_prev = t[k]
        d = v[k - 1 if k else 0] * dt
        s = OPTS.sigma_bottom_m_s if lock[k] else OPTS.sigma_water_m_s
        q = (dt * s) ** 2 * np.eye(2)
        dr, q_dr = dr + d, q_dr + q
        pf_b.predict(d, q)
        pmf_b.predict(d, q)
        acc = acc + q
        if t[k] + 1e-9 < due_at:
            assert q_a is None
            continue
        due_at += OPTS.update_period_s
        assert q_a is not None and np.array_equal(q_a, acc)
        acc = np.zeros((2, 2))
        snd = ping(tmap, truth[k], noise, 0.3)
        ua = aided.update(tmap, snd)
        ub = (pf_b.update(tmap, snd, 0.3), pmf_b.update(tmap, snd, 0.3))
        assert [u.used_beams for u in ua] == [u.used_beams for u in ub]
        updates += 1
    assert updates == int(t[-1] // OPTS.update_period_s)
    for a, b in ((pf_a, pf_b), (pmf_a, pmf_b)):
        ma, Pa = a.estimate()
        mb, Pb = b.estimate()
        assert np.array_equal(ma, mb) and np.array_equal(Pa, Pb)
    assert np.allclose(aided.dr.position, dr, rtol=0, atol=1e-9)
    assert np.allclose(aided.dr.covariance, q_dr, rtol=1e-12)


def test_bad_options_times_and_velocities_are_one_clear_error():
    with pytest.raises(NavInputError, match="update_period_s = 0"):
        DvlAidedOptions(0, 0.05, 0.2, 0.3)
    with pytest.raises(NavInputError, match="sigma_water_m_s = nan"):
        DvlAidedOptions(1.0, 0.05, float("nan"), 0.3)
    aided = DvlAidedTrn(OPTS, 10.0, [0.0, 0.0], np.eye(2), ())
    with pytest.raises(NavInputError, match="before the previous"):
        aided.advance(9.0, [1.0, 0.0], True)
    with pytest.raises(NavInputError, match="velocity_world_m_s"):
        aided.advance(10.2, [np.nan, 0.0], True)
    with pytest.raises(NavInputError, match="P0_m2"):
        DvlAidedTrn(OPTS, 0.0, [0.0, 0.0], [[1.0, 2.0], [0.0, 1.0]], ())
