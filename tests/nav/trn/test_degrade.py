"""Check 6 (TRN part): beams off the map or on NaN cells dropped, a ping with no usable beam a
no-op, never NaN in an estimate; bad options are one clear error; same seed, same numbers."""

from __future__ import annotations

import numpy as np
import pytest

from nav.errors import NavInputError
from nav.trn import ParticleTrn, PointMassTrn, Soundings, TerrainMap, TrnOptions
from tests.nav.trn.toy import ping, terrain_depth, toy_map

FILTERS = [
    ("particle", lambda o, x, p: ParticleTrn(o, x, p, 4)),
    ("point mass", lambda o, x, p: PointMassTrn(o, x, p, 4)),
]


@pytest.mark.parametrize(("name", "make"), FILTERS)
def test_a_ping_with_no_usable_beam_changes_nothing(name, make):
    tmap = toy_map(size_m=100.0)
    f = make(TrnOptions(particles=2000), np.array([50.0, 50.0]), 4.0 * np.eye(2))
    before = f.estimate()
    far = Soundings(np.zeros((4, 2)) + [500.0, 0.0], np.full(4, 40.0), np.ones(4, bool))
    none = Soundings(np.zeros((4, 2)), np.zeros(4), np.zeros(4, bool))
    for s in (far, none):
        u = f.update(tmap, s, 0.3)
        assert u.used_beams == 0 and not u.reinitialised
        after = f.estimate()
        np.testing.assert_array_equal(after[0], before[0])
        np.testing.assert_array_equal(after[1], before[1])


@pytest.mark.parametrize(("name", "make"), FILTERS)
def test_flying_off_a_small_map_with_nan_cells_never_gives_nan(name, make):
    # a 60 m map with a hole of no data; the vehicle flies across it and 60 m beyond its edge
    x = np.arange(0.0, 61.0)
    z = terrain_depth(x[None, :], x[:, None])
    z[20:30, 25:40] = np.nan
    tmap = TerrainMap(x, x, z)
    rng = np.random.default_rng(0)
    truth = np.array([10.0, 25.0])
    f = make(TrnOptions(particles=2000), truth + [1.0, -1.0], 4.0 * np.eye(2))
    used = []
    for _ in range(100):
        truth = truth + [1.2, 0.0]
        f.predict([1.2, 0.0], 0.01 * np.eye(2))
        u = f.update(tmap, ping(tmap, truth, rng, 0.3), 0.3)
        used.append(u.used_beams)
        m, p = f.estimate()
        assert np.all(np.isfinite(m)) and np.all(np.isfinite(p))
        assert np.isfinite(u.nis) and np.isfinite(u.ess)
    assert max(used) == 4 and used[-1] == 0  # on the map, then off it


def test_beams_on_nan_cells_are_dropped_from_the_likelihood():
    # one beam on a hole: the update equals the update without that beam
    tmap = toy_map(size_m=100.0)
    z = tmap.depth_m.copy()
    hole = TerrainMap(tmap.x_m, tmap.y_m, np.where(np.arange(101)[None, :] > 80, np.nan, z))
    s = ping(tmap, np.array([80.0, 50.0]), np.random.default_rng(1), 0.3)
    s_hole = Soundings(s.offset_m, s.depth_m, s.valid)
    keep = s.offset_m[:, 0] < 0  # the two beams to the west stay off the hole
    s_two = Soundings(s.offset_m[keep], s.depth_m[keep], s.valid[keep])
    a = PointMassTrn(TrnOptions(), [80.0, 50.0], 0.5 * np.eye(2))
    b = PointMassTrn(TrnOptions(), [80.0, 50.0], 0.5 * np.eye(2))
    ua = a.update(hole, s_hole, 0.3)
    b.update(tmap, s_two, 0.3)
    assert ua.used_beams == 2
    np.testing.assert_allclose(a.estimate()[0], b.estimate()[0], atol=1e-9)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("particles", 5),
        ("grid_points", 4.5),
        ("sigma_bias_m", -1.0),
        ("resample_threshold", 0.0),
        ("roughening", np.nan),
        ("nis_window", 0),
        ("divergence_probability", 0.7),
        ("reinitialise", 1),
        ("reinit_sigma_m", 0.0),
        ("grid_sigmas", 2.0),
        ("min_cell_m", 0.0),
    ],
)
def test_bad_options_are_one_clear_error(field, value):
    with pytest.raises(NavInputError, match=f"TrnOptions.{field} = ") as e:
        TrnOptions(**{field: value})
    assert "\n" not in str(e.value) and "must be" in str(e.value)


@pytest.mark.parametrize(("name", "make"), FILTERS)
def test_bad_state_or_noise_is_one_clear_error(name, make):
    with pytest.raises(NavInputError, match="P0_m2"):
        make(TrnOptions(particles=100), [0.0, 0.0], [[1.0, 2.0], [2.0, 1.0]])
    f = make(TrnOptions(particles=100), [0.0, 0.0], np.eye(2))
    with pytest.raises(NavInputError, match="displacement_m"):
        f.predict([np.nan, 0.0], np.eye(2))
    with pytest.raises(NavInputError, match="sigma_m"):
        f.update(toy_map(50.0), Soundings(np.zeros((2, 2)), np.ones(2), np.ones(2, bool)), -1.0)
    with pytest.raises(NavInputError, match="soundings with offset_m"):
        f.update(toy_map(50.0), Soundings(np.zeros((3, 2)), np.ones(2), np.ones(2, bool)), 0.3)


def test_same_seed_same_numbers():
    tmap = toy_map(size_m=100.0)
    out = []
    for _ in range(2):
        rng = np.random.default_rng(9)
        f = ParticleTrn(TrnOptions(particles=3000), [50.0, 50.0], 9.0 * np.eye(2), 17)
        for _ in range(10):
            f.predict([0.5, 0.5], 0.01 * np.eye(2))
            f.update(tmap, ping(tmap, np.array([52.0, 49.0]), rng, 0.3), 0.3)
        out.append(f.estimate())
    np.testing.assert_array_equal(out[0][0], out[1][0])
    np.testing.assert_array_equal(out[0][1], out[1][1])
