"""The online DVL in the physics world: its velocity against MuJoCo's own velocity of the ``dvl``
site, its beam ranges against the analytic heightfield intersection, lock and water track in a
rig, the new site changing nothing else."""

import mujoco
import numpy as np
import pytest

from bauv_sim import seabed as sb
from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
from bauv_sim.frames import R_from_quat_wxyz
from bauv_sim.sensors import DvlConfig, DvlPing, LengthErrorConfig, SpeedErrorConfig
from bauv_sim.sensors.rig import SensorRig

pytestmark = pytest.mark.filterwarnings("error")
EXACT = {"beam": SpeedErrorConfig(), "range": LengthErrorConfig()}
RELIEF = sb.SeabedConfig(
    half_extent_m=80.0,
    cell_m=4.0,
    depth_at_origin_m=20.0,
    slope=0.02,
    relief_std_m=2.0,
    n_modes=12,
    min_wavelength_m=15.0,
    max_wavelength_m=80.0,
    min_depth_m=4.5,
    seed=3,
)


def _site_velocity_body(phys, site="bauv/dvl"):
    """MuJoCo's velocity of a site (its own kinematics on a copy of the state), body FLU."""
    m = phys.model.ptr
    d = mujoco.MjData(m)
    mujoco.mj_copyData(d, m, phys.data.ptr)
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    mujoco.mj_comVel(m, d)
    sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, site)
    assert sid >= 0
    res = np.zeros(6)
    mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, sid, res, 0)  # (ang, lin), world
    R = R_from_quat_wxyz(phys.truth().quat_wxyz)
    return R.T @ res[3:], d.site_xpos[sid].copy()


@pytest.fixture(scope="module")
def phys():
    return build_physics(
        SceneConfig(seabed=RELIEF, beacons=(), vehicles=(VehicleSpec(depth_m=5.0),))
    )


def _ping(rig, phys, k=60):
    tick = rig.sense(k, phys.truth(), phys.commands())
    return tick.arrived


def test_bottom_lock_is_mujocos_velocity_of_the_dvl_site_and_ranges_the_heightfields(phys):
    bed = sb.generate(RELIEF)
    cfg = DvlConfig(period_s=0.2, **EXACT)
    rig = SensorRig({"dvl": cfg}, phys, "bauv", seed=1, run=0)
    lever = np.array(rig.lever_arms_body_m["dvl"])
    np.testing.assert_allclose(lever, [0.4, 0.0, -0.163], atol=1e-12)  # the model's site
    rng = np.random.default_rng(3)
    for _ in range(6):
        phys.set_pose(
            [rng.uniform(-40, 40), rng.uniform(-40, 40), -rng.uniform(3, 8)],
            [rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4), rng.uniform(0, 2 * np.pi)],
            rng.normal(0, 1, 3),
            angular_velocity_body_rad_s=rng.normal(0, 0.5, 3),
        )
        (m,) = _ping(rig, phys)
        ping = m.payload
        assert isinstance(ping, DvlPing) and ping.mode == 1 and ping.beam_echo.all()
        want, site = _site_velocity_body(phys)
        np.testing.assert_allclose(m.value, want, rtol=0, atol=1e-9)
        np.testing.assert_allclose(ping.velocity_body_m_s, want, rtol=0, atol=1e-9)
        # ranges: the analytic intersection of the triangulated heightfield, from the site
        R = R_from_quat_wxyz(phys.truth().quat_wxyz)
        e = ping.beam_directions_body @ R.T
        L, hit = bed.ray_ranges(site, e, cfg.max_range_m)
        assert hit.all()
        np.testing.assert_allclose(ping.beam_ranges_m, L, rtol=0, atol=0.01)
        np.testing.assert_allclose(ping.lever_arm_body_m, lever, atol=1e-12)


def test_a_swimming_vehicle_in_a_current_bottom_locks_and_water_tracks(phys):
    phys.set_pose([10.0, -5.0, -4.0], [0.0, 0.0, 0.5])
    phys.set_water_world([0.3, -0.2, 0.0])
    phys.set_tail_beat_frequency_hz(1.5)
    phys.advance(3.0)
    try:
        cfg = DvlConfig(period_s=0.2, **EXACT)
        rig = SensorRig({"dvl": cfg}, phys, "bauv", seed=1, run=0)
        (m,) = _ping(rig, phys)
        want, _ = _site_velocity_body(phys)
        assert m.payload.mode == 1
        np.testing.assert_allclose(m.value, want, rtol=0, atol=1e-9)
        # water track above the maximum altitude: the site's velocity minus the water's
        cfg_w = cfg.model_copy(update={"max_altitude_m": 2.0})
        rig_w = SensorRig({"dvl": cfg_w}, phys, "bauv", seed=1, run=0)
        (mw,) = _ping(rig_w, phys)
        vt = phys.truth()
        R = R_from_quat_wxyz(vt.quat_wxyz)
        water = want - R.T @ vt.current_world_m_s
        assert mw.payload.mode == 2 and mw.payload.altitude_m == 0
        assert not mw.payload.beam_echo.any() and np.all(mw.payload.beam_ranges_m == 0)
        np.testing.assert_allclose(mw.value, water, rtol=0, atol=1e-9)
        assert np.linalg.norm(mw.value - m.value) > 0.2
        # no fallback: nothing arrives; between pings nothing either
        rig_0 = SensorRig(
            {"dvl": cfg_w.model_copy(update={"fallback": "none"})}, phys, "bauv", 1, 0
        )
        assert _ping(rig_0, phys) == ()
        rig_slow = SensorRig({"dvl": cfg.model_copy(update={"period_s": 1.0})}, phys, "bauv", 1, 0)
        assert _ping(rig_slow, phys, k=61) == () and len(_ping(rig_slow, phys, k=60)) == 1
    finally:
        phys.set_water_world([0.0, 0.0, 0.0])
        phys.set_tail_beat_frequency_hz(0.0)


def test_noisy_pings_are_finite_and_the_same_for_the_same_seed(phys):
    phys.set_pose([0.0, 0.0, -5.0], [0.1, -0.05, 1.0], [0.5, 0.2, 0.0])
    cfg = DvlConfig(
        beam=SpeedErrorConfig(sigma_m_s=0.01, dropout_probability=0.2),
        range=LengthErrorConfig(sigma_m=0.02),
    )
    a = SensorRig({"dvl": cfg}, phys, "bauv", seed=4, run=2)
    b = SensorRig({"dvl": cfg}, phys, "bauv", seed=4, run=2)
    for k in range(1, 40):
        ma, mb = _ping(a, phys, k), _ping(b, phys, k)
        assert len(ma) == len(mb)
        for x, y in zip(ma, mb, strict=True):
            np.testing.assert_array_equal(x.value, y.value)
            assert np.all(np.isfinite(x.value)) and np.all(np.isfinite(x.payload.beam_ranges_m))
