"""Cooperative navigation of a synthetic team (generated in test_coop_synthetic from its truth):
acceptance check 4's ordering and consistency, covariance intersection against naive fusion
when the peers' estimates are correlated, and the CI weight against a brute-force minimum."""

import numpy as np
import pytest

from nav.cooperative import CoopOptions, ci_weight, team_metrics, team_tracks
from nav.cooperative.decentralised import _posterior_position_det, _posterior_state_log_det
from nav.errors import NavInputError
from tests.nav.test_coop_synthetic import make_team


@pytest.fixture(scope="module")
def team():
    return make_team(n=60, v=4, duration_s=300.0, seed=3)


@pytest.fixture(scope="module")
def metrics(team):
    out = {}
    for method, fusion in [
        ("dr", "ci"),
        ("ga2", "ci"),
        ("leader-ekf", "ci"),
        ("decentralised", "ci"),
        ("central", "ci"),
        ("decentralised", "naive"),
    ]:
        tracks = team_tracks(team.record, method, CoopOptions(fusion=fusion))
        key = method if fusion == "ci" else "naive"
        out[key] = team_metrics(tracks, team.truth_m, team.true_offset_s)
    return out


@pytest.mark.slow
def test_check4_central_beats_decentralised_beats_leader_only(metrics):
    for i in (1, 2, 3):  # the followers
        central = metrics["central"][i].mean_error_m
        dec = metrics["decentralised"][i].mean_error_m
        leader_only = min(metrics["leader-ekf"][i].mean_error_m, metrics["ga2"][i].mean_error_m)
        assert central <= dec <= leader_only, (i, central, dec, leader_only)
        # and the margins are real, not rounding
        assert dec < 0.9 * leader_only and central < 0.9 * dec


def test_check4_decentralised_is_not_over_confident_and_central_is_consistent(metrics):
    for i in range(4):
        dec, central = metrics["decentralised"][i], metrics["central"][i]
        assert dec.consistent, (i, dec.nees, dec.nees_band)
        low, high = central.nees_band
        assert low <= central.nees <= high, (i, central.nees, central.nees_band)
    # the clocks: both cooperative filters recover the followers' offsets (prior 1 ms)
    for i in (1, 2, 3):
        assert metrics["central"][i].clock_rmse_s < 1e-4
        assert metrics["decentralised"][i].clock_rmse_s < 4e-4
        assert metrics["leader-ekf"][i].clock_rmse_s is None


def test_naive_fusion_is_over_confident(metrics):
    # the same decentralised filter fusing the peers as if independent: the check of the band
    # sees it (the test that passes for CI can fail)
    for i in (1, 2, 3):
        naive = metrics["naive"][i]
        assert not naive.consistent, (i, naive.nees, naive.nees_band)
        assert naive.nees > 5 * naive.nees_band[1]


@pytest.mark.slow
def test_ci_covers_the_error_when_the_peers_estimates_are_correlated():
    # three vehicles launched from one ship: their starts share one error (the ship's GPS, 2 m
    # per axis) and each states only its own marginal covariance; no fixes, so ranges observe
    # the relative positions only and the common error never leaves. Naive fusion takes the
    # peers' estimates as independent and shrinks its covariance below the common error; CI
    # does not.
    team = make_team(n=100, v=3, duration_s=200.0, seed=8, fix_vehicles=())
    rec = team.record
    rng = np.random.default_rng(80)
    common = rng.normal(0, 2.0, (rec.n_runs, 1, 2))
    own = rng.normal(0, 1.0, (rec.n_runs, rec.n_vehicles, 2))
    start = team.truth_m[:, :, 0] + common + own
    start_cov = np.broadcast_to(np.eye(2) * 5.0, start.shape + (2,)).copy()
    fields = {f: getattr(rec, f) for f in rec.__dataclass_fields__}
    fields.update(start_m=start, start_cov_m2=start_cov)
    rec = type(rec)(**fields)
    ci = team_metrics(team_tracks(rec, "decentralised"), team.truth_m)
    naive = team_metrics(
        team_tracks(rec, "decentralised", CoopOptions(fusion="naive")), team.truth_m
    )
    for i in range(3):
        assert ci[i].consistent, (i, ci[i].nees, ci[i].nees_band)
        assert naive[i].nees > naive[i].nees_band[1], (i, naive[i].nees, naive[i].nees_band)


@pytest.mark.parametrize("criterion", ["position", "state"])
def test_ci_weight_is_the_minimum_of_its_criterion(criterion):
    rng = np.random.default_rng(0)
    n = 50
    A = rng.normal(size=(n, 4, 4))
    P_own = A @ A.transpose(0, 2, 1) + np.eye(4) * 0.1
    B = rng.normal(size=(n, 3, 3))
    P_peer = B @ B.transpose(0, 2, 1) + np.eye(3) * 0.1
    h_own, h_peer = rng.normal(size=(n, 4)), rng.normal(size=(n, 3))
    w = ci_weight(P_own, P_peer, h_own, h_peer, 0.01, criterion=criterion)
    # brute force on a fine grid, with the posterior formed by an explicit joint update
    ws = np.linspace(1e-3, 1 - 1e-3, 999)[None, :, None, None]
    J = np.zeros((n, ws.shape[1], 7, 7))
    J[:, :, :4, :4] = P_own[:, None] / ws
    J[:, :, 4:, 4:] = P_peer[:, None] / (1 - ws)
    h = np.concatenate([h_own, h_peer], axis=1)[:, None, :]
    Jh = np.einsum("nwij,nwj->nwi", J, np.broadcast_to(h, J.shape[:3]))
    S = np.einsum("nwi,nwi->nw", np.broadcast_to(h, Jh.shape), Jh) + 0.01
    post = J - Jh[..., :, None] * Jh[..., None, :] / S[..., None, None]
    m = 2 if criterion == "position" else 4
    best = ws[0, :, 0, 0][np.argmin(np.linalg.det(post[..., :m, :m]), axis=1)]
    assert np.allclose(w, best, atol=2e-3)
    assert np.all((w > 0) & (w < 1))
    # the objectives used by the search agree with the explicit posterior (up to a constant)
    g = np.einsum("nij,nj->ni", P_own, h_own)
    a = np.einsum("ni,ni->n", h_own, g)
    b = np.einsum("ni,nij,nj->n", h_peer, P_peer, h_peer)
    fp = _posterior_position_det(P_own, g, a, b, 0.01, np.full((n, 1), 0.3))[:, 0]
    fs = _posterior_state_log_det(P_own, g, a, b, 0.01, np.full((n, 1), 0.3))[:, 0]
    J = np.zeros((n, 7, 7))
    J[:, :4, :4] = P_own / 0.3
    J[:, 4:, 4:] = P_peer / 0.7
    h = np.concatenate([h_own, h_peer], axis=1)
    Jh = np.einsum("nij,nj->ni", J, h)
    post = (
        J - Jh[:, :, None] * Jh[:, None, :] / (np.einsum("ni,ni->n", h, Jh) + 0.01)[:, None, None]
    )
    assert np.allclose(fp, np.linalg.det(post[:, :2, :2]), rtol=1e-9)
    assert np.allclose(fs + np.log(np.linalg.det(P_own)), np.log(np.linalg.det(post[:, :4, :4])))


def test_team_tracks_refuses_an_unknown_method(team):
    with pytest.raises(NavInputError, match="method"):
        team_tracks(team.record, "magic")
