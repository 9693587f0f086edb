"""The TRN posterior Cramer-Rao bound against closed forms on a plane of known gradient."""

from __future__ import annotations

import numpy as np
import pytest

from nav.errors import NavInputError
from nav.trn import TerrainMap, terrain_information, trn_pcrb

G = np.array([0.3, -0.1])  # the plane's gradient, m/m
SIGMA = 0.5
M = 4


def plane_gradients(k):
    """The gradients a map of the plane gives at 4 beams over k pings (they are all G)."""
    x = np.arange(0.0, 101.0, 5.0)
    plane = TerrainMap(x, x, 40.0 + G[0] * x[None, :] + G[1] * x[:, None])
    pts = np.random.default_rng(0).uniform(10.0, 90.0, (k, M, 2))
    g, ok = plane.gradient(pts[..., 0], pts[..., 1])
    assert ok.all()
    return g


def test_without_process_noise_the_information_adds_up():
    k = 25
    j0 = np.diag([1 / 100.0, 1 / 25.0])
    b = trn_pcrb(
        j0, np.zeros((k, 2, 2)), plane_gradients(k), np.full((k, M), SIGMA), np.ones((k, M), bool)
    )
    for i in [0, 9, 24]:
        expected = np.linalg.inv(j0 + (i + 1) * M * np.outer(G, G) / SIGMA**2)
        np.testing.assert_allclose(b[i], expected, rtol=1e-10)


def test_with_process_noise_the_bound_reaches_the_scalar_riccati_fixed_point():
    # isotropic J0 and Q: along u = G/|G| the information obeys j' = 1/(1/j + q) + a with
    # a = M |G|^2 / sigma^2, whose fixed point is j = a/2 + sqrt(a^2/4 + a/q); across G no
    # information arrives and the bound grows by q per step
    k, q, p0 = 400, 0.01, 4.0
    b = trn_pcrb(
        np.eye(2) / p0,
        np.repeat(q * np.eye(2)[None], k, 0),
        plane_gradients(k),
        np.full((k, M), SIGMA),
        np.ones((k, M), bool),
    )
    a = M * G @ G / SIGMA**2
    j_inf = a / 2 + np.sqrt(a * a / 4 + a / q)
    u = G / np.linalg.norm(G)
    v = np.array([-u[1], u[0]])
    assert u @ b[-1] @ u == pytest.approx(1.0 / j_inf, rel=1e-9)
    assert v @ b[-1] @ v == pytest.approx(p0 + k * q, rel=1e-9)


def test_a_marginalised_common_bias_takes_the_information_of_one_beam_out():
    # equal gradients and sigmas: G^T (s^2 I + sb^2 1 1^T)^-1 G = g g^T M / (s^2 + M sb^2)
    g = plane_gradients(1)
    sb = 2.0
    info = terrain_information(g, np.full((1, M), SIGMA), np.ones((1, M), bool), sb)[0]
    r = SIGMA**2 * np.eye(M) + sb**2 * np.ones((M, M))
    np.testing.assert_allclose(info, g[0].T @ np.linalg.solve(r, g[0]), rtol=1e-10)
    np.testing.assert_allclose(info, np.outer(G, G) * M / (SIGMA**2 + M * sb**2), rtol=1e-10)


def test_inactive_beams_give_no_information_and_runs_are_averaged():
    g = plane_gradients(2)
    act = np.array([[True, False, False, False], [False] * 4])
    info = terrain_information(g, np.full((2, M), SIGMA), act)
    np.testing.assert_allclose(info[0], np.outer(G, G) / SIGMA**2, rtol=1e-10)
    np.testing.assert_array_equal(info[1], 0.0)
    two = np.stack([g, 2.0 * g])  # two paths: the information is their mean
    b = trn_pcrb(np.eye(2), np.zeros((2, 2, 2)), two, SIGMA, np.ones((2, 2, M), bool))
    np.testing.assert_allclose(b[0], np.linalg.inv(np.eye(2) + 2.5 * M * np.outer(G, G) / SIGMA**2))


def test_bad_shapes_are_one_clear_error():
    with pytest.raises(NavInputError, match="J0"):
        trn_pcrb(np.zeros((2, 2)), np.zeros((1, 2, 2)), np.zeros((1, M, 2)), SIGMA, True)
    with pytest.raises(NavInputError, match="Q"):
        trn_pcrb(np.eye(2), np.zeros((3, 2, 2)), np.zeros((1, M, 2)), SIGMA, True)
