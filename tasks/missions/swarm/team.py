"""The team comparison of a ``mission/swarm`` flight on the acoustic network (issue 24): the
flight's recorded measurements as a :class:`nav.cooperative.TeamRecord`, and the team methods on
it (:func:`nav.cooperative.team_tracks`) against the vehicles' truth (:mod:`tasks.missions.swarm`).

Every method sees the same data, the measurements the vehicles had in flight, on the control
tick's grid (vehicle 0 the leader, then f1, f2 ...):

* **dead reckoning over ground** of each vehicle from its per-tick columns, as its navigation
  stepped it (:func:`dr_steps`): the step from tick q to q + 1 is ``dt (S_{q+1} (sin H_{q+1},
  cos H_{q+1}) + c_q)`` with the log's speed S and the compass heading H of tick q + 1 and the
  current c the vehicle dead-reckoned with at the end of tick q (a follower's: the leader's
  estimate it received; the leader's: its EKF's); its covariance seed 003's eq. 5 for the
  course and speed over ground (:func:`nav.relative.dr_increment_covariance`) with the sigmas
  the vehicle's navigation assumes (the leader's ``sigma_heading_deg`` and ``sigma_speed_m_s``,
  the followers' ``sigma_course_deg`` and ``sigma_speed_m_s``), plus the current's uncertainty
  (:func:`~tasks.missions.swarm.coop.current_covariance`: the team filters have no current in
  their state);
* **the start**: each vehicle's initial estimate and covariance;
* **the depths**: the pressure depths;
* **the leader's USBL fixes**: the fix's own position of the reference point at its time of
  validity, its covariance the USBL's measurement noise (the leader's navigation sigmas) mapped
  by first-order propagation through the inversion
  (:meth:`nav.models.UsblMeasurement.fix_covariance`);
* **every range of the network** each vehicle received (its ``network`` table): sender,
  receiver, the stamps by the two clocks and the range, placed on the grid by the stamps (the
  vehicles know no other time: the clocks' offsets, milliseconds, are far below the tick):
  the transmission at the sample at or before the sender's scheduled time, the reception at the
  sample at or after the receiver's stamp.

The methods (``TEAM_METHODS``): seed 003's GA2 and range EKF on each follower's ranges from the
leader alone (``ga2``, ``leader-ekf``), the decentralised filters with every range, clocks in
the state and covariance intersection (``decentralised``, the online method's algorithm on the
record's grid) and the centralised EKF over the whole team (``central``, the reference). Per
vehicle: the mean, final and largest horizontal error against the truth, and the NEES (2 dof)
with its chi-square band.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim.acoustics.clock import draw_clocks
from nav.cooperative import TeamRecord, team_metrics, team_tracks
from nav.models import UsblMeasurement
from nav.relative import dr_increment, dr_increment_covariance
from tasks.closed_loop.result import EstimateTrack, MissionRun, VehicleRun
from tasks.core.export import Column
from tasks.missions.swarm.network import NETWORK
from tasks.missions.swarm.options import coop_options, current_covariance
from tasks.missions.swarm.scenario import FOLLOWERS, LEADER, SwarmScenario

Array = NDArray[np.float64]

TEAM_METHODS: tuple[str, ...] = ("ga2", "leader-ekf", "decentralised", "central")
"""The methods compared after each flight on the network."""


def dr_steps(
    v: VehicleRun,
    k: int,
    current: str,
    sigma_course_rad: float,
    sigma_speed_m_s: float,
    current_sigma_m_s: float,
) -> tuple[Array, Array]:
    """A vehicle's dead-reckoned steps over ground between its first ``k`` ticks (module
    docstring).

    Args:
        v: the vehicle's run.
        k: ticks used.
        current: the per-tick column of the current it dead-reckoned with (absent: none).
        sigma_course_rad: sigma_C of eq. 5, rad.
        sigma_speed_m_s: sigma_S of eq. 5, m/s.
        current_sigma_m_s: the current's uncertainty (:func:`current_covariance`), m/s.

    Returns:
        ``(step_m, cov_m2)``: shapes (k - 1, 2) m and (k - 1, 2, 2) m^2.
    """
    t = v["t"][:k]
    h, s = v["meas_heading"][1:k], v["meas_speed"][1:k]
    c = v[current][: k - 1, :2] if current in v.ticks else np.zeros((k - 1, 2))
    ve = s * np.sin(h) + c[:, 0]
    vn = s * np.cos(h) + c[:, 1]
    course, speed = np.arctan2(ve, vn), np.hypot(ve, vn)
    dt = np.diff(t)
    # dr_increment's dt S (sin C, cos C) with S dt as the speed over one second, per step
    step = dr_increment(course, speed * dt, 1.0)
    cov = dr_increment_covariance(course, speed * dt, 1.0, sigma_course_rad, sigma_speed_m_s * dt)
    return step, cov + current_covariance(dt, current_sigma_m_s)


def team_record(scn: SwarmScenario, flight: MissionRun) -> TeamRecord:
    """The flight's measurements as one team record (module docstring; one run).

    Raises:
        NavInputError: from :class:`~nav.cooperative.TeamRecord` if the flight's data do not
            make a record (naming the field).
    """
    team = (LEADER, *FOLLOWERS[: scn.followers.count])
    runs = [flight.vehicles[name] for name in team]
    k = min(len(v["t"]) for v in runs)
    t = runs[0]["t"][:k]
    nav = scn.navigation
    steps, covs = [], []
    for name, v in zip(team, runs, strict=True):
        if name == LEADER:
            ln = scn.leader.navigation
            args = ("ekf_current", math.radians(ln.sigma_heading_deg), ln.sigma_speed_m_s)
        else:
            args = ("current_est", math.radians(nav.sigma_course_deg), nav.sigma_speed_m_s)
        step, cov = dr_steps(v, k, *args, nav.coop.current_sigma_m_s)
        steps.append(step)
        covs.append(cov)
    lead = runs[0]
    usbl = lead.fixes.get("usbl")
    if usbl is not None and len(usbl["t_valid"].values):
        tv = usbl["t_valid"].values
        keep = tv <= t[-1] + 1e-9
        z = np.column_stack([usbl[c].values for c in ("range", "azimuth", "elevation")])[keep]
        ln = scn.leader.navigation
        sig = (
            ln.sigma_range_m,
            math.radians(ln.sigma_azimuth_deg),
            math.radians(ln.sigma_elevation_deg),
        )
        fix_tick = np.minimum(np.searchsorted(t, tv[keep] - 1e-9), k - 1)
        fix_m = usbl["position"].values[keep, :2]
        fix_cov = UsblMeasurement(np.zeros(3), *sig, min_horizontal_m=0.0).fix_covariance(z)
        fix_cov = fix_cov[:, :2, :2]
    else:
        fix_tick, fix_m, fix_cov = np.zeros(0, np.intp), np.zeros((0, 2)), np.zeros((0, 2, 2))
    cols: dict[str, list[Any]] = {c: [] for c in ("s", "r", "tx", "rx", "range", "T", "L")}
    for i, v in enumerate(runs):
        tab = v.fixes.get(NETWORK)
        if tab is None:
            continue
        T, L = tab["tx_local"].values, tab["rx_local"].values
        # a tick within a nanosecond of a stamp counts as at it (the grid's rounding)
        tx = np.maximum(np.searchsorted(t, T + 1e-9, side="right") - 1, 0)
        rx = np.searchsorted(t, L - 1e-9, side="left")
        ok = (rx < k) & (rx >= tx)
        cols["s"] += list(tab["sender"].values[ok])
        cols["r"] += [i] * int(ok.sum())
        cols["tx"] += list(tx[ok])
        cols["rx"] += list(rx[ok])
        cols["range"] += list(tab["range"].values[ok])
        cols["T"] += list(T[ok])
        cols["L"] += list(L[ok])
    m = len(cols["s"])
    f = len(fix_tick)
    return TeamRecord(
        t_s=t,
        dr_step_m=np.stack(steps)[None],
        dr_step_cov_m2=np.stack(covs)[None],
        depth_m=np.stack([v["meas_depth"][:k] for v in runs])[None],
        start_m=np.stack([v["ekf_pos"][0, :2] for v in runs])[None],
        start_cov_m2=np.stack([v["ekf_P"][0, :2, :2] for v in runs])[None],
        fix_tick=np.asarray(fix_tick, dtype=np.intp),
        fix_vehicle=np.zeros(f, dtype=np.intp),
        fix_m=fix_m[None],
        fix_cov_m2=fix_cov[None],
        fix_present=np.ones((1, f), dtype=bool),
        range_sender=np.asarray(cols["s"], dtype=np.intp),
        range_receiver=np.asarray(cols["r"], dtype=np.intp),
        range_tx_tick=np.asarray(cols["tx"], dtype=np.intp),
        range_rx_tick=np.asarray(cols["rx"], dtype=np.intp),
        range_m=np.asarray(cols["range"], dtype=float).reshape(1, m),
        range_tx_local_s=np.asarray(cols["T"], dtype=float).reshape(1, m),
        range_rx_local_s=np.asarray(cols["L"], dtype=float).reshape(1, m),
        range_present=np.ones((1, m), dtype=bool),
        kind="owtt",
        sound_speed_m_s=scn.followers.network.nominal_sound_speed_m_s,
        sigma_range_m=nav.sigma_range_m,
    )


def true_clock_offsets(scn: SwarmScenario, seed: int, run: int, t_s: Array) -> Array:
    """Each vehicle's true clock offset on the grid (the network's clocks, drawn as its devices
    draw them), shape (1, v, k), s."""
    net = scn.followers.network
    team = (LEADER, *FOLLOWERS[: scn.followers.count])
    rows = [draw_clocks(net.clock_of(v), seed, (run,), v).offset(t_s[None])[0] for v in team]
    return np.stack(rows)[None]


def track_column(method: str) -> str:
    """The per-tick column of a team method's position estimate (``team_<method>_pos``, the
    method's ``-`` as ``_``); its covariance is ``team_<method>_P``."""
    return f"team_{method.replace('-', '_')}_pos"


def add_track_columns(v: VehicleRun, method: str, tracks, i: int) -> None:
    """Add vehicle ``i``'s estimate of a team method to its per-tick columns (the run data):
    ``team_<method>_pos`` (east, north, m) and ``team_<method>_P`` (2 x 2, m^2, symmetrised:
    ``(P + P^T) / 2``), null on the ticks after the team's common samples; and declare it as
    one of the vehicle's estimates (``team <method>``, :attr:`VehicleRun.estimates`)."""
    n = len(v["t"])
    k = tracks.position_m.shape[2]
    pos = np.full((n, 2), np.nan)
    cov = np.full((n, 2, 2), np.nan)
    pos[:k] = tracks.position_m[0, i]
    c = tracks.cov_m2[0, i]
    cov[:k] = 0.5 * (c + np.swapaxes(c, 1, 2))
    col = track_column(method)
    what = f"{method} team estimate (acoustic network, tasks.missions.swarm.team)"
    v.ticks[col] = Column(pos, "m", f"{what}, world", ("east", "north"), k < n)
    v.ticks[col[: -len("pos")] + "P"] = Column(
        cov, "m^2", f"{what}: its stated covariance", ("east", "north"), k < n
    )
    # declared for the recording beside the vehicle's own estimates
    v.estimates = (*v.estimates, EstimateTrack(col, f"team {method}", col[: -len("pos")] + "P"))


def team_comparison(scn: SwarmScenario, flight: MissionRun) -> dict[str, dict[str, Any]]:
    """Every method of :data:`TEAM_METHODS` on the flight's record (:func:`team_record`),
    against the truth (:func:`nav.cooperative.team_metrics`, from the second sample); each
    method's estimates are added to the vehicles' per-tick columns (:func:`add_track_columns`).

    Returns:
        Per method, per vehicle: ``mean_error_m``, ``final_error_m``, ``max_error_m``
        (horizontal), ``nees`` (mean over the samples, 2 dof; absent without a covariance),
        ``nees_low`` and ``nees_high`` (the two-sided 95 % band of one run), ``consistent``
        (1 when the NEES is at or below the band's upper end), ``clock_rmse_ms`` (methods with
        clocks, against the network's true clocks) and ``ranges_used``.
    """
    record = team_record(scn, flight)
    team = (LEADER, *FOLLOWERS[: scn.followers.count])
    k = record.n_samples
    truth = np.stack([flight.vehicles[n]["truth_pos"][:k, :2] for n in team])[None]
    offsets = true_clock_offsets(scn, flight.seed, flight.run, record.t_s)
    options = coop_options(scn)
    out: dict[str, dict[str, Any]] = {}
    for method in TEAM_METHODS:
        tracks = team_tracks(record, method, options)
        for i, name in enumerate(team):
            add_track_columns(flight.vehicles[name], method, tracks, i)
        rows = {}
        for name, m in zip(team, team_metrics(tracks, truth, offsets), strict=True):
            row = {
                "mean_error_m": m.mean_error_m,
                "final_error_m": m.final_error_m,
                "max_error_m": m.max_error_m,
                "nees_low": m.nees_band[0],
                "nees_high": m.nees_band[1],
                "ranges_used": float(tracks.ranges_used[0, team.index(name)]),
            }
            if m.nees is not None:
                row["nees"] = m.nees
                row["consistent"] = float(bool(m.consistent))
            if m.clock_rmse_s is not None:
                row["clock_rmse_ms"] = 1e3 * m.clock_rmse_s
            rows[name] = row
        out[method] = rows
    return out
