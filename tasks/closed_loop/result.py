"""What a mission run leaves behind: plain data (typed per-tick columns with units), never the
live task.

Per vehicle, :class:`VehicleRun` holds the per-tick columns (:data:`TICK_COLUMNS`, plus the
mission's own), the fixes the navigator received (one table per device) and the way-point
outcome; :class:`MissionRun` holds the vehicles of one run and whether it failed. Both are
registered with the block store (:mod:`tasks.core.store`), so they travel between workers and to
disk as data, and the report exports them as Parquet (:mod:`tasks.core.export`, schema in
``docs/run-data.md``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tasks.closed_loop.scenario import MODES
from tasks.core import store
from tasks.core.export import Column

ENU = ("east", "north", "up")

TICK_COLUMNS: Mapping[str, tuple[str, str, tuple[str, ...]]] = {
    "t": ("s", "simulation time", ()),
    "truth_pos": ("m", "true position of the reference point, world ENU", ENU),
    "truth_quat_wxyz": ("1", "true attitude quaternion, body FLU to world ENU", tuple("wxyz")),
    "truth_rph": (
        "rad",
        "true roll (stbd down +), pitch (nose up +), heading (cw from north)",
        ("roll", "pitch", "heading"),
    ),
    "truth_vel": ("m/s", "true velocity over ground, world ENU", ENU),
    "truth_vel_water": ("m/s", "true velocity through water, world ENU", ENU),
    "truth_current": ("m/s", "water velocity at the vehicle, world ENU", ENU),
    "ekf_pos": ("m", "EKF position estimate, world ENU", ENU),
    "ekf_P": ("m^2", "EKF position covariance, world ENU (symmetrised: (P + P^T) / 2)", ENU),
    "dr_pos": ("m", "dead-reckoned position, world ENU", ENU),
    "meas_heading": ("rad", "compass heading, clockwise from north", ()),
    "meas_depth": ("m", "pressure depth (held between samples), positive down", ()),
    "meas_speed": ("m/s", "speed navigation used (log, else odometry)", ()),
    "speed_from_log": ("bool", "whether meas_speed is the log's", ()),
    "truth_tail_angles": (
        "rad",
        "true tail joint angles: peduncle to hull, caudal fin to peduncle (to port +)",
        ("peduncle", "caudal_fin"),
    ),
    "truth_fin_angles": (
        "rad",
        "true lateral fin pitch angles (leading edge up +)",
        ("port", "starboard"),
    ),
    "motor_power": ("W", "mechanical motor power", ()),
    "cmd_tail_beat_frequency": ("Hz", "commanded tail-beat frequency", ()),
    "cmd_tail_bias": ("rad", "commanded tail bias (positive turns to port)", ()),
    "cmd_fin_port": ("rad", "commanded port lateral fin angle", ()),
    "cmd_fin_starboard": ("rad", "commanded starboard lateral fin angle", ()),
    "cmd_battery": ("m", "commanded battery position (forward +)", ()),
    "guidance_course": ("rad", "commanded course, clockwise from north", ()),
    "guidance_depth": ("m", "commanded depth", ()),
    "guidance_speed": ("m/s", "commanded speed through water", ()),
    "guidance_mode": ("enum", "guidance mode (labelled: transit, ascend, surface, dive, done)", ()),
    "guidance_waypoint": ("index", "way-point being approached", ()),
    "usbl_event": ("bool", "a USBL fix reached the navigator at this tick", ()),
    "gps_event": ("bool", "a GPS fix reached the navigator at this tick", ()),
}
"""Per-tick columns of every vehicle: name -> (unit, description, components)."""

CURRENT_COLUMN = ("m/s", "EKF current estimate (east, north)", ("east", "north"))
"""The column ``ekf_current``, present when the EKF carries the current."""

NIS_COLUMN = (
    "1",
    "normalised innovation squared of the update (what the gate tests); null when the fix was "
    "refused before the update or not applied",
    (),
    True,
)
"""The ``nis`` column of the fix tables (nullable: (unit, description, components, True))."""

FIX_COLUMNS: Mapping[str, Mapping[str, tuple]] = {
    "usbl": {
        "t_valid": ("s", "time of validity (acoustic reply)", ()),
        "t_arrival": ("s", "time the fix reached the navigator", ()),
        "range": ("m", "measured slant range to the transceiver", ()),
        "azimuth": ("rad", "measured azimuth, clockwise from north", ()),
        "elevation": ("rad", "measured elevation, positive up", ()),
        "accepted": ("bool", "applied by the navigator (not gated out or refused)", ()),
        "position": ("m", "the fix's own position of the reference point, world ENU", ENU),
        "nis": NIS_COLUMN,
    },
    "gps": {
        "t_valid": ("s", "time of validity", ()),
        "t_arrival": ("s", "time the fix reached the navigator", ()),
        "east": ("m", "measured antenna east", ()),
        "north": ("m", "measured antenna north", ()),
        "accepted": ("bool", "applied by the navigator (not gated out)", ()),
        "position": ("m", "the fix (antenna, up = 0), world ENU", ENU),
        "nis": NIS_COLUMN,
    },
    "modem": {
        "t_valid": ("s", "time of validity (the range was measured)", ()),
        "t_arrival": ("s", "time the range and the leader's message reached the navigator", ()),
        "range": ("m", "measured slant range between the modem transducers", ()),
        "horizontal_range": ("m", "the range made horizontal with the depths (0: refused)", ()),
        "centre_east": ("m", "east of the range circle's centre used (leader side)", ()),
        "centre_north": ("m", "north of the range circle's centre used", ()),
        "hdop": ("1", "HDOP of the fix (seed 003 eq. 7-8; 0 if not computed, capped at 100)", ()),
        "criterion": ("1", "V^T P V of the adjustment (GA) or the NIS (EKF); 0 otherwise", ()),
        "refusal": ("enum", "ok (accepted), else why not (labelled: REFUSAL_LABELS)", ()),
        "accepted": ("bool", "the range corrected the estimate", ()),
        "position": ("m", "the estimate after the range, world ENU (up = -depth)", ENU),
    },
    "doa": {
        "t_valid": ("s", "time of validity (the bearing set)", ()),
        "t_arrival": ("s", "time the bearing reached the navigator", ()),
        "beacon": ("index", "the beacon seen: i of the scene's site beacon_<i>", ()),
        "azimuth": ("rad", "measured azimuth of the beacon, clockwise from north", ()),
        "elevation": ("rad", "measured elevation of the beacon, positive up", ()),
        "tan_phi": (
            "1",
            "measured tan(phi), phi counter-clockwise from east (seed 004 eq. 17); 0 where the "
            "tangent is not ok",
            (),
        ),
        "tan_lambda": ("1", "measured tan(lambda) (seed 004 eq. 17); 0 where not ok", ()),
        "tangent_ok": ("bool", "the tangent pair is within doa.max_tangent", ()),
        "accepted": ("bool", "the filter's update at a filter step took the bearing", ()),
        "beacon_east": ("m", "east of the beacon (the scene's site)", ()),
        "beacon_north": ("m", "north of the beacon", ()),
        "beacon_up": ("m", "up of the beacon", ()),
    },
}
"""Columns of the fix tables, by device (``doa``: one row per bearing of a set, ``mission/seed004``;
its fix record's measurement vector is the columns after ``t_arrival`` but ``accepted``)."""

REFUSAL_LABELS = (
    "ok",
    "dr",
    "no range",
    "range below minimum",
    "gate",
    "no fix",
    "no direction",
    "degenerate",
)
"""Labels of the modem table's ``refusal`` codes (``tasks.missions.swarm.REFUSAL_CODES``)."""

ENUM_LABELS: Mapping[str, tuple[str, ...]] = {"guidance_mode": MODES, "refusal": REFUSAL_LABELS}
"""The labels of the integer enum columns (code ``i`` is ``labels[i]``), by column name: the
files hold them as labelled (dictionary-encoded) columns."""


@store.plain_data("closed_loop.EstimateTrack")
@dataclass(frozen=True)
class EstimateTrack:
    """One position estimate a vehicle's navigation part declares, by the per-tick columns that
    hold it: what the recording draws as that vehicle's track of ``method`` (with its covariance
    ellipsoid when it has one) and what the run data names.

    Attributes:
        column: the per-tick position column, shape (T, 3) (east, north, up) or (T, 2) (east,
            north; drawn at the true depth), m, world ENU.
        method: the method's name in labels and colours (``"EKF"``, ``"DR"``, ``"GA1"``...):
            :func:`tasks.core.style.rgb` gives its colour.
        covariance: the column of its position covariance, shape (T, 3, 3) or (T, 2, 2)
            (horizontal), m^2, world ENU; ``None`` for an estimate without one (dead reckoning).
    """

    column: str
    method: str
    covariance: str | None = None


STANDARD_ESTIMATES: tuple[EstimateTrack, ...] = (
    EstimateTrack("ekf_pos", "EKF", "ekf_P"),
    EstimateTrack("dr_pos", "DR"),
)
"""The estimates of the standard navigation part (:data:`TICK_COLUMNS`): the EKF with its
covariance and dead reckoning."""


@store.plain_data("closed_loop.VehicleRun")
@dataclass
class VehicleRun:
    """One vehicle of one mission run, as plain data.

    Attributes:
        name: the vehicle's name in the scene.
        ticks: per-tick columns by name (see :data:`TICK_COLUMNS`), each of length T.
        fixes: per device, the fixes the navigator received (see :data:`FIX_COLUMNS`).
        waypoints: per way-point as flown: index, east_m, north_m, acceptance_radius_m,
            closest_true_distance_m, closest_at_s, reached_by_truth, reached_by_estimate,
            leg_end_s.
        summary: scalar results (errors in m, duration s, energy J, fix counts).
        outcome: plain data the mission's parts report at the end (see their ``outcome``).
        estimates: the position estimates its navigation part declared
            (:attr:`~tasks.closed_loop.parts.VehicleParts.estimates`), for the recording.
    """

    name: str
    ticks: dict[str, Column]
    fixes: dict[str, dict[str, Column]] = field(default_factory=dict)
    waypoints: list[dict[str, Any]] = field(default_factory=list)
    summary: dict[str, float] = field(default_factory=dict)
    outcome: dict[str, Any] = field(default_factory=dict)
    estimates: tuple[EstimateTrack, ...] = STANDARD_ESTIMATES

    def __getitem__(self, name: str) -> NDArray:
        """The values of a per-tick column."""
        return self.ticks[name].values


@store.plain_data("closed_loop.MissionRun")
@dataclass
class MissionRun:
    """One run of a mission, as plain data.

    Attributes:
        run: run index.
        seed: batch seed.
        failed: ``None``, or what failed, when and why.
        vehicles: the vehicles, in the scene's order.
    """

    run: int
    seed: int
    failed: str | None
    vehicles: dict[str, VehicleRun] = field(default_factory=dict)

    @property
    def lead(self) -> VehicleRun:
        """The first vehicle (the only one of a one-vehicle mission)."""
        return next(iter(self.vehicles.values()))

    @property
    def summary(self) -> dict[str, float]:
        """The first vehicle's summary (empty if the run has no data)."""
        return self.lead.summary if self.vehicles else {}

    @property
    def waypoints(self) -> list[dict[str, Any]]:
        """The first vehicle's way-points."""
        return self.lead.waypoints if self.vehicles else []


class TickLog:
    """Per-tick rows of one vehicle, turned into columns at the end (lists while flying, so the
    loop appends in O(1))."""

    def __init__(self, extra: Mapping[str, tuple[str, str, str, tuple[str, ...], bool]]):
        self.rows: dict[str, list] = {k: [] for k in TICK_COLUMNS}
        self.extra = dict(extra)
        for k in self.extra:
            self.rows[k] = []
        self.current: list = []

    def add(self, values: Mapping[str, Any]) -> None:
        """Append one tick (every column of :data:`TICK_COLUMNS`, plus the extras)."""
        for k, v in values.items():
            self.rows[k].append(v)

    def columns(self) -> dict[str, Column]:
        """The columns of the ticks logged so far (a matrix column, the covariance, is
        symmetrised: ``(P + P^T) / 2``, which moves it by rounding only)."""
        out = {}
        n = len(self.rows["t"])
        for k, (unit, desc, comps) in TICK_COLUMNS.items():
            v = np.asarray(self.rows[k][:n])
            if v.ndim == 3:
                v = 0.5 * (v + np.swapaxes(v, 1, 2))
            out[k] = Column(v, unit, desc, comps, labels=ENUM_LABELS.get(k, ()))
        if self.current:
            unit, desc, comps = CURRENT_COLUMN
            out["ekf_current"] = Column(np.asarray(self.current[:n]), unit, desc, comps)
        for k, (_, unit, desc, comps, nullable) in self.extra.items():
            out[k] = Column(np.asarray(self.rows[k][:n]), unit, desc, comps, nullable)
        return out


def fix_columns(fixes) -> dict[str, dict[str, Column]]:
    """The fix tables (see :data:`FIX_COLUMNS`) of a navigation part's fix records."""
    out: dict[str, dict[str, Column]] = {}
    for device, spec in FIX_COLUMNS.items():
        rows = [f for f in fixes if f.device == device]
        if not rows:
            continue
        z = np.array([f.z for f in rows], dtype=float).reshape(len(rows), -1)
        values = {
            "t_valid": np.array([f.t_valid_s for f in rows]),
            "t_arrival": np.array([f.t_arrival_s for f in rows]),
            "accepted": np.array([f.accepted for f in rows], dtype=bool),
            "position": np.array([f.position_m for f in rows], dtype=float).reshape(-1, 3),
            "nis": np.array([f.nis for f in rows], dtype=float),
        }
        for j, name in enumerate(k for k in spec if k not in values):
            values[name] = z[:, j]
        for k in spec:
            if k in ENUM_LABELS:  # codes carried as floats in the fix's measurement vector
                values[k] = values[k].astype(np.int64)
            elif spec[k][0] == "bool":  # flags carried as floats there too
                values[k] = values[k].astype(bool)
            elif spec[k][0] == "index":
                values[k] = values[k].astype(np.int64)
        # spec[k] is (unit, description, components[, nullable]): never as far as labels
        out[device] = {
            k: Column(values[k], *spec[k], labels=ENUM_LABELS.get(k, ()))  # type: ignore[misc]
            for k in spec
        }
    return out


def summarise(vr: VehicleRun, waypoints, legs, completed: bool) -> None:
    """Fill a vehicle's way-point outcome and summary from its columns.

    Args:
        vr: the vehicle (its ``ticks`` and ``fixes`` filled).
        waypoints: the way-points as flown, (east m, north m, acceptance radius m).
        legs: how each leg ended (``{"waypoint", "reached", "t_s"}``).
        completed: whether guidance finished the mission.
    """
    t = vr["t"]
    truth, ekf, dr = vr["truth_pos"], vr["ekf_pos"], vr["dr_pos"]
    e_ekf = np.hypot(*(ekf - truth)[:, :2].T)
    e_dr = np.hypot(*(dr - truth)[:, :2].T)
    by_wp = {leg["waypoint"]: leg for leg in legs}
    wps = []
    for i, (east, north, radius) in enumerate(waypoints):
        d = np.hypot(truth[:, 0] - east, truth[:, 1] - north)
        j = int(np.argmin(d))
        leg = by_wp.get(i)
        wps.append(
            {
                "index": i,
                "east_m": east,
                "north_m": north,
                "acceptance_radius_m": radius,
                "closest_true_distance_m": float(d[j]),
                "closest_at_s": float(t[j]),
                "reached_by_truth": bool(d[j] <= radius),
                "reached_by_estimate": bool(leg["reached"]) if leg else False,
                "leg_end_s": float(leg["t_s"]) if leg else None,
            }
        )
    usbl = vr.fixes.get("usbl", {})
    gps = vr.fixes.get("gps", {})
    power = vr["motor_power"]
    dt = np.diff(t, prepend=t[0])
    summary = {
        "duration_s": float(t[-1]),
        "completed": float(completed),
        "ekf_mean_error_m": float(e_ekf.mean()),
        "ekf_max_error_m": float(e_ekf.max()),
        "ekf_final_error_m": float(e_ekf[-1]),
        "dr_mean_error_m": float(e_dr.mean()),
        "dr_max_error_m": float(e_dr.max()),
        "dr_final_error_m": float(e_dr[-1]),
        "usbl_fixes": float(len(usbl["t_valid"].values) if usbl else 0),
        "usbl_rejected": float((~usbl["accepted"].values).sum() if usbl else 0),
        "gps_fixes": float(len(gps["t_valid"].values) if gps else 0),
        "energy_j": float(np.sum(power * dt)),
        "mean_power_w": float(np.mean(power)),
    }
    if wps:
        summary["waypoints_reached_by_truth"] = float(sum(w["reached_by_truth"] for w in wps))
        summary["max_closest_distance_m"] = float(max(w["closest_true_distance_m"] for w in wps))
    vr.waypoints = wps
    vr.summary = summary
