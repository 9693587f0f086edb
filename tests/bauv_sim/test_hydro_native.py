"""The native (GPU-ready) formulation of the hydrodynamics against the plugin ``bauv.hydro``: at
random states the callback's force plus the armature's share of the added mass equals the
plugin's force plus the added mass it puts in the mass matrix, and the lagged added mass is
stable (its recursion's spectral radius below 1)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from bauv_sim import build, hydro, hydro_native, manoeuvres
from bauv_sim.errors import ConfigError, PhysicsError

from .test_hydrodynamics import _randomise

TWO = build.SceneConfig(
    vehicles=(
        build.VehicleSpec(name="leader", depth_m=3.0),
        build.VehicleSpec(name="follower", east_m=-30.0, depth_m=3.0),
    )
)


@pytest.fixture(autouse=True)
def _no_callback_left():
    """The callback of a native model makes every later compilation of the process fail
    (hydro_native.compiling): none is left installed for the next test."""
    yield
    hydro_native.uninstall()


def _pair(config: build.SceneConfig):
    return (
        build.build_physics(config, hydrodynamics="plugin"),
        build.build_physics(config, hydrodynamics="native"),
    )


def _total_hydro_force(m, d, qacc, native: bool) -> np.ndarray:
    """Everything the hydrodynamics adds to M qacc = f at the acceleration qacc: the plugin's
    force less its added mass times qacc, or the callback's (lagged acceleration = qacc) less the
    armature's added mass times qacc; MuJoCo's own fluid force in both."""
    if not native:
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        mujoco.mj_makeM(m, d)  # MuJoCo's mass matrix without the plugin's block
        raw = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, raw)
        return hydro.plugin_force(d, np.arange(m.nv)) - (full - raw) @ qacc + d.qfrc_fluid
    nat = hydro_native.native_of(m)
    assert nat is not None
    d.qacc[:] = qacc
    f = sum(hydro_native.vehicle_force(m, d, v) for v in nat.vehicles)
    armature = np.zeros(m.nv)  # the vehicle file's free joint has none of its own
    for v in nat.vehicles:
        armature[v.dof : v.dof + 6] = m.dof_armature[v.dof : v.dof + 6]
    return f - armature * qacc + d.qfrc_fluid


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_native_equals_the_plugin_at_random_states_of_two_vehicles_in_different_water(seed):
    plug, nat = _pair(TWO)
    rng = np.random.default_rng(seed)
    (mp, dp), (mn, dn) = (plug.model.ptr, plug.data.ptr), (nat.model.ptr, nat.data.ptr)
    _randomise(mp, dp, rng)
    mujoco.mj_resetData(mn, dn)
    dn.qpos[:], dn.qvel[:] = dp.qpos, dp.qvel
    waters = {
        "leader/": (rng.normal(0, 0.3, 3), rng.normal(0, 0.2, 3)),
        "follower/": (rng.normal(0, 0.3, 3), rng.normal(0, 0.2, 3)),
    }
    for m, d in ((mp, dp), (mn, dn)):
        inst = hydro.plugin_instances(m)
        for prefix, (w, a) in waters.items():
            hydro.set_water(m, d, inst[prefix], w, a, t0_s=-0.05)
        hydro.set_water_velocity(m, hydro.water(m, d, inst["leader/"])[0])
        mujoco.mj_forward(m, d)
    qacc = rng.normal(0, 1.0, mp.nv)  # any acceleration: both are linear in it
    want = _total_hydro_force(mp, dp, qacc, native=False)
    got = _total_hydro_force(mn, dn, qacc, native=True)
    assert np.abs(want).max() > 10.0  # a state with real forces
    assert np.allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


def test_the_callback_is_what_the_step_adds_and_the_native_model_has_no_plugin():
    _, nat = _pair(build.SceneConfig())
    m, d = nat.model.ptr, nat.data.ptr
    assert m.nplugin == 0
    _randomise(m, d, np.random.default_rng(5))
    mujoco.mj_forward(m, d)  # d.qacc now holds this state's acceleration, the next lag
    lag = np.array(d.qacc)
    v = hydro_native.native_of(m).vehicles[0]
    expect = hydro_native.vehicle_force(m, d, v)
    mujoco.mj_fwdVelocity(m, d)  # evaluates the passive forces with the callback
    other = d.qfrc_spring + d.qfrc_damper + d.qfrc_gravcomp + d.qfrc_fluid
    assert np.array_equal(d.qacc, lag)
    assert np.allclose(d.qfrc_passive - other, expect, rtol=1e-12, atol=1e-9)


def test_lagged_added_mass_is_stable_and_the_armature_holds_the_rest():
    _, nat = _pair(build.SceneConfig())
    m, d = nat.model.ptr, nat.data.ptr
    native = hydro_native.native_of(m)
    assert 0.0 < native.stability_ratio < 1.0
    v = native.vehicles[0]
    arm = m.dof_armature[v.dof : v.dof + 6]
    assert np.allclose(arm[:3], v.m_iso_kg) and np.allclose(arm[3:], np.diag(v.M_A)[3:])
    assert np.allclose(v.dA + np.diag(arm), v.M_A, atol=1e-12)
    # the ratio from its definition: a lagged sway force that equals the mass would not converge
    v.dA = v.M_A - np.diag(np.r_[[0.0] * 3, np.diag(v.M_A)[3:]]) + np.diag([0, 200.0, 0, 0, 0, 0])
    mujoco.mj_forward(m, d)
    assert hydro_native.stability_ratio(m, d, v) > 1.0


def test_an_unknown_formulation_is_named():
    with pytest.raises(ConfigError, match="hydrodynamics = 'gpu'"):
        build.build_physics(build.SceneConfig(), hydrodynamics="gpu")


@pytest.mark.parametrize(("m_iso_kg", "stable"), [(20.0, True), (10.0, False)])
def test_the_ratio_predicts_whether_the_swim_diverges(m_iso_kg, stable):
    """Less isotropic mass in the armature, more lagged: ratio 0.82 swims, 1.13 diverges (the
    facade raises at the first bad step)."""
    with hydro_native.formulation("native"):
        phys = manoeuvres.open_water_scene(speed_m_s=1.0)
    phys.set_timestep(0.004)
    m, d = phys.model.ptr, phys.data.ptr
    v = hydro_native.native_of(m).vehicles[0]
    hydro_native._set_armature(m, v, np.zeros(6), m_iso_kg)
    mujoco.mj_forward(m, d)
    ratio = hydro_native.stability_ratio(m, d, v)
    assert (ratio < 1.0) == stable
    phys.set_tail_beat_frequency_hz(1.2)
    if stable:
        phys.advance(2.0)
        assert np.all(np.isfinite(d.qvel)) and np.abs(d.qvel).max() < 20.0
    else:
        with pytest.raises(PhysicsError):
            phys.advance(2.0)
