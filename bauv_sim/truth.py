"""The truth record: what the world produces and the only thing sensors read.

Both worlds (MuJoCo physics and the seeds' kinematic models) fill the same record. Arrays carry a
leading axis of Monte Carlo runs; a world whose truth is the same for every run (the seed 000
straight passage) uses a run axis of length 1 that broadcasts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bauv_sim.frames import course_speed_from_velocity, depth_from_z


@dataclass(frozen=True)
class Truth:
    """True motion of the vehicle, sampled on a time grid.

    Attributes:
        t_s: sample times, shape (T,), s.
        pos_world_m: positions of the vehicle's reference point, shape (n, T, 3), m, world.
        vel_ground_world_m_s: velocity over ground, shape (n, T, 3), m/s, world.
        vel_water_world_m_s: velocity through water (over ground minus current), shape (n, T, 3),
            m/s, world.
        heading_rad: heading of the body x axis, shape (n, T), rad clockwise from north.
        roll_pitch_rad: roll (starboard down +) and pitch (nose up +), shape (n, T, 2), rad.
        current_world_m_s: water velocity at the vehicle, shape (n, T, 3), m/s, world.
    """

    t_s: NDArray[np.float64]
    pos_world_m: NDArray[np.float64]
    vel_ground_world_m_s: NDArray[np.float64]
    vel_water_world_m_s: NDArray[np.float64]
    heading_rad: NDArray[np.float64]
    roll_pitch_rad: NDArray[np.float64]
    current_world_m_s: NDArray[np.float64]

    @property
    def n_runs(self) -> int:
        """Length of the run axis (1 when the truth is shared by all runs)."""
        return self.pos_world_m.shape[0]

    @property
    def depth_m(self) -> NDArray[np.float64]:
        """Depth, shape (n, T), m, positive down."""
        return depth_from_z(self.pos_world_m[..., 2])

    @property
    def course_over_ground_rad(self) -> NDArray[np.float64]:
        """Course over ground, shape (n, T), rad clockwise from north."""
        return course_speed_from_velocity(self.vel_ground_world_m_s)[0]

    @property
    def speed_over_ground_m_s(self) -> NDArray[np.float64]:
        """Horizontal speed over ground, shape (n, T), m/s."""
        return course_speed_from_velocity(self.vel_ground_world_m_s)[1]

    @property
    def speed_through_water_m_s(self) -> NDArray[np.float64]:
        """Horizontal speed through water, shape (n, T), m/s."""
        return course_speed_from_velocity(self.vel_water_world_m_s)[1]

    def take(self, index: NDArray[np.intp] | slice) -> Truth:
        """The record restricted to some time samples (same run axis)."""
        return Truth(
            self.t_s[index],
            self.pos_world_m[:, index],
            self.vel_ground_world_m_s[:, index],
            self.vel_water_world_m_s[:, index],
            self.heading_rad[:, index],
            self.roll_pitch_rad[:, index],
            self.current_world_m_s[:, index],
        )
