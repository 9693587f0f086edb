"""Seed 001's kinematic world (eq. 27-29) against formulas written out here, and the library-level
part of acceptance check 4 (the current estimated from surfacings in a uniform current)."""

import math

import numpy as np
import pytest

from bauv_sim import rng as rng_mod
from bauv_sim.config import ConfigError, validate
from bauv_sim.kinematic import seed001 as kin
from nav import surfacing as corr


def unit(c):
    c = np.asarray(c, dtype=float)
    return np.stack([np.sin(c), np.cos(c)], axis=-1)


def gens(n, *names, seed=11):
    return [rng_mod.generator(seed, i, "test", *names) for i in range(n)]


def quiet_world(**kw):
    """No random current perturbation, no Vr, uniform hull response unless overridden."""
    base = dict(
        current_speed_rel_var=0.0,
        current_speed_var_m2_s2=0.0,
        current_direction_var_deg2=0.0,
        random_speed_max_m_s=0.0,
        rho_s_cos_coeffs=(1.0,),
        step_s=0.01,
    )
    base.update(kw)
    return kin.Seed001WorldConfig(**base)


def fly(cfg, vehicle, vc, courses, seed=11, start=None):
    """Three legs back to back from the origin, each from the previous leg's true end."""
    n = courses.shape[0]
    pert = kin.draw_perturbations(cfg, 3 * cfg.leg_duration_s + 1, gens(n, "cur", seed=seed))
    pos = np.zeros((n, 2)) if start is None else start
    legs = []
    for j in range(courses.shape[1]):
        lt = kin.leg_truth(
            cfg,
            vehicle,
            vc,
            pert,
            pos,
            j * cfg.leg_duration_s,
            courses[:, j],
            gens(n, f"vr{j}", seed=seed),
        )
        legs.append(lt)
        pos = lt.pos_world_m[:, -1]
    return legs


def test_rho_s_is_the_navigation_series():
    g = np.linspace(-4, 4, 50)
    coeffs = (1.0, 0.1, 0.1, -0.05)
    assert np.allclose(kin.rho_s(g, coeffs), corr.CurrentResponse(coeffs).rho_s(g))
    assert kin.Seed001WorldConfig().rho_s_cos_coeffs == corr.DEFAULT_RHO_S_COS_COEFFS


def test_config_defaults_and_validation():
    cfg = kin.Seed001WorldConfig()
    assert cfg.leg_duration_s == 100.0 and cfg.samples_per_leg == 100 and cfg.step_s == 0.001
    assert cfg.current_hold_max_steps == 10000 and cfg.random_speed_max_m_s == 0.3
    with pytest.raises(ConfigError, match="whole multiple"):
        validate(kin.Seed001WorldConfig, {"step_s": 0.3})
    with pytest.raises(ConfigError, match="positive"):
        validate(kin.Seed001WorldConfig, {"rho_s_cos_coeffs": [1.0, -1.5]})
    with pytest.raises(ConfigError, match="unknown field"):
        validate(kin.Seed001WorldConfig, {"sigma": 1.0})


def test_eq29_stage1_mean_magnitude():
    cfg = quiet_world(rho_s_cos_coeffs=(1.0, 0.1, 0.1))

    def rs(g):
        return 1.0 + 0.1 * math.cos(g) + 0.1 * math.cos(2 * g)

    hull = np.radians([20.0, 110.0, 200.0, 340.0])
    got = kin.mean_current_speed(cfg, np.full(4, 0.5), hull)
    gammas = np.radians([0.0, 90.0, 180.0, 40.0])
    ref = rs(math.radians(20.0))  # rho_s(alpha_c) as printed
    assert np.allclose(got, [0.5 * rs(g) / ref for g in gammas])


def test_noise_free_leg_is_eq27_28_exactly():
    cfg = quiet_world(rho_s_cos_coeffs=(1.0, 0.1, 0.1))
    vs, beta = np.array([0.3, -0.1]), np.radians([20.0, 5.0])
    vc = np.array([0.5, 0.1])
    courses = np.radians([[45.0, 225.0, 300.0], [0.0, 90.0, 180.0]])
    legs = fly(cfg, kin.Seed001Vehicle(vs, beta), vc, courses)
    start = np.zeros((2, 2))
    for j, lt in enumerate(legs):
        a = courses[:, j]
        m = kin.mean_current_speed(cfg, vc, a + beta)
        v = unit(a) + vs[:, None] * unit(a + beta) + m[:, None] * unit(math.radians(20.0))
        assert np.allclose(lt.pos_world_m, start[:, None] + v[:, None] * lt.t_s[None, :, None])
        assert np.allclose(lt.mean_current_world_m_s, m[:, None] * unit(math.radians(20.0)))
        start = lt.pos_world_m[:, -1]


def test_held_perturbations_integrate_exactly():
    cfg = kin.Seed001WorldConfig(current_hold_max_steps=700, step_s=0.01)
    pert = kin.draw_perturbations(cfg, 30.0, gens(2, "cur"))
    # step-by-step sum at the hold step (0.001 s) of the piecewise-constant process
    t = np.arange(0.0, 30.0, cfg.current_hold_step_s) + 0.5 * cfg.current_hold_step_s
    for r in range(2):
        k = np.searchsorted(pert.ends_s[r], t, side="right")
        u = unit(pert.direction_rad[r][k])
        direct_u = np.cumsum(u, axis=0)[-1] * cfg.current_hold_step_s
        direct_zu = np.cumsum(pert.z[r][k, None] * u, axis=0)[-1] * cfg.current_hold_step_s
        iu, izu = pert.integrals(np.array([30.0]))
        assert np.allclose(iu[r, 0], direct_u, atol=1e-9)
        assert np.allclose(izu[r, 0], direct_zu, atol=1e-9)
        # holds are whole numbers of 0.001 s steps in [1, N_d,max]
        steps = np.diff(np.concatenate([[0.0], pert.ends_s[r]])) / cfg.current_hold_step_s
        assert np.allclose(steps, np.round(steps)) and steps.min() >= 1 and steps.max() <= 700


def test_perturbation_statistics():
    cfg = kin.Seed001WorldConfig()  # N_d,max = 10000 steps of 0.001 s, sigma_alpha^2 = 10 deg^2
    pert = kin.draw_perturbations(cfg, 2000.0, gens(4, "cur"))
    z = np.concatenate(pert.z)
    d = np.degrees(np.concatenate(pert.direction_rad))
    holds = np.concatenate([np.diff(np.concatenate([[0.0], e])) for e in pert.ends_s])
    n = z.size
    assert abs(z.mean()) < 5 / math.sqrt(n) and abs(z.std() - 1) < 0.05
    assert abs(d.mean() - 20.0) < 5 * math.sqrt(10 / n) and abs(d.var() / 10 - 1) < 0.1
    assert holds.mean() == pytest.approx(5.0005, rel=0.05)  # uniform on 1..10000 steps


def test_vr_variance_matches_white_noise_formula():
    # Vr alone: displacement variance T t r_max^2 / 6 per axis
    cfg = quiet_world(random_speed_max_m_s=0.3, step_s=0.01)
    sums = kin.random_velocity_sums(cfg, 100.0, gens(600, "vr"))
    disp = sums.sum(axis=1)
    expected = 100.0 * 0.01 * 0.3**2 / 6
    assert disp.var(axis=0) == pytest.approx([expected, expected], rel=0.2)
    assert np.all(np.abs(disp.mean(axis=0)) < 5 * math.sqrt(expected / 600))


def test_coarser_step_changes_truth_only_by_vr_noise():
    """Paired missions (same courses, same current realisation) at t = 0.001 s and 0.02 s: the
    legs' ends differ only by the Vr white noise, sd sqrt(T r_max^2 (t1 + t2) / 6) = 0.19 m/axis."""
    fine = kin.Seed001WorldConfig()
    coarse = kin.Seed001WorldConfig(step_s=0.02)
    vehicle = kin.Seed001Vehicle(np.full(12, 0.3), np.radians(np.full(12, 20.0)))
    vc = np.full(12, 0.5)
    courses = kin.draw_courses("cp1", gens(12, "courses"))
    a = fly(fine, vehicle, vc, courses)
    b = fly(coarse, vehicle, vc, courses)
    diff = np.concatenate(
        [x.displacement_world_m - y.displacement_world_m for x, y in zip(a, b, strict=True)]
    )
    sd = math.sqrt(100.0 * 0.09 * (0.001 + 0.02) / 6)
    assert np.max(np.abs(diff)) < 5 * sd
    # versus a current-driven spread of metres between missions
    spread = np.std(
        np.concatenate([x.displacement_world_m for x in a]) - 100 * unit(courses.T.ravel())
    )
    assert spread > 10 * sd


def test_draw_courses_respects_the_procedures():
    c1 = kin.draw_courses("cp1", gens(300, "c"), cp1_min_separation_rad=math.radians(10))
    assert np.all(np.abs(np.sin(c1[:, 1] - c1[:, 0])) >= math.sin(math.radians(10)) - 1e-12)
    assert np.all((c1 >= 0) & (c1 < 2 * np.pi))
    c2 = kin.draw_courses("cp2", gens(5, "c"))
    assert np.allclose(np.degrees(c2[:, :2]), [45.0, 225.0])
    assert np.array_equal(
        c1, kin.draw_courses("cp1", gens(300, "c"), cp1_min_separation_rad=math.radians(10))
    )
    with pytest.raises(ValueError):
        kin.draw_courses("cp3", gens(1, "c"))  # type: ignore[arg-type]


@pytest.mark.parametrize("procedure", ["cp1", "cp2"])
def test_uniform_current_estimated_from_surfacings(procedure):
    """Acceptance 4 (uniform case, kinematic world): the current estimated from two surfacings
    equals the true current: to 1e-9 without Vr, to 0.01 m/s with the paper's Vr (r_max 0.3 m/s,
    whose leg mean has sd sqrt(t r_max^2 / (6 T)) = 0.0012 m/s per axis at t = 0.01 s)."""
    n = 20
    vs = np.linspace(-0.3, 0.3, n)
    beta = np.radians(np.linspace(-20, 20, n))
    vc = np.linspace(0.05, 0.5, n)
    courses = kin.draw_courses(procedure, gens(n, "courses"))  # type: ignore[arg-type]
    true_current = vc[:, None] * unit(math.radians(20.0))
    for r_max, tol in ((0.0, 1e-9), (0.3, 0.01)):
        cfg = quiet_world(random_speed_max_m_s=r_max)
        legs = fly(cfg, kin.Seed001Vehicle(vs, beta), vc, courses[:, :2])
        dr = 100.0 * unit(courses[:, :2])
        delta = np.stack([lt.displacement_world_m for lt in legs], axis=1) - dr
        proc = corr.cp1 if procedure == "cp1" else corr.cp2
        est = proc(delta, 100.0, courses[:, :2])
        assert np.max(np.abs(est.current_world_m_s - true_current)) < tol
        assert np.max(np.abs(est.vs_m_s - vs)) < 3 * tol
        # the baseline attributes the vehicle error to the current
        base = corr.baseline(
            legs[1].pos_world_m[:, -1], legs[1].pos_world_m[:, 0] + dr[:, 1], 100.0
        )
        err = np.linalg.norm(base.current_world_m_s - true_current, axis=1)
        assert np.allclose(err, np.abs(vs), atol=tol)
