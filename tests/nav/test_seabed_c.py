"""The seabed shift's C arithmetic (``nav/seabed_shift.c``, behind :func:`nav.seabed.fit_slopes`
and :func:`nav.seabed.shift_estimate`) against the numpy implementation it replaced
(``tests/nav/seabed_reference.py``), on random images with dropouts and on degenerate cases."""

import numpy as np
import pytest

from nav import seabed
from nav.errors import NavError, NavInputError
from nav.seabed import BeamGeometry, SlopeBasis, fit_slopes, shift_estimate

from . import seabed_reference

GEO = BeamGeometry.seed004()
P = 40


def _images(seed, geo=GEO):
    """Random image pairs over a harmonic seabed, with dropouts and degenerate paths.

    Path 0 has two beams with an echo (no shift), path 1 nine (no slope fit: it needs more than
    the nine functions of the harmonic basis), path 2 ten, path 3 a flat seabed (only the
    vertical observed), path 4 no echo in image k+1; the others lose a random tenth of their
    beams in each image. Ranges without an echo are NaN.
    """
    rng = np.random.default_rng(seed)
    mi, mj = geo.shape
    pos = np.column_stack([rng.uniform(0, 300, P), rng.uniform(-20, 20, P), rng.normal(-10, 1, P)])
    att0 = np.column_stack([rng.normal(0, 0.05, P), rng.uniform(-1.1, 1.1, P)])
    att1 = att0 + rng.normal(0, 0.05, (P, 2))
    step = 2.0 * np.column_stack([np.cos(att0[:, 1]), np.sin(att0[:, 1]), np.zeros(P)])
    amp = rng.uniform(0.5, 3.0, (P, 4))
    amp[3] = 0.0  # flat

    def ranges(x, att):
        # the depth below each beam's start by a few fixed-point steps on z = -30 + h(x, y)
        e = geo.directions(att)  # (P, mi, mj, 3)
        L = np.full((P, mi, mj), 25.0)
        for _ in range(30):
            foot = x[:, None, None] + L[..., None] * e
            w = 2 * np.pi / 20.0
            h = (
                amp[:, 0, None, None] * np.sin(w * foot[..., 0])
                + amp[:, 1, None, None] * np.cos(w * foot[..., 1])
                + amp[:, 2, None, None] * np.sin(2 * w * foot[..., 0])
                + amp[:, 3, None, None] * np.cos(2 * w * foot[..., 1])
            )
            L = (x[:, None, None, 2] - (-30.0 + h)) / -e[..., 2]
        noise = rng.normal(0, 0.1, L.shape)
        noise[3] = 0.0  # the flat seabed: feet at one depth
        return L + noise

    L0 = ranges(pos, att0)
    L1 = ranges(pos + step, att1)
    echo0 = rng.random((P, mi, mj)) > 0.1
    echo1 = rng.random((P, mi, mj)) > 0.1
    for p, n in ((0, 2), (1, 9), (2, 10)):
        echo0[p] = echo1[p] = False
        echo0[p].flat[:n] = echo1[p].flat[:n] = True
    echo1[4] = False
    cmd = step + rng.normal(0, 0.1, (P, 3))
    return (
        np.where(echo0, L0, np.nan),
        np.where(echo1, L1, np.nan),
        att0,
        att1,
        echo0,
        echo1,
        pos + rng.normal(0, 5, (P, 3)),
        cmd,
    )


def _assert_close(got, want, rtol):
    """Equal to ``rtol`` of each path's largest magnitude."""
    g, w = np.asarray(got, float), np.asarray(want, float)
    assert g.shape == w.shape
    scale = np.abs(w).reshape(len(w), -1).max(axis=1)
    err = np.abs(g - w).reshape(len(w), -1).max(axis=1)
    assert np.all(err <= rtol * scale), f"paths {np.flatnonzero(err > rtol * scale)}"


@pytest.mark.parametrize("covariance", ["residual", "range_noise"])
@pytest.mark.parametrize(
    ("reading", "delta_e"),
    [("one_attitude", "linear"), ("turning", "linear"), ("turning", "exact")],
)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_c_shift_equals_the_numpy_reference(seed, reading, delta_e, covariance):
    L0, L1, att0, att1, echo0, echo1, pos, cmd = _images(seed)
    kw = dict(
        echo=echo0,
        next_echo=echo1,
        reading=reading,
        delta_e=delta_e,
        position_m=pos,
        covariance=covariance,
        commanded_shift_m=cmd if seed % 2 else None,
    )
    got = shift_estimate(L0, L1, GEO, att0, att1, **kw)
    want = seabed_reference.shift_estimate(L0, L1, GEO, att0, att1, **kw)
    assert np.array_equal(got.beams, want.beams)
    assert np.array_equal(got.rank, want.rank)
    assert np.array_equal(got.ok, want.ok)
    assert got.ok.dtype == want.ok.dtype == bool
    # rounding times the condition of the slope fit (up to seabed.FIT_C_CONDITION) and of eq. 15
    _assert_close(got.shift_m, want.shift_m, 1e-10)
    _assert_close(got.covariance_m2, want.covariance_m2, 1e-10)
    _assert_close(got.residual_rms, want.residual_rms, 1e-10)
    # every case is there: no shift (too few beams, no fit), a flat seabed seen only vertically,
    # whole shifts
    assert not want.ok[[0, 1, 4]].any() and want.ok[2]
    assert want.rank[3] == 1 and np.all(want.rank[5:] == 3)
    if seed % 2:
        assert np.array_equal(got.shift_m[~got.ok], cmd[~got.ok])


@pytest.mark.parametrize("kind", ["harmonic", "plane", "quadratic"])
@pytest.mark.parametrize("seed", [0, 3])
def test_c_shift_with_other_bases_and_given_slopes_equals_the_reference(seed, kind):
    L0, L1, att0, att1, echo0, echo1, pos, _ = _images(seed)
    basis = SlopeBasis(kind, 17.0, 23.0, 3) if kind == "harmonic" else SlopeBasis(kind)
    kw = dict(echo=echo0, next_echo=echo1, reading="turning", position_m=pos, basis=basis)
    got = shift_estimate(L0, L1, GEO, att0, att1, **kw)
    want = seabed_reference.shift_estimate(L0, L1, GEO, att0, att1, **kw)
    assert np.array_equal(got.ok, want.ok) and np.array_equal(got.rank, want.rank)
    # a quadratic fit of a harmonic seabed leaves eq. 15 ill-conditioned (A^T A up to 1 / rcond^2
    # = 1e8): two eigen-decompositions of it agree to about that times the rounding error
    _assert_close(got.shift_m, want.shift_m, 1e-8)
    _assert_close(got.covariance_m2, want.covariance_m2, 1e-8)
    # known slopes, the same plane under every beam: A has rank 1 (rank-deficient eq. 15)
    slopes = np.broadcast_to([0.1, -0.2, 1.0], (*L0.shape, 3)).copy()
    slopes[5:] += np.random.default_rng(seed).normal(0, 0.3, (P - 5, *L0.shape[1:], 3))
    kw["slopes"] = slopes
    got = shift_estimate(L0, L1, GEO, att0, att1, **kw)
    want = seabed_reference.shift_estimate(L0, L1, GEO, att0, att1, **kw)
    assert np.array_equal(got.rank, want.rank) and want.rank[3] == 1
    _assert_close(got.shift_m, want.shift_m, 1e-8)
    _assert_close(got.covariance_m2, want.covariance_m2, 1e-8)
    _assert_close(got.residual_rms, want.residual_rms, 1e-8)


def test_tiny_rcond_takes_the_svd_as_the_reference():
    L0, L1, att0, att1, echo0, echo1, pos, cmd = _images(4)
    kw = dict(echo=echo0, next_echo=echo1, position_m=pos, rcond=1e-10, commanded_shift_m=cmd)
    got = shift_estimate(L0, L1, GEO, att0, att1, **kw)
    want = seabed_reference.shift_estimate(L0, L1, GEO, att0, att1, **kw)
    assert np.array_equal(got.rank, want.rank) and np.array_equal(got.ok, want.ok)
    _assert_close(got.shift_m, want.shift_m, 1e-10)
    _assert_close(got.covariance_m2, want.covariance_m2, 1e-10)


@pytest.mark.parametrize("kind", ["harmonic", "plane", "quadratic"])
def test_c_slope_fit_equals_the_reference_and_hands_ill_conditioned_paths_to_numpy(
    kind, monkeypatch
):
    rng = np.random.default_rng(7)
    pts = np.concatenate(
        [rng.uniform(-15, 15, (30, 64, 2)), rng.normal(-30, 2, (30, 64, 1))], axis=-1
    )
    valid = rng.random((30, 64)) > 0.2
    valid[0, 12:] = False  # 12 points at most: a quadratic fit's, not the harmonic one's
    pts[1, :, 1] = 0.5 * pts[1, :, 0]  # feet on a line: rank-deficient (the SVD)
    pts[2, :, 1] = 0.5 * pts[2, :, 0] + 1e-3 * rng.normal(size=64)  # nearly: ill-conditioned
    basis = SlopeBasis(kind)
    handed = []
    numpy_fit = seabed._fit_slopes_numpy

    def spy(points, *args):
        handed.append(len(points))
        return numpy_fit(points, *args)

    monkeypatch.setattr(seabed, "_fit_slopes_numpy", spy)
    grad, ok = fit_slopes(pts, valid, basis)
    want, want_ok = seabed_reference.fit_slopes(pts, valid, basis)
    assert np.array_equal(ok, want_ok)
    _assert_close(grad, want, 1e-10)
    assert 2 <= sum(handed) < 10  # the bad paths went to numpy, the rest were fitted in C
    # all paths to numpy: the numbers of the reference exactly
    monkeypatch.setattr(seabed, "FIT_C_CONDITION", 0.0)
    grad, ok = fit_slopes(pts, valid, basis)
    assert np.array_equal(grad, want) and np.array_equal(ok, want_ok)


def test_slope_fit_refuses_mismatched_shapes():
    with pytest.raises(NavInputError, match="fit_slopes: points of shape"):
        fit_slopes(np.zeros((2, 10, 3)), np.ones((2, 9), bool), SlopeBasis.seed004())


def test_a_missing_c_library_is_an_error_that_says_how_to_build_it(monkeypatch):
    monkeypatch.setattr(seabed, "_SHIFT_LIBRARY", "_no_such_library")
    seabed._shift_library.cache_clear()
    try:
        with pytest.raises(NavError, match=r"not built: reinstall the package"):
            shift_estimate(
                np.full((1, 8, 8), 20.0), np.full((1, 8, 8), 20.0), GEO, np.zeros((1, 2))
            )
    finally:
        seabed._shift_library.cache_clear()
