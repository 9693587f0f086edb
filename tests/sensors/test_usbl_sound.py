"""The USBL and the modem in a sea with a sound-speed profile: what they measure is the nominal
speed times the travel time along the bent ray, and the arrival direction of that ray.

Truth: a single constant-gradient layer, where the ray through two points is the circle centred
on the level at which the speed would vanish (worked out here from the geometry, not from the
code): travel time ``(1/|g|) |ln tan(psi_B/2) - ln tan(psi_A/2)|``, the arrival elevation the
tangent of the circle at the receiver.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bauv_sim.acoustics import SoundSpeedConfig
from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
from bauv_sim.frames import R_from_quat_wxyz
from bauv_sim.sensors.modem import Modem, ModemConfig
from bauv_sim.sensors.online import Peer
from bauv_sim.sensors.rig import SensorRig
from bauv_sim.sensors.usbl import Usbl, UsblConfig
from bauv_sim.truth import Truth
from nav.acoustics import Isovelocity, LayeredMedium, SoundSpeedProfile

C0, G = 1480.0, 0.05  # m/s at the surface, 1/s: rays curve upwards (faster below)
MEDIUM = LayeredMedium(SoundSpeedProfile.constant_gradient(C0, G, 4000.0))
EXACT = {"range": {"sigma_m": 0.0}, "azimuth": {"sigma_deg": 0.0}, "elevation": {"sigma_deg": 0.0}}


def _truth(pos: np.ndarray) -> Truth:
    n, k = pos.shape[:2]
    zeros = np.zeros((n, k, 3))
    return Truth(
        np.arange(k, dtype=float), pos, zeros, zeros, np.zeros((n, k)), np.zeros((n, k, 2)), zeros
    )


def _circle(source: np.ndarray, receiver: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Travel time and arrival elevation (at the receiver) of the constant-gradient ray."""
    x_b = np.hypot(*(receiver[..., :2] - source[..., :2]).T).T
    u_a, u_b = source[..., 2], receiver[..., 2]
    u_c = C0 / G
    x_c = (x_b**2 + (u_b - u_c) ** 2 - (u_a - u_c) ** 2) / (2.0 * x_b)
    psi_a = np.arctan2(u_a - u_c, -x_c)
    psi_b = np.arctan2(u_b - u_c, x_b - x_c)
    travel = np.abs(np.log(np.tan(-psi_b / 2)) - np.log(np.tan(-psi_a / 2))) / G
    # back along the arc from B: direction (sin psi, -cos psi) in (x, up); elevation from it
    arrival = np.arctan2(-np.cos(psi_b), -np.sin(psi_b))
    return travel, arrival


def _passage() -> np.ndarray:
    east = np.linspace(-400.0, 400.0, 9)
    pos = np.stack([east, 0.6 * east + 30.0, -(20.0 + 0.05 * np.abs(east))], axis=-1)
    return pos[None]


def test_usbl_in_a_gradient_measures_nominal_speed_times_travel_time_and_the_bent_ray() -> None:
    transceiver = np.array([5.0, -3.0, -2.0])
    pos = _passage()
    cfg = UsblConfig(**EXACT, processing_delay_s=0.3)
    s = Usbl(cfg, transceiver, 0, (0,), propagation=MEDIUM).sample(_truth(pos), np.arange(9))
    travel, arrival = _circle(pos[0], np.broadcast_to(transceiver, pos[0].shape))
    d = pos[0] - transceiver
    azimuth = np.arctan2(d[:, 0], d[:, 1]) % (2 * np.pi)
    assert s.produced.all()
    np.testing.assert_allclose(s.values[0, :, 0], 1500.0 * travel, rtol=1e-9)
    np.testing.assert_allclose(s.values[0, :, 1], azimuth, atol=1e-12)
    np.testing.assert_allclose(s.values[0, :, 2], arrival, atol=1e-8)
    np.testing.assert_allclose(s.t_arrival_s[0], np.arange(9) + travel + 0.3, rtol=1e-12)
    # The bent ray arrives from below the straight line (rays curve up in this gradient) and
    # the range is not the slant distance: the bias a nominal speed carries.
    straight = np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1]))
    assert np.all(s.values[0, :, 2] < straight)
    assert np.all(np.abs(s.values[0, :, 0] - np.linalg.norm(d, axis=-1)) > 0.3)


def test_usbl_errors_are_the_same_draws_with_and_without_a_medium() -> None:
    transceiver = np.array([0.0, 0.0, -2.0])
    pos = np.broadcast_to(_passage(), (50, 9, 3)).copy()
    cfg = UsblConfig()
    plain = Usbl(cfg, transceiver, 4, tuple(range(50))).sample(_truth(pos), np.arange(9))
    exact = Usbl(UsblConfig(**EXACT), transceiver, 4, tuple(range(50))).sample(
        _truth(pos), np.arange(9)
    )
    # Isovelocity at the nominal speed: the same fixes as no medium, to rounding.
    iso = Usbl(cfg, transceiver, 4, tuple(range(50)), propagation=Isovelocity(1500.0))
    same = iso.sample(_truth(pos), np.arange(9))
    np.testing.assert_allclose(same.values, plain.values, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(same.produced, plain.produced)
    np.testing.assert_allclose(same.t_arrival_s, plain.t_arrival_s, rtol=1e-14)
    # In the gradient: the same error draws on top of the acoustic measurement.
    bent = Usbl(cfg, transceiver, 4, tuple(range(50)), propagation=MEDIUM)
    got = bent.sample(_truth(pos), np.arange(9))
    clean = Usbl(UsblConfig(**EXACT), transceiver, 4, (0,), propagation=MEDIUM)
    base = clean.sample(_truth(pos[:1]), np.arange(9)).values
    np.testing.assert_allclose(
        got.values[..., 0] - base[..., 0], plain.values[..., 0] - exact.values[..., 0], atol=1e-9
    )


def test_usbl_in_a_shadow_gives_no_fix() -> None:
    # A negative gradient from the surface bends rays down: a transponder at 3 m depth 3 km away
    # from a transceiver at 3 m is in the shadow of the direct ray (it would turn in the air).
    medium = LayeredMedium(SoundSpeedProfile.constant_gradient(1540.0, -0.05, 1000.0))
    pos = np.array([[[3000.0, 0.0, -3.0], [300.0, 0.0, -3.0]]])
    cfg = UsblConfig(**EXACT, max_range_m=5000.0)
    s = Usbl(cfg, np.array([0.0, 0.0, -3.0]), 0, (0,), propagation=medium).sample(
        _truth(pos), np.arange(2)
    )
    assert s.produced.tolist() == [[False, True]]
    assert np.all(np.isfinite(s.values)) and np.all(np.isfinite(s.t_arrival_s))


def test_modem_range_is_nominal_speed_times_travel_time() -> None:
    sender = _passage()
    receiver = sender + np.array([120.0, -60.0, -35.0])
    cfg = ModemConfig(range={"sigma_m": 0.0, "bias_m": 0.0}, max_range_m=1000.0)
    idx = np.arange(9)
    s = Modem(cfg, 0, (0,), propagation=MEDIUM).sample(_truth(sender), _truth(receiver), idx)
    travel, _ = _circle(sender[0], receiver[0])
    assert s.produced.all()
    np.testing.assert_allclose(s.values[0], 1500.0 * travel, rtol=1e-9)
    _, _, t_arr = Modem(cfg, 0, (0,), propagation=MEDIUM).measure(
        np.linalg.norm(receiver - sender, axis=-1), idx.astype(float), travel[None]
    )
    np.testing.assert_allclose(t_arr[0], idx + travel + 0.5, rtol=1e-12)
    # Seed 003's errors: the same draws with and without the medium.
    noisy = ModemConfig(max_range_m=1000.0)
    with_medium = Modem(noisy, 2, (0,), propagation=MEDIUM).sample(
        _truth(sender), _truth(receiver), idx
    )
    without = Modem(noisy, 2, (0,)).sample(_truth(sender), _truth(receiver), idx)
    true_r = np.linalg.norm(receiver - sender, axis=-1)
    np.testing.assert_allclose(
        with_medium.values - 1500.0 * travel, without.values - true_r, atol=1e-9
    )


@pytest.fixture(scope="module")
def single():
    scene = SceneConfig(
        vehicles=(VehicleSpec(name="bauv", east_m=150.0, north_m=80.0, depth_m=2.0),)
    )
    return build_physics(scene, control_tick_s=0.2)


def test_online_usbl_takes_the_rigs_medium(single) -> None:
    sound = SoundSpeedConfig(kind="table", depths_m=(0.0, 4000.0), speeds_m_s=(C0, C0 + 200.0))
    medium = sound.propagation()
    assert isinstance(medium, LayeredMedium)
    cfg = UsblConfig(**EXACT, period_s=1.0)
    rig = SensorRig({"usbl": cfg}, single, "bauv", 5, 0, propagation=medium)
    plain = SensorRig({"usbl": cfg}, single, "bauv", 5, 0)
    truth = single.truth("bauv")
    got, ref = [], []
    for k in range(1, 12):
        at = dataclasses.replace(truth, t_s=0.2 * k)
        got += rig.sense(k, at, {}).arrived
        ref += plain.sense(k, at, {}).arrived
    assert got and len(got) == len(ref)
    device = rig.devices[0]
    pos = truth.position_world_m + R_from_quat_wxyz(truth.quat_wxyz) @ device.lever_arm_body_m
    travel, arrival = _circle(pos[None], device.transceiver_world_m[None])
    assert got[0].value[0] == pytest.approx(1500.0 * travel[0], rel=1e-9)
    assert got[0].value[2] == pytest.approx(arrival[0], abs=1e-8)
    assert ref[0].value[0] == pytest.approx(np.linalg.norm(pos - device.transceiver_world_m))
    assert got[0].t_arrival_s - got[0].t_valid_s == pytest.approx(travel[0], rel=1e-9)


def test_sound_config_default_is_no_medium_and_bad_input_names_the_field() -> None:
    from bauv_sim.config import validate
    from bauv_sim.errors import ConfigError

    assert SoundSpeedConfig().propagation() is None
    assert SoundSpeedConfig(speed_m_s=1510.0).propagation() == Isovelocity(1510.0)
    munk = SoundSpeedConfig(kind="munk").profile()
    assert munk is not None and munk.speed(1300.0) == pytest.approx(1500.0, abs=1e-9)
    # Munk (1974): c(0) = 1500 (1 + 0.00737 (e^2 - 3)).
    assert munk.speed(0.0) == pytest.approx(1500.0 * (1 + 0.00737 * (np.e**2 - 3)), rel=1e-12)
    ts = SoundSpeedConfig(
        kind="temperature_salinity",
        depths_m=(0.0, 1000.0),
        temperatures_c=(25.0, 25.0),
        salinities_psu=(35.0,),
    ).profile()
    assert ts is not None and ts.speed(1000.0) == pytest.approx(1550.744, abs=5e-4)
    for data, field in [
        ({"kind": "table", "depths_m": [0, 10], "speeds_m_s": [1500]}, "speeds_m_s"),
        ({"kind": "table", "depths_m": [10, 0], "speeds_m_s": [1500, 1501]}, "depths_m"),
        ({"depths_m": [0.0]}, "depths_m"),
        (
            {
                "kind": "temperature_salinity",
                "depths_m": [0],
                "temperatures_c": [40],
                "salinities_psu": [35],
            },
            "temperatures_c",
        ),
    ]:
        with pytest.raises(ConfigError, match=field):
            validate(SoundSpeedConfig, data)


@pytest.mark.slow
@pytest.mark.parametrize("sound", [None, {"speed_m_s": 1510.0}, {"kind": "munk"}])
def test_mission_scenario_sound_reaches_the_rig(sound) -> None:
    from tasks.closed_loop.scenario import MissionScenario
    from tasks.closed_loop.world import single_vehicle_scene, standard_vehicle

    scenario = MissionScenario() if sound is None else MissionScenario(sound=sound)
    physics = build_physics(single_vehicle_scene(scenario), control_tick_s=0.2)
    parts = standard_vehicle(scenario, 0, 0, physics)
    usbl = next(d for d in parts.rig.devices if type(d).__name__ == "UsblDevice")
    medium = usbl._usbl.propagation
    if sound is None:
        assert medium is None
    elif "speed_m_s" in sound:
        assert medium == Isovelocity(1510.0)
    else:
        assert isinstance(medium, LayeredMedium)
        assert medium.profile.speed(0.0) == pytest.approx(1548.52, abs=0.01)


@pytest.mark.slow
def test_online_modem_takes_the_rigs_medium() -> None:
    """The follower's modem (seed 003's instant ranges) in a sound-speed gradient: the range is
    the nominal speed times the circular ray's travel time, worked out in the test, and the
    latency the travel time plus the processing."""
    scene = SceneConfig(
        vehicles=(
            VehicleSpec(name="leader", east_m=0.0, north_m=0.0, depth_m=2.0),
            VehicleSpec(name="f1", east_m=160.0, north_m=-90.0, depth_m=4.0),
        )
    )
    phys = build_physics(scene, control_tick_s=0.2)
    cfg = ModemConfig(range={"sigma_m": 0.0, "bias_m": 0.0}, broadcast="truth")
    rig = SensorRig({"modem": cfg}, phys, "f1", 5, 0, "f1", propagation=MEDIUM)
    plain = SensorRig({"modem": cfg}, phys, "f1", 5, 0, "f1")
    lead, me = phys.truth("leader"), phys.truth("f1")
    got, ref = [], []
    for k in range(1, 60):
        t = 0.2 * k
        peers = {"leader": Peer(dataclasses.replace(lead, t_s=t), None)}
        at = dataclasses.replace(me, t_s=t)
        got += rig.sense(k, at, {}, peers=peers).arrived
        ref += plain.sense(k, at, {}, peers=peers).arrived
    assert got and len(got) == len(ref)
    sites = [phys.site_position_world("modem", v) for v in ("leader", "f1")]
    travel, _ = _circle(sites[0][None], sites[1][None])
    for m, r in zip(got, ref, strict=True):
        assert m.value[0] == pytest.approx(1500.0 * travel[0], rel=1e-9)
        assert r.value[0] == pytest.approx(np.linalg.norm(sites[0] - sites[1]), rel=1e-12)
        assert m.t_arrival_s - m.t_valid_s == pytest.approx(travel[0] + 0.5, rel=1e-9)
    assert abs(got[0].value[0] - ref[0].value[0]) > 1e-3  # the medium is heard
