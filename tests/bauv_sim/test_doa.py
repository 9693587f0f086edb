"""DOA bearings against direct geometry (eq. 17 as printed), their error statistics, bad geometry
(a beacon overhead, eq. 17's form at phi = 90 deg) and the online device."""

import math

import numpy as np
import pytest

from bauv_sim.build import BeaconSpec, SceneConfig, VehicleSpec, build_physics
from bauv_sim.sensors import AngleErrorConfig
from bauv_sim.sensors.doa import Doa, DoaConfig, DoaSet
from bauv_sim.sensors.rig import SensorRig

SEED004_BEACONS = np.array(
    [[500.0, 100.0, 0.0], [500.0, -100.0, 0.0], [-100.0, 100.0, 0.0], [-100.0, -100.0, 0.0]]
)
QUIET = DoaConfig(
    azimuth=AngleErrorConfig(sigma_deg=0.0), elevation=AngleErrorConfig(sigma_deg=0.0)
)


def test_noise_free_bearings_are_the_geometry_of_eq17():
    rng = np.random.default_rng(0)
    pos = np.column_stack(
        [rng.uniform(-50, 300, 20), rng.uniform(-30, 30, 20), rng.uniform(-12, -8, 20)]
    )
    s = Doa(QUIET, SEED004_BEACONS, 1, (0,)).sample_positions(pos[None], np.arange(20.0))
    assert s.produced.all() and s.tangent_ok.all() and not s.overhead.any()
    for b, xb in enumerate(SEED004_BEACONS):
        dx, dy, dz = (xb - pos).T
        phi = math.pi / 2 - np.arctan2(dx, dy)  # from x counter-clockwise, via the north angle
        phi = (phi + np.pi) % (2 * np.pi) - np.pi
        np.testing.assert_allclose(s.angles_rad[0, :, b, 0], phi, atol=1e-12)
        np.testing.assert_allclose(
            np.sin(s.angles_rad[0, :, b, 1]), dz / np.sqrt(dx**2 + dy**2 + dz**2), atol=1e-12
        )
        # eq. 17 as printed, with cos(phi)
        np.testing.assert_allclose(s.tangents[0, :, b, 0], dy / dx, rtol=1e-12)
        np.testing.assert_allclose(s.tangents[0, :, b, 1], dz * np.cos(phi) / dx, rtol=1e-12)
    assert s.warnings() == []


@pytest.mark.parametrize("noise_on", ["tangent", "angle"])
def test_error_statistics_follow_the_chosen_form(noise_on):
    n, k = 300, 200
    cfg = DoaConfig(noise_on=noise_on)  # 0.5 deg
    pos = np.zeros((n, k, 3)) + np.array([20.0, 5.0, -10.0])
    s = Doa(cfg, SEED004_BEACONS, 4, tuple(range(n))).sample_positions(
        pos, np.arange(k, dtype=float)
    )
    q = Doa(QUIET, SEED004_BEACONS, 4, tuple(range(n))).sample_positions(
        pos, np.arange(k, dtype=float)
    )
    if noise_on == "tangent":
        err = s.tangents - q.tangents
        want = math.tan(math.radians(0.5))  # seed 004: N(0, tan^2(0.5 deg))
    else:
        err = s.angles_rad - q.angles_rad
        err[..., 0] = (err[..., 0] + np.pi) % (2 * np.pi) - np.pi
        want = math.radians(0.5)
    std = err.reshape(-1, 2).std(axis=0)
    se = want / math.sqrt(2 * err[..., 0].size)
    np.testing.assert_allclose(std, want, atol=5 * se)
    assert np.abs(err.reshape(-1, 2).mean(axis=0)).max() < 5 * want / math.sqrt(err[..., 0].size)
    # the angles stay in the beacon's half-plane: never off by pi
    dphi = (s.angles_rad[..., 0] - q.angles_rad[..., 0] + np.pi) % (2 * np.pi) - np.pi
    assert np.abs(dphi).max() < math.radians(5)


def test_same_seed_same_numbers():
    pos = np.zeros((3, 10, 3))
    a = Doa(DoaConfig(), SEED004_BEACONS, 9, (0, 1, 2)).sample_positions(pos, np.arange(10.0))
    b = Doa(DoaConfig(), SEED004_BEACONS, 9, (0, 1, 2)).sample_positions(pos, np.arange(10.0))
    assert np.array_equal(a.tangents, b.tangents) and np.array_equal(a.angles_rad, b.angles_rad)
    # run 1 draws the same in a batch of one
    c = Doa(DoaConfig(), SEED004_BEACONS, 9, (1,)).sample_positions(pos[:1], np.arange(10.0))
    assert np.array_equal(c.tangents[0], a.tangents[1])


def test_beacon_straight_above_degrades_with_a_flag_and_no_nan():
    beacons = np.array([[0.0, 0.0, 0.0], [0.0, 50.0, 0.0], [80.0, 0.0, 0.0]])
    pos = np.array([[[0.0, 0.0, -10.0], [0.005, 0.0, -10.0], [1.0, 0.0, -10.0]]])
    for noise_on in ("tangent", "angle"):
        s = Doa(DoaConfig(noise_on=noise_on), beacons, 2, (0,)).sample_positions(
            pos, np.arange(3.0)
        )
        for arr in (s.tangents, s.angles_rad):
            assert np.all(np.isfinite(arr))
        # beacon 0 overhead at samples 0 and 1 (within 1 cm horizontally): no bearing
        assert s.overhead[0, :2, 0].all() and not s.produced[0, :2, 0].any()
        assert np.all(s.angles_rad[0, :2, 0] == 0) and np.all(s.tangents[0, :2, 0] == 0)
        # at 1 m it is 84 deg up: produced, eq. 17's tan(lambda) = 10 still within max_tangent
        assert s.produced[0, 2, 0] and s.tangent_ok[0, 2, 0]
        # beacon 1 due north (X_B - X = 0 at samples 0): eq. 17's tan(phi) is infinite
        assert s.produced[0, 0, 1] and not s.tangent_ok[0, 0, 1]
        assert s.tangents[0, 0, 1, 0] == 0
        assert abs(s.angles_rad[0, 0, 1, 0] - np.pi / 2) < math.radians(3)
        # beacon 2 is unaffected
        assert s.produced[0, :, 2].all() and s.tangent_ok[0, :, 2].all()
        lines = s.warnings(("b0", "b1", "b2"))
        assert any("b0" in ln and "straight above" in ln and "2 of 3" in ln for ln in lines)
        assert any("b1" in ln and "ill-conditioned" in ln for ln in lines)
        assert not any("b2" in ln for ln in lines)


def test_max_range_and_dropouts_remove_bearings():
    far = DoaConfig(max_range_m=300.0, dropout_probability=0.3)
    pos = np.zeros((400, 5, 3)) + np.array([0.0, 0.0, -10.0])
    s = Doa(far, SEED004_BEACONS, 3, tuple(range(400))).sample_positions(pos, np.arange(5.0))
    assert not s.produced[..., :2].any()  # 510 m away
    frac = s.produced[..., 2:].mean()
    assert abs(frac - 0.7) < 4 * math.sqrt(0.21 / s.produced[..., 2:].size)
    # a lost set loses every beacon of it
    assert np.array_equal(s.produced[..., 2], s.produced[..., 3])


def test_reference_angle_errors_are_refused():
    with pytest.raises(ValueError, match="sector_bias_deg"):
        DoaConfig(azimuth=AngleErrorConfig(sector_bias_deg=(1.0, 0.0, 0.0, 0.0)))


def test_online_doa_device_bearings_to_the_scene_beacons():
    beacons = (
        BeaconSpec(name="beacon_0", east_m=200.0, north_m=50.0),
        BeaconSpec(name="beacon_1", east_m=-100.0, north_m=-80.0),
    )
    phys = build_physics(SceneConfig(beacons=beacons, vehicles=(VehicleSpec(depth_m=3.0),)))
    rig = SensorRig({"doa": QUIET.model_copy(update={"period_s": 0.5})}, phys, "bauv", 1, 0)
    vt = phys.truth()
    assert rig.sense(1, vt, phys.commands()).arrived == ()  # not a sampling tick
    (m,) = rig.sense(5, vt, phys.commands()).arrived
    assert isinstance(m.payload, DoaSet) and m.payload.beacons == ("beacon_0", "beacon_1")
    world = phys.beacons_world()
    for b, name in enumerate(m.payload.beacons):
        d = world[name] - vt.position_world_m
        assert abs(m.value[2 * b] - math.atan2(d[1], d[0])) < 1e-12
        assert abs(m.value[2 * b + 1] - math.atan2(d[2], math.hypot(d[0], d[1]))) < 1e-12
    assert m.payload.produced.all() and m.payload.tangent_ok.all()
