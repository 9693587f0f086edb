"""The filters' parts against independent truth: the likelihood with hypotheses that miss beams
(the dense Gaussian, the sub-cloud mean), the prediction of both filters (Gaussian propagation),
systematic resampling and roughening (Gordon et al. 1993's jitter)."""

from __future__ import annotations

import numpy as np
import pytest

from nav.trn import ParticleTrn, PointMassTrn, TerrainMap, TrnOptions, log_likelihood
from nav.trn.particle import systematic_resample
from tests.nav.trn.toy import dvl_offsets, toy_map


def test_likelihood_with_some_hypotheses_off_the_map_keeps_the_dense_gaussian():
    # hypotheses near the map's east edge lose beams; those that keep all four must still
    # compare as the dense Gaussian with covariance s^2 I + sb^2 1 1^T says
    tmap = toy_map(size_m=100.0)
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(70.0, 99.0, 300), rng.uniform(30.0, 70.0, 300)])
    off = dvl_offsets()
    z = rng.normal(50.0, 2.0, 4)
    s = np.array([0.3, 0.4, 0.3, 0.5])
    sb = 3.0
    ll, _, ok = log_likelihood(pts, tmap, z, off, s, sb)
    full = ok.all(axis=1)
    assert 20 < full.sum() < 280  # both kinds are there
    h, _ = tmap.depth(pts[full, None, 0] + off[:, 0], pts[full, None, 1] + off[:, 1])
    e = z - h
    r_inv = np.linalg.inv(np.diag(s**2) + sb**2 * np.ones((4, 4)))
    dense = -0.5 * np.einsum("ni,ij,nj->n", e, r_inv, e)
    np.testing.assert_allclose(ll[full] - ll[full][0], dense - dense[0], rtol=1e-9, atol=1e-9)


def test_a_hypothesis_that_predicts_no_beam_gets_the_weighted_mean_likelihood():
    # one beam, no bias: the hypothesis off the map gets log sum_j w_j L_j / sum_j w_j over the
    # hypotheses on it (mbtrnav's sub-cloud rule)
    tmap = toy_map(size_m=100.0)
    pts = np.array([[20.0, 30.0], [40.0, 60.0], [55.0, 55.0], [500.0, 500.0]])
    w = np.array([0.1, 0.5, 0.2, 0.2])
    z, off, s = np.array([51.0]), np.zeros((1, 2)), np.array([0.8])
    ll, h, ok = log_likelihood(pts, tmap, z, off, s, 0.0, w)
    np.testing.assert_array_equal(ok[:, 0], [True, True, True, False])
    lik = np.exp(-0.5 * (z[0] - h[:3, 0]) ** 2 / s[0] ** 2) / np.sqrt(2 * np.pi * s[0] ** 2)
    np.testing.assert_allclose(ll[:3], np.log(lik), rtol=1e-12)
    assert ll[3] == pytest.approx(np.log(w[:3] @ lik / w[:3].sum()), rel=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["particle", "point mass"])
def test_prediction_propagates_a_gaussian(kind):
    # no measurement: after k steps the density is N(x0 + k d, P0 + k Q)
    x0, p0 = np.array([10.0, -5.0]), np.array([[4.0, 1.0], [1.0, 2.0]])
    d, q, k = np.array([0.7, -0.3]), np.array([[0.3, 0.1], [0.1, 0.2]]), 40
    if kind == "particle":
        f = ParticleTrn(TrnOptions(particles=200_000), x0, p0, 1)
        tol_m, tol_p = 0.03, 0.03  # 200,000 draws: standard errors ~0.01 m and ~0.3 %
    else:
        f = PointMassTrn(TrnOptions(), x0, p0)
        tol_m, tol_p = 1e-3, 0.01  # a grid's discretisation
    for _ in range(k):
        f.predict(d, q)
    m, p = f.estimate()
    want = p0 + k * q
    np.testing.assert_allclose(m, x0 + k * d, atol=tol_m * np.sqrt(want.diagonal()).max())
    np.testing.assert_allclose(p, want, atol=tol_p * want.diagonal().max())


def test_systematic_resampling_copies_each_particle_in_proportion_to_its_weight():
    w = np.array([0.1, 0.0, 0.45, 0.2, 0.25])
    n = w.size * 200
    big = np.repeat(w, 200) / 200
    counts = np.bincount(systematic_resample(big, np.random.default_rng(2)) // 200, minlength=5)
    # systematic resampling gives each particle floor or ceil of n w copies (Kitagawa 1996)
    assert np.all(np.abs(counts - n * w) <= 1), counts


def test_roughening_adds_gordons_jitter():
    # two particles of half the weight 100 m apart: after resampling, each copy sits at its parent
    # plus N(0, (K E N^-1/2)^2) with E = 100 m the span along x (Gordon et al. 1993)
    n, k = 40_000, 0.2
    f = ParticleTrn(TrnOptions(particles=n, roughening=k), [0.0, 0.0], np.eye(2), 0)
    f.particles = np.zeros((n, 2))
    f.particles[n // 2 :, 0] = 100.0
    f.weights = np.zeros(n)
    f.weights[[0, n - 1]] = 0.5
    f._resample()
    left = f.particles[f.particles[:, 0] < 50.0]
    assert abs(len(left) - n / 2) <= 1
    want = k * 100.0 / np.sqrt(n)
    assert np.std(left[:, 0]) == pytest.approx(want, rel=0.03)
    assert np.std(left[:, 1]) < 1e-12  # no span along y, no jitter
    assert f.resamplings == 1 and np.all(f.weights == 1.0 / n)


def test_no_beam_on_the_map_for_any_hypothesis_is_no_information():
    tmap = TerrainMap([0.0, 1.0], [0.0, 1.0], np.ones((2, 2)))
    pts = np.array([[5.0, 5.0], [6.0, 5.0]])
    ll, _, ok = log_likelihood(pts, tmap, np.array([3.0]), np.zeros((1, 2)), np.array([1.0]), 2.0)
    assert not ok.any() and np.all(ll == ll[0]) and np.all(np.isfinite(ll))
