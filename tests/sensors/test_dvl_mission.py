"""The DVL in the closed-loop missions' rig: off by default (the missions unchanged), on with
``sensors.use_dvl``, pinging in the physics world without changing anything else of a flight."""

import numpy as np
import pytest

from bauv_sim.build import build_physics
from bauv_sim.config import load_config
from bauv_sim.errors import ConfigError
from bauv_sim.sensors import DvlPing
from tasks.closed_loop.scenario import MissionScenario
from tasks.closed_loop.world import WaypointMission, fly, single_vehicle_scene, standard_vehicle

pytestmark = pytest.mark.slow

SHORT = {
    "guidance": {"waypoints": [{"east_m": 0.0, "north_m": 30.0}]},
    "timing": {"max_duration_s": 20.0},
}


def _scenario(**sensors):
    return load_config(MissionScenario, {**SHORT, "sensors": sensors})


def test_the_mission_rig_carries_the_dvl_only_when_asked_and_it_bottom_locks():
    off = _scenario()
    physics = build_physics(single_vehicle_scene(off))
    assert "dvl" not in [d.name for d in standard_vehicle(off, 1, 0, physics).rig.devices]
    on = _scenario(use_dvl=True)
    physics = build_physics(single_vehicle_scene(on))
    rig = standard_vehicle(on, 1, 0, physics).rig
    assert rig.lever_arms_body_m["dvl"] == pytest.approx((0.4, 0.0, -0.163), abs=1e-12)
    every = round(on.sensors.dvl.period_s / physics.control_tick_s)
    pings = [
        m
        for k in range(every, 5 * every + 1, every)
        for m in rig.sense(k, physics.truth(), physics.commands()).arrived
        if m.device == "dvl"
    ]
    assert len(pings) == 5 and all(isinstance(m.payload, DvlPing) for m in pings)
    # 3 m deep over the default seabed (about 6 m): about 3 m of altitude, bottom lock
    ping = pings[-1].payload
    assert ping.mode == 1 and 2.0 < ping.altitude_m < 4.0 and np.isfinite(pings[-1].value).all()


def test_a_flight_with_the_dvl_is_the_flight_without_it():
    """The DVL draws from its own streams and the navigator does not read it: the same seed
    flies the same flight, bit for bit."""
    a = fly(WaypointMission(), _scenario(), 3, 0)
    b = fly(WaypointMission(), _scenario(use_dvl=True), 3, 0)
    assert a.failed is None and b.failed is None
    assert a.lead.ticks.keys() == b.lead.ticks.keys()
    for name, col in a.lead.ticks.items():
        np.testing.assert_array_equal(b.lead.ticks[name].values, col.values, err_msg=name)


def test_a_dvl_period_off_the_tick_is_refused_naming_the_field():
    with pytest.raises(ConfigError, match=r"sensors\.dvl\.period_s = 0\.3"):
        _scenario(use_dvl=True, dvl={"period_s": 0.3})
    _scenario(dvl={"period_s": 0.3})  # not carried: not checked
