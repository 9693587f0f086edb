"""Seabed soundings from acoustic ranges: DVL beams, an altimeter or a multibeam.

A beam of unit direction ``d`` (body FLU) from a transducer at the lever arm ``r`` (body FLU, from
the vehicle's reference point) that echoes at range ``rho`` hits the seabed at

    p_hit = p_ref + R(roll, pitch, heading) (r + rho d)          (world ENU)

so its horizontal offset from the reference point is the (east, north) part of
``R (r + rho d)`` and the seabed depth there is ``depth_ref - [R (r + rho d)]_z`` with
``depth_ref`` the reference point's depth from the pressure sensor (depth = -z). ``R`` is the
measured attitude's rotation world-from-body: yaw about world z (``pi/2 - heading``), then pitch
nose up, then roll starboard down (the project's convention, as ``bauv_sim.frames``). An
altimeter is one beam ``(0, 0, -1)``; a multibeam any number of beams.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class Soundings:
    """Seabed soundings of one ping, relative to the vehicle's reference point.

    Attributes:
        offset_m: horizontal seabed hit point minus the vehicle reference point, world
            (east, north), shape ``(m, 2)``, m (0 where not valid).
        depth_m: measured seabed depth at those points, shape ``(m,)``, m, positive down (0 where
            not valid).
        valid: whether each beam gave a sounding, shape ``(m,)``.
    """

    offset_m: Array
    depth_m: Array
    valid: BoolArray

    @property
    def count(self) -> int:
        """Number of valid soundings."""
        return int(np.count_nonzero(self.valid))


def world_from_body(roll_pitch_heading_rad: ArrayLike) -> Array:
    """Rotation world ENU from body FLU for one attitude.

    Args:
        roll_pitch_heading_rad: ``(roll, pitch, heading)``, shape ``(3,)``, rad; roll starboard
            down positive, pitch nose up positive, heading clockwise from north.

    Returns:
        ``R = Rz(pi/2 - heading) Ry(-pitch) Rx(roll)``, shape ``(3, 3)``.
    """
    roll, pitch, heading = (float(a) for a in np.asarray(roll_pitch_heading_rad, dtype=float))
    yaw = np.pi / 2 - heading
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(-pitch), np.sin(-pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


def soundings(
    ranges_m: ArrayLike,
    echo: ArrayLike,
    directions_body: ArrayLike,
    roll_pitch_heading_rad: ArrayLike,
    lever_arm_body_m: ArrayLike,
    vehicle_depth_m: float,
) -> Soundings:
    """Seabed soundings of one ping (module docstring's equation).

    Args:
        ranges_m: slant range of each beam, shape ``(m,)``, m.
        echo: whether each beam echoed, shape ``(m,)``; a beam without echo, or with a range that
            is not finite and > 0, is not valid.
        directions_body: unit direction of each beam, body FLU, shape ``(m, 3)``.
        roll_pitch_heading_rad: the measured attitude, shape ``(3,)``, rad.
        lever_arm_body_m: the transducer from the reference point, body FLU, shape ``(3,)``, m.
        vehicle_depth_m: depth of the reference point (pressure sensor), m, positive down.

    Returns:
        The soundings; never NaN (invalid beams hold zeros).

    Raises:
        NavInputError: shapes that do not match, a non-finite attitude, lever arm or depth.
    """
    rho = np.asarray(ranges_m, dtype=float).reshape(-1)
    m = rho.size
    ok = np.asarray(echo, dtype=bool).reshape(-1)
    d = np.asarray(directions_body, dtype=float)
    att = np.asarray(roll_pitch_heading_rad, dtype=float)
    lever = np.asarray(lever_arm_body_m, dtype=float)
    if ok.size != m or d.shape != (m, 3):
        raise NavInputError(
            f"echo {ok.shape} and directions_body {d.shape}: must be ({m},) and ({m}, 3) for "
            f"{m} ranges"
        )
    if att.shape != (3,) or not np.all(np.isfinite(att)):
        raise NavInputError(f"roll_pitch_heading_rad = {att}: must be 3 finite angles, rad")
    if lever.shape != (3,) or not np.all(np.isfinite(lever)):
        raise NavInputError(f"lever_arm_body_m = {lever}: must be 3 finite numbers, m")
    if not np.isfinite(vehicle_depth_m):
        raise NavInputError(f"vehicle_depth_m = {vehicle_depth_m}: must be finite")
    valid = ok & np.isfinite(rho) & (rho > 0.0) & np.all(np.isfinite(d), axis=1)
    r = world_from_body(att)
    rel_body = lever[None, :] + np.where(valid, rho, 0.0)[:, None] * np.where(
        valid[:, None], d, 0.0
    )
    rel_world = rel_body @ r.T
    offset = np.where(valid[:, None], rel_world[:, :2], 0.0)
    depth = np.where(valid, float(vehicle_depth_m) - rel_world[:, 2], 0.0)
    return Soundings(offset_m=offset, depth_m=depth, valid=valid)
