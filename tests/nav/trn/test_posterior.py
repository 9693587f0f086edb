"""Check 3 of issue 23: the particle and point-mass filters against the posterior computed on a
fine grid, their NEES over 100 runs, and re-initialisation after a 50 m initial error."""

from __future__ import annotations

import numpy as np
import pytest

from nav.metrics import nees, nees_band
from nav.trn import ParticleTrn, PointMassTrn, TrnOptions
from tests.nav.trn.toy import dvl_offsets, ping, toy_map

SIGMA_M = 0.3
SIGMA_BIAS_M = 10.0


def fine_grid_posterior(tmap, x0, p0, steps, pings, half_m=20.0, cell_m=0.04):
    """Mean and covariance of p(x_K | z_1..K) on a fine grid, written out independently.

    The motion is known exactly (Q = 0), so the position at ping k is ``x_K - (D_K - D_k)``
    with ``D_k`` the sum of the displacements up to ping k; the prior is ``N(x0 + D_K, P0)``
    and each ping's likelihood is the Gaussian of the innovations with the dense covariance
    ``s^2 I + sigma_b^2 1 1^T`` (inverted with numpy, not with Sherman-Morrison).
    """
    total = np.sum(steps, axis=0)
    centre = x0 + total
    ax = np.arange(-half_m, half_m + cell_m / 2, cell_m)
    px, py = np.meshgrid(centre[0] + ax, centre[1] + ax, indexing="ij")
    pts = np.column_stack([px.ravel(), py.ravel()])
    dev = pts - centre
    logp = -0.5 * np.einsum("ni,ij,nj->n", dev, np.linalg.inv(p0), dev)
    m = dvl_offsets().shape[0]
    r = SIGMA_M**2 * np.eye(m) + SIGMA_BIAS_M**2 * np.ones((m, m))
    r_inv = np.linalg.inv(r)
    done = np.zeros(2)
    for step, s in zip(steps, pings, strict=True):
        done = done + step
        at = pts - (total - done)
        hit = at[:, None, :] + s.offset_m[None]
        h, ok = tmap.depth(hit[..., 0], hit[..., 1])
        assert ok.all()
        e = s.depth_m[None, :] - h
        logp = logp - 0.5 * np.einsum("ni,ij,nj->n", e, r_inv, e)
    w = np.exp(logp - logp.max())
    w /= w.sum()
    mean = w @ pts
    d = pts - mean
    return mean, (d * w[:, None]).T @ d


def run_pings(flt, tmap, steps, pings, q):
    out = []
    for step, s in zip(steps, pings, strict=True):
        flt.predict(step, q)
        out.append(flt.update(tmap, s, SIGMA_M))
    return out


@pytest.fixture(scope="module")
def toy_case():
    tmap = toy_map()
    rng = np.random.default_rng(7)
    p0 = np.diag([3.0**2, 2.0**2])
    truth0 = np.array([180.0, 210.0])
    x0 = truth0 + rng.multivariate_normal(np.zeros(2), p0)
    steps = [np.array([2.0, 1.0])] * 3
    truth = truth0.copy()
    pings = []
    for step in steps:
        truth = truth + step
        pings.append(ping(tmap, truth, rng, SIGMA_M, bias_m=2.5))
    mean, cov = fine_grid_posterior(tmap, x0, p0, steps, pings)
    return tmap, x0, p0, steps, pings, mean, cov


@pytest.mark.slow
def test_particle_filter_matches_the_fine_grid_posterior(toy_case):
    tmap, x0, p0, steps, pings, mean, cov = toy_case
    f = ParticleTrn(TrnOptions(particles=20_000, sigma_bias_m=SIGMA_BIAS_M), x0, p0, 3)
    ups = run_pings(f, tmap, steps, pings, np.zeros((2, 2)))
    m, p = f.estimate()
    # Monte Carlo tolerance: a weighted mean of ESS effective draws has a standard error of
    # sqrt(P_ii / ESS); the variances' relative standard error is sqrt(2 / ESS) (Gaussian); 4
    # standard errors, with the smallest ESS seen over the pings
    ess = min(u.ess for u in ups)
    assert ess > 500
    sd = np.sqrt(np.diag(cov))
    assert np.all(np.abs(m - mean) <= 4.0 * sd / np.sqrt(ess)), (m - mean, sd, ess)
    rel = np.abs(np.diag(p) - np.diag(cov)) / np.diag(cov)
    assert np.all(rel <= 4.0 * np.sqrt(2.0 / ess)), (rel, ess)
    corr = cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1])
    corr_pf = p[0, 1] / np.sqrt(p[0, 0] * p[1, 1])
    assert abs(corr_pf - corr) <= 4.0 * (1 - corr**2) / np.sqrt(ess)


def test_point_mass_filter_matches_the_fine_grid_posterior(toy_case):
    tmap, x0, p0, steps, pings, mean, cov = toy_case
    f = PointMassTrn(TrnOptions(sigma_bias_m=SIGMA_BIAS_M), x0, p0, 0)
    run_pings(f, tmap, steps, pings, np.zeros((2, 2)))
    m, p = f.estimate()
    # the PMF's error is deterministic (its 64 x 64 grid against a 1000 x 1000 one): a
    # twentieth of a standard deviation in the mean, 5 % in the covariance
    sd = np.sqrt(np.diag(cov))
    assert np.all(np.abs(m - mean) <= 0.05 * sd), (m - mean, sd)
    assert np.all(np.abs(p - cov) <= 0.05 * np.sqrt(np.outer(np.diag(cov), np.diag(cov)))), (p, cov)


N_RUNS = 100
N_PINGS = 12
STEP_M = np.array([1.5, 0.5])
Q_M2 = 0.1**2 * np.eye(2)
P0_M2 = np.diag([4.0**2, 3.0**2])


def monte_carlo(make_filter, bias_m=2.5):
    """100 runs: truth drawn from the prior, random-walk motion, pings with a map offset.

    Returns the final errors ``(R, 2)``, covariances ``(R, 2, 2)`` and the true gradients at the
    footprints ``(R, K, 4, 2)`` (for the PCRB)."""
    tmap = toy_map()
    rng = np.random.default_rng(2024)
    errs, covs, grads = [], [], []
    off = dvl_offsets()
    for r in range(N_RUNS):
        x0 = np.array([120.0, 150.0]) + rng.uniform(0.0, 100.0, 2)
        truth = x0 + rng.multivariate_normal(np.zeros(2), P0_M2)
        f = make_filter(x0, r)
        g_run = []
        for _ in range(N_PINGS):
            truth = truth + STEP_M + rng.multivariate_normal(np.zeros(2), Q_M2)
            f.predict(STEP_M, Q_M2)
            f.update(tmap, ping(tmap, truth, rng, SIGMA_M, bias_m=bias_m), SIGMA_M)
            hit = truth + off
            g_run.append(tmap.gradient(hit[:, 0], hit[:, 1])[0])
        m, p = f.estimate()
        errs.append(m - truth)
        covs.append(p)
        grads.append(g_run)
    return np.array(errs), np.array(covs), np.array(grads)


@pytest.fixture(scope="module")
def pf_runs():
    opt = TrnOptions(particles=5_000, sigma_bias_m=SIGMA_BIAS_M)
    return monte_carlo(lambda x0, r: ParticleTrn(opt, x0, P0_M2, 1000 + r))


@pytest.fixture(scope="module")
def pmf_runs():
    opt = TrnOptions(sigma_bias_m=SIGMA_BIAS_M)
    return monte_carlo(lambda x0, r: PointMassTrn(opt, x0, P0_M2, r))


@pytest.mark.slow
@pytest.mark.parametrize("runs", ["pf_runs", "pmf_runs"])
def test_nees_over_100_runs_is_in_the_chi_square_band(runs, request):
    errs, covs, _ = request.getfixturevalue(runs)
    low, high = nees_band(2, N_RUNS, 0.95)
    avg = float(np.mean(nees(errs, covs)))
    assert low <= avg <= high, (avg, low, high)


@pytest.mark.parametrize("runs", ["pf_runs", "pmf_runs"])
def test_rmse_over_runs_is_at_least_the_pcrb(runs, request):
    from nav.trn import trn_pcrb

    errs, _, grads = request.getfixturevalue(runs)
    bound = trn_pcrb(
        np.linalg.inv(P0_M2),
        np.repeat(Q_M2[None], N_PINGS, axis=0),
        grads,
        np.full(grads.shape[:-1], SIGMA_M),
        np.ones(grads.shape[:-1], bool),
        sigma_bias_m=SIGMA_BIAS_M,
    )[-1]
    mse = float(np.mean(np.sum(errs**2, axis=1)))
    # Monte Carlo tolerance: the mean of 100 squared errors of 2 dof has a relative standard
    # error of about sqrt(2 / (2 * 100)) = 0.1 (chi-square); 3 of them below the bound allowed
    assert mse >= 0.7 * float(np.trace(bound)), (mse, np.trace(bound))
    # and the bound is not vacuous: it is below the prior's spread moved by the noise
    assert np.trace(bound) < 0.2 * np.trace(P0_M2)


@pytest.mark.slow
def test_reinitialisation_recovers_from_a_50_m_initial_error():
    tmap = toy_map()
    rng = np.random.default_rng(5)
    truth = np.array([200.0, 160.0])
    p0 = 3.0**2 * np.eye(2)
    filters = {
        "particle": ParticleTrn(TrnOptions(reinit_sigma_m=30.0), truth + [50.0, 0.0], p0, 11),
        "point mass": PointMassTrn(
            TrnOptions(reinit_sigma_m=30.0, grid_points=128), truth + [50.0, 0.0], p0, 0
        ),
    }
    step = np.array([0.0, 1.0])
    for _ in range(120):
        truth = truth + step + rng.normal(0.0, 0.05, 2)
        s = ping(tmap, truth, rng, SIGMA_M)
        for f in filters.values():
            f.predict(step, 0.05**2 * np.eye(2))
            f.update(tmap, s, SIGMA_M)
    for name, f in filters.items():
        m, p = f.estimate()
        e = m - truth
        assert f.reinitialisations >= 1, name
        assert float(nees(e, p)) <= 13.8, (name, e, p)  # chi-square(2) 0.999 quantile
        assert np.hypot(*e) < 2.0, (name, e)
