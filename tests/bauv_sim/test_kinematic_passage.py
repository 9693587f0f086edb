"""The straight passage reproduces its defining geometry."""

import math

import numpy as np
import pytest

from bauv_sim.config import load_config
from bauv_sim.errors import ConfigError
from bauv_sim.kinematic.passage import (
    StraightPassageConfig,
    TransceiverConfig,
    straight_passage,
)


def test_defaults_reproduce_figure7_geometry():
    cfg, tx = StraightPassageConfig(), TransceiverConfig(east_m=25.0, north_m=-40.0)
    tr = straight_passage(cfg, tx)
    p = tr.pos_world_m[0]
    rel = p[:, :2] - tx.position_world_m()[:2]
    d = np.hypot(rel[:, 0], rel[:, 1])
    assert int(np.argmin(d)) == 450 and d.min() == pytest.approx(10.0)
    # transceiver to starboard: the cross product of heading and the line of sight is negative
    v = tr.vel_ground_world_m_s[0, 450, :2]
    to_tx = -rel[450]
    assert v[0] * to_tx[1] - v[1] * to_tx[0] < 0
    assert np.allclose(tr.course_over_ground_rad, math.radians(220))
    assert np.allclose(tr.speed_over_ground_m_s, 1.0) and np.allclose(tr.depth_m, 3.0)
    assert len(tr.t_s) == 601 and tr.t_s[-1] == 600.0


def test_explicit_start_and_validation():
    cfg = StraightPassageConfig(start_east_m=1.0, start_north_m=2.0, depth_m=5.0)
    tr = straight_passage(cfg, TransceiverConfig())
    assert np.allclose(tr.pos_world_m[0, 0], [1.0, 2.0, -5.0])
    with pytest.raises(ConfigError, match="both start_east_m and start_north_m"):
        load_config(StraightPassageConfig, {"start_east_m": 1.0})
    with pytest.raises(ConfigError, match="duration_s"):
        load_config(StraightPassageConfig, {"duration_s": 10.5})
