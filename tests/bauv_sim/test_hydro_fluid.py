"""The ellipsoid fluid model applied by the plugin (issue 27, check 3) against MuJoCo's own.

The model file turns MuJoCo's fluid model off (``option density`` and ``viscosity`` 0) and gives
the water to the plugin (numeric ``hydro_water``), which applies the same ellipsoid model once per
body. The independent truth is MuJoCo: the same file with the water back in the option and without
``hydro_water`` (the model as it was, MuJoCo computing ``qfrc_fluid``) must give the same passive
forces at any state.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from bauv_sim import hydro
from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
from bauv_sim.hull import MODEL_DIR, SEAWATER_DENSITY_KG_M3, SEAWATER_VISCOSITY_PA_S

SCENE = MODEL_DIR / "scene.xml"


def _mujoco_fluid(spec: mujoco.MjSpec) -> mujoco.MjSpec:
    """The same model with MuJoCo's fluid model doing the ellipsoid forces (as before issue 27)."""
    for n in list(spec.numerics):
        if n.name.endswith("hydro_water"):
            spec.delete(n)
    spec.option.density, spec.option.viscosity = SEAWATER_DENSITY_KG_M3, SEAWATER_VISCOSITY_PA_S
    return spec


@pytest.fixture(scope="module")
def models() -> tuple[mujoco.MjModel, mujoco.MjModel]:
    hydro.load_plugin()
    new = mujoco.MjSpec.from_file(str(SCENE)).compile()
    old = _mujoco_fluid(mujoco.MjSpec.from_file(str(SCENE))).compile()
    return new, old


def _random_state(m: mujoco.MjModel, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    q = m.qpos0.copy()
    q[:3] = rng.normal(0.0, 1.0, 3) + [0.0, 0.0, -3.0]
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    for j in range(1, m.njnt):  # hinges and slides within their ranges
        lo, hi = m.jnt_range[j]
        q[m.jnt_qposadr[j]] = rng.uniform(lo, hi) if m.jnt_limited[j] else rng.uniform(-1, 1)
    v = rng.normal(0.0, 0.5, m.nv)
    v[:3] += rng.normal(0.0, 1.0, 3)
    return q, v


def test_model_file_has_mujoco_fluid_model_off_and_water_in_plugin(models):
    new, old = models
    assert new.opt.density == 0.0 and new.opt.viscosity == 0.0
    assert hydro.plugin_fluid_model(new) and not hydro.plugin_fluid_model(old)
    assert hydro.water_properties(new) == (SEAWATER_DENSITY_KG_M3, SEAWATER_VISCOSITY_PA_S)
    assert hydro.water_properties(old) == (SEAWATER_DENSITY_KG_M3, SEAWATER_VISCOSITY_PA_S)


@pytest.mark.parametrize("wind_is_water", [True, False])
def test_plugin_ellipsoid_forces_equal_mujoco_qfrc_fluid_at_random_states(models, wind_is_water):
    """qfrc_passive of the new model = qfrc_passive of the old (MuJoCo's qfrc_fluid included) to
    1e-9, at random positions, attitudes, joint angles, velocities and waters (accelerating or
    not; MuJoCo's ``option wind`` the vehicle's water, or another vehicle's: the old plugin then
    corrects MuJoCo's drag, the new one computes it in the vehicle's water)."""
    new, old = models
    dn, do = mujoco.MjData(new), mujoco.MjData(old)
    rng = np.random.default_rng(27)
    largest_fluid = 0.0
    for trial in range(40):
        q, v = _random_state(new, rng)
        w = rng.normal(0.0, 0.4, 3)
        a = rng.normal(0.0, 0.05, 3) if trial % 2 else np.zeros(3)
        wind = w if wind_is_water else rng.normal(0.0, 0.4, 3)
        for m, d in ((new, dn), (old, do)):
            d.qpos[:], d.qvel[:], d.time = q, v, 2.5
            hydro.set_water(m, d, 0, w, a, t0_s=2.5)
            m.opt.wind[:] = wind
            mujoco.mj_forward(m, d)
        assert not np.any(dn.qfrc_fluid)
        largest_fluid = max(largest_fluid, float(np.abs(do.qfrc_fluid).max()))
        np.testing.assert_allclose(dn.qfrc_passive, do.qfrc_passive, rtol=0, atol=1e-9)
    assert largest_fluid > 0.5  # the comparison covers forces of consequence (N, N m)


def test_water_with_mujoco_fluid_model_on_is_refused():
    """hydro_water and a nonzero option density would apply the ellipsoid model twice: the plugin
    refuses to start."""
    spec = mujoco.MjSpec.from_file(str(SCENE))
    spec.option.density = SEAWATER_DENSITY_KG_M3
    with pytest.raises(ValueError, match="option density and viscosity must be 0"):
        spec.compile()


def test_built_two_vehicle_scene_equals_mujoco_fluid_formulation():
    """A built scene of two vehicles (prefixed elements), each in its own water, MuJoCo's wind the
    first one's: the plugin's ellipsoid forces equal MuJoCo's (``hydrodynamics="mujoco-fluid"``,
    the model as before) on both vehicles to 1e-9."""
    cfg = SceneConfig(
        vehicles=[VehicleSpec(name="a", speed_m_s=1.0), VehicleSpec(name="b", east_m=20.0)]
    )
    phys = {k: build_physics(cfg, hydrodynamics=k) for k in ("plugin", "mujoco-fluid")}
    new, old = phys["plugin"].model.ptr, phys["mujoco-fluid"].model.ptr
    assert hydro.plugin_fluid_model(new) and not hydro.plugin_fluid_model(old)
    rng = np.random.default_rng(5)
    waters = {"a/": rng.normal(0.0, 0.3, 3), "b/": rng.normal(0.0, 0.3, 3)}
    v = rng.normal(0.0, 0.5, new.nv)
    for p in phys.values():
        m, d = p.model.ptr, p.data.ptr
        d.qvel[:] = v
        for prefix, w in waters.items():
            hydro.set_water(m, d, hydro.plugin_instances(m)[prefix], w)
        m.opt.wind[:] = waters["a/"]
        mujoco.mj_forward(m, d)
    dn, do = phys["plugin"].data.ptr, phys["mujoco-fluid"].data.ptr
    assert np.abs(do.qfrc_fluid).max() > 0.5
    np.testing.assert_allclose(dn.qfrc_passive, do.qfrc_passive, rtol=0, atol=1e-9)
