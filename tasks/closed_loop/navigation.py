"""The navigation part of a vehicle: rig records in, estimate out (the vehicle's computer).

:class:`EkfNavigation` is the standard part: the online :class:`~nav.navigator.Navigator` (EKF,
optionally with the water current in its state, and a dead-reckoning track) fed from the rig:

1. the speed is the log's (through water) when it has one, else the odometry's;
2. predict with the compass heading and that speed (not on the initial tick);
3. update with the pressure depth when it was sampled this tick;
4. apply every fix that reached the vehicle this tick, in arrival order, at its time of validity,
   each through the navigator's chi-square gate.

Step 4 is the adaptation of devices to measurements: a :class:`FixAdapter` per device turns the
rig's record into a :class:`nav.navigator.Measurement` (value, time of validity and its
measurement model from :mod:`nav.models`), lets the navigator fuse it and keeps a
:class:`FixRecord`. The standard adapters are :class:`UsblFixes` (range, azimuth, elevation; the
transponder's lever arm rotated by the vehicle's own measured attitude at that time moves the
effective transceiver) and :class:`GpsFixes` (the antenna's lever arm removed from the fix); a
mission adds its own devices' adapters (``adapters``) without touching the navigator, which never
asks which device a measurement came from.

Each tick returns a :class:`NavOutput`; each fix is kept as a :class:`FixRecord` for the run data.
A mission can wrap this part (seed 001's DRNS beside the EKF, :mod:`tasks.missions.correction`) or
replace it with any object that has :meth:`step` and :meth:`outcome`; what a wrapping part adds
is a typed report (a frozen dataclass of the mission's) in :attr:`NavOutput.report`, read back
with :func:`report_of`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

from bauv_sim.frames import R_from_roll_pitch_heading
from bauv_sim.geo import LocalFrame
from bauv_sim.sensors.online import Broadcast
from bauv_sim.sensors.online import Measurement as Record
from bauv_sim.sensors.rig import RigTick
from nav.errors import NavInputError
from nav.models import (
    CourseSpeedDepthMotion,
    DepthMeasurement,
    HorizontalPositionMeasurement,
    UsblMeasurement,
)
from nav.navigator import Estimate, Measurement, Navigator, OnlineNavigator
from tasks.closed_loop.scenario import NavigationConfig

Array = NDArray[np.float64]


@dataclass(frozen=True)
class FixRecord:
    """A position fix as the navigator received it.

    Attributes:
        device: ``"usbl"`` or ``"gps"`` (missions add theirs: ``"modem"``, ``"doa"``; the
            columns of each: :data:`tasks.closed_loop.result.FIX_COLUMNS`).
        t_valid_s: time of validity, s.
        t_arrival_s: time it reached the vehicle, s.
        z: the measurement, shape (m,): USBL (range m, azimuth rad, elevation rad), GPS antenna
            (east m, north m), DOA (beacon, azimuth rad, elevation rad, tan phi, tan lambda,
            tangent ok, beacon east/north/up m).
        accepted: whether the navigator applied it (not rejected by the gate or refused).
        position_m: the fix's own position of the vehicle's reference point, shape (3,), m,
            world (USBL inverted; GPS: the antenna's fix, up = 0; a bearing has none: DOA
            gives the filter's estimate at its arrival, not written to the run data).
        nis: the update's normalised innovation squared ``y^T S^-1 y`` (what the gate tests),
            NaN when the navigator refused the fix before computing it (or did not apply GPS).
        reference_m: a horizontal fix of the vehicle's reference point (east, north), shape
            (2,), m, that guidance is told of (GPS: the antenna's fix less its lever arm), or
            ``None``.
    """

    device: str
    t_valid_s: float
    t_arrival_s: float
    z: Array
    accepted: bool
    position_m: Array
    nis: float = float("nan")
    reference_m: Array | None = None


@dataclass(frozen=True)
class NavOutput:
    """The navigation part's output at one tick (what guidance and the autopilot read).

    Attributes:
        t_s: time, s.
        estimate: the EKF's position estimate and covariance (world ENU, m, m^2).
        dr_position_m: dead-reckoned position, shape (3,), m, world.
        current_m_s: estimated current (east, north), shape (2,), m/s, or ``None``.
        heading_rad: measured heading (compass), rad clockwise from north.
        speed_m_s: the speed navigation used (log, else odometry), m/s.
        speed_from_log: whether that speed is the log's.
        odometry_speed_m_s: the odometry's speed (held), m/s.
        depth_m: measured depth (held), m.
        ins: INS ``(roll, pitch, roll rate, pitch rate, heading rate)``, shape (5,), rad, rad/s.
        fixes: the fixes delivered this tick.
        gps_fix: whether a GPS fix reached the vehicle this tick.
        gps_reference_m: that fix with the antenna's lever arm removed (the reference point's
            east, north), shape (2,), m, or ``None``.
        report: what a wrapping part adds, typed: a frozen dataclass of the part's (e.g.
            :class:`nav.navigator.FollowerReport`, seed 001's corrected position), read back
            with :func:`report_of`; ``None`` for the standard part.
        broadcast: what the vehicle sends about itself over the acoustic modem (its position,
            velocity and covariance as its navigator states them), or ``None``; the world hands
            it to the other vehicles' rigs (:class:`~bauv_sim.sensors.online.Peer`).
    """

    t_s: float
    estimate: Estimate
    dr_position_m: Array
    current_m_s: Array | None
    heading_rad: float
    speed_m_s: float
    speed_from_log: bool
    odometry_speed_m_s: float
    depth_m: float
    ins: Array
    fixes: tuple[FixRecord, ...]
    gps_fix: bool
    gps_reference_m: Array | None = None
    report: object | None = None
    broadcast: Broadcast | None = None


R = TypeVar("R")


def report_of(nav: NavOutput, kind: type[R]) -> R:
    """The navigation output's report, checked to be of the type a reader expects.

    Args:
        nav: the navigation output.
        kind: the report's type.

    Raises:
        TypeError: if the part that produced ``nav`` reports something else (a mission wired
            a guidance part to the wrong navigation part).
    """
    rep = nav.report
    if not isinstance(rep, kind):
        raise TypeError(
            f"navigation report is {type(rep).__name__}, not the {kind.__name__} expected"
        )
    return rep


class FixAdapter(Protocol):
    """Turns one device's records into measurements for the navigator (module docstring)."""

    def apply(self, nav: OnlineNavigator, m: Record, t_s: float) -> FixRecord:
        """Fuse the record ``m`` that reached the vehicle at ``t_s`` (s) and say how it went."""
        ...


@dataclass(frozen=True)
class UsblFixes:
    """USBL fixes: range, azimuth and elevation from the transceiver to the vehicle's
    transponder (:class:`nav.models.UsblMeasurement`), applied at their time of validity.

    Attributes:
        model: the measurement model with the transceiver's true position.
        transponder_body_m: the transponder's lever arm, shape (3,), m, body FLU; rotated by the
            attitude measured at the time of validity, it moves the effective transceiver.
    """

    model: UsblMeasurement
    transponder_body_m: Array

    def apply(self, nav: OnlineNavigator, m: Record, t_s: float) -> FixRecord:
        roll, pitch, h = m.attitude_rad
        R = R_from_roll_pitch_heading(roll, pitch, h)
        model = dataclasses.replace(
            self.model,
            transceiver_world_m=self.model.transceiver_world_m - R @ self.transponder_body_m,
        )
        nis = float("nan")
        try:
            info = nav.fuse(Measurement(m.value, model, m.t_valid_s))
            accepted, nis = not bool(info.rejected[0]), float(info.nis[0])
        except NavInputError:
            accepted = False
        return FixRecord("usbl", m.t_valid_s, t_s, m.value, accepted, model.invert(m.value), nis)


@dataclass(frozen=True)
class GpsFixes:
    """GPS fixes of the antenna (east, north) at the surface, the antenna's lever arm removed
    (:class:`nav.models.HorizontalPositionMeasurement`), applied now; always recorded and told
    to guidance, applied only with ``apply_to_estimate``.

    Attributes:
        model: the measurement model.
        antenna_body_m: the antenna's lever arm, shape (3,), m, body FLU.
        apply_to_estimate: whether the navigator fuses them.
        frame: the scene's geographic frame when the receiver reports WGS 84 (latitude,
            longitude) in deg (:class:`bauv_sim.sensors.gps.GpsDevice` given the frame): the
            fix is made east/north with it (the navigator stays east/north; the record's ``z``
            is that east/north); ``None``: the receiver reports east/north.
    """

    model: HorizontalPositionMeasurement
    antenna_body_m: Array
    apply_to_estimate: bool = True
    frame: LocalFrame | None = None

    def apply(self, nav: OnlineNavigator, m: Record, t_s: float) -> FixRecord:
        z = m.value
        if self.frame is not None:
            z = np.concatenate(self.frame.to_local(z[0], z[1]), axis=None)
        roll, pitch, h = m.attitude_rad
        arm_world = R_from_roll_pitch_heading(roll, pitch, h) @ self.antenna_body_m
        z_ref = z - arm_world[:2]
        accepted, nis = True, float("nan")
        if self.apply_to_estimate:
            info = nav.fuse(Measurement(z_ref, self.model))
            accepted, nis = not bool(info.rejected[0]), float(info.nis[0])
        position = np.array([z[0], z[1], 0.0])
        return FixRecord("gps", m.t_valid_s, t_s, z, accepted, position, nis, z_ref)


class EkfNavigation:
    """The standard navigation part (see the module docstring).

    Args:
        cfg: navigator settings.
        x0: initial position estimate, shape (3,), m, world.
        transceiver_world_m: the USBL transceiver, shape (3,), m, world.
        lever_arms_body_m: the rig's lever arms by device (``usbl``, ``gps``), body FLU, m.
        use_gps: apply GPS fixes (they are still recorded and reported to guidance). A vehicle
            without USBL has no USBL device in its rig.
        adapters: the mission's own devices' adapters, by device name in the rig (added to,
            or replacing, the standard ``usbl`` and ``gps``).
        frame: the scene's geographic frame when the rig's GPS reports latitude/longitude (see
            :class:`GpsFixes`), else ``None``.
    """

    def __init__(
        self,
        cfg: NavigationConfig,
        x0: Array,
        transceiver_world_m: Array,
        lever_arms_body_m: dict[str, tuple[float, float, float]],
        use_gps: bool = True,
        adapters: Mapping[str, FixAdapter] | None = None,
        frame: LocalFrame | None = None,
    ):
        n = cfg
        self.use_gps = use_gps
        self.motion = CourseSpeedDepthMotion(
            math.radians(n.sigma_heading_deg), n.sigma_speed_m_s, n.sigma_vertical_m_per_tick
        )
        self.usbl_model = UsblMeasurement(
            transceiver_world_m,
            n.sigma_range_m,
            math.radians(n.sigma_azimuth_deg),
            math.radians(n.sigma_elevation_deg),
        )
        self.transceiver_world_m = transceiver_world_m
        self.gps_model = HorizontalPositionMeasurement(n.sigma_gps_m)
        self.depth_model = DepthMeasurement(n.sigma_depth_m)
        zero = (0.0, 0.0, 0.0)
        self.transponder_arm = np.asarray(lever_arms_body_m.get("usbl", zero), dtype=float)
        self.antenna_arm = np.asarray(lever_arms_body_m.get("gps", zero), dtype=float)
        self.adapters: dict[str, FixAdapter] = {
            "usbl": UsblFixes(self.usbl_model, self.transponder_arm),
            "gps": GpsFixes(self.gps_model, self.antenna_arm, use_gps, frame),
            **(adapters or {}),
        }
        self.nav = Navigator(
            0.0,
            x0,
            initial_covariance(cfg),
            self.motion,
            n.history_s,
            n.gate_probability if n.gate_enabled else None,
            current_sigma0_m_s=n.current_sigma0_m_s if n.estimate_current else None,
            current_walk_m_s_per_sqrt_s=n.current_walk_m_s_per_sqrt_s,
            max_consecutive_rejections=n.max_consecutive_rejections or None,
        )

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        """One navigation tick (see the module docstring).

        Args:
            tick: the rig's records of this tick.
            initial: the initial tick (no prediction).
        """
        t = tick.t_s
        heading = tick.value("compass")
        log_speed = tick.value("log")
        odo_speed = tick.value("odometry")
        speed, from_log = (log_speed, True) if log_speed is not None else (odo_speed, False)
        depth = tick.value("pressure")
        nav = self.nav
        if not initial:
            nav.predict(t, heading, speed, 0.0)
        if "pressure" in tick.sampled:
            nav.fuse(Measurement(np.array([depth]), self.depth_model))
        new: list[FixRecord] = []
        gps_ref = None
        for m in tick.arrived:
            adapter = self.adapters.get(m.device)
            if adapter is None:
                continue
            rec = adapter.apply(nav, m, t)
            new.append(rec)
            if rec.reference_m is not None:
                gps_ref = rec.reference_m
        cur = nav.current_estimate
        return NavOutput(
            t_s=t,
            estimate=nav.estimate,
            dr_position_m=nav.dr_position,
            current_m_s=None if cur is None else cur[0],
            heading_rad=heading,
            speed_m_s=speed,
            speed_from_log=from_log,
            odometry_speed_m_s=odo_speed,
            depth_m=depth,
            ins=tick.held["ins"],
            fixes=tuple(new),
            gps_fix=gps_ref is not None,
            gps_reference_m=gps_ref,
        )

    def outcome(self) -> dict[str, Any]:
        """Plain data about the whole run (none for the standard part)."""
        return {}


def initial_covariance(cfg: NavigationConfig) -> Array:
    """The navigator's initial position covariance: the GNSS fix horizontally, the pressure
    sensor vertically, shape (3, 3), m^2."""
    return np.diag([cfg.initial_sigma_m**2, cfg.initial_sigma_m**2, cfg.sigma_depth_m**2])
