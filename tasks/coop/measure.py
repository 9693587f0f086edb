"""Every vehicle's own measurements for a block of runs: dead-reckoning steps from compass and log
with their covariance, depths from the pressure sensor, the starts (the leader's GPS fix, the
followers' known launch), and the leader's USBL fixes turned into horizontal positions.

Streams (:mod:`bauv_sim.rng`) are addressed by vehicle name and device, ``(seed, run, "sensor",
f"{name}/compass", ...)``, so run ``i`` draws the same numbers in any block and whatever the other
vehicles, and a sensitivity setting that changes only the acoustics keeps every one of these.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bauv_sim.errors import ConfigError
from bauv_sim.kinematic.team import TeamTruth
from bauv_sim.sensors import Compass, ErrorProcess, LengthErrorConfig, Log, Pressure, Usbl
from bauv_sim.sensors.base import periodic_indices
from nav.acoustics import Propagation
from nav.models import UsblMeasurement
from nav.relative.motion import dr_increment, dr_increment_covariance
from tasks.coop.scenario import CoopScenario

Array = NDArray[np.float64]


@dataclass(frozen=True)
class OwnMeasurements:
    """What every vehicle measures of itself (v vehicles, the leader first; n runs; k samples;
    f USBL fixes).

    Attributes:
        dr_step_m: DR displacement over ground between samples, (n, v, k - 1, 2), m east/north.
        dr_step_cov_m2: its covariance as the filters are told, (n, v, k - 1, 2, 2), m^2.
        depth_m: measured depth, (n, v, k), m.
        start_m: the believed start, (n, v, 2), m.
        start_cov_m2: its covariance, (n, v, 2, 2), m^2.
        fix_tick: sample index of each USBL fix, (f,).
        fix_m: the leader's fix, (n, f, 2), m.
        fix_cov_m2: its covariance, (n, f, 2, 2), m^2.
        fix_present: whether the fix exists, (n, f).
    """

    dr_step_m: Array
    dr_step_cov_m2: Array
    depth_m: Array
    start_m: Array
    start_cov_m2: Array
    fix_tick: NDArray[np.intp]
    fix_m: Array
    fix_cov_m2: Array
    fix_present: NDArray[np.bool_]


def _hold_last(values: Array, produced: NDArray[np.bool_], what: str) -> Array:
    """Absent samples take the last produced one (before the first: the first produced)."""
    if produced.all():
        return values
    if not produced.any(axis=1).all():
        raise ConfigError(f"{what}: a run produced no sample at all (dropout probability?)")
    idx = np.where(produced, np.arange(values.shape[1]), -1)
    idx = np.maximum.accumulate(idx, axis=1)
    idx = np.where(idx < 0, produced.argmax(axis=1)[:, None], idx)
    return np.take_along_axis(values, idx, axis=1)


def unmodelled_q_m2(sigma_m_s: float, correlation_s: float, dt_s: float) -> float:
    """Per-axis position variance added per step for a velocity error the devices' white noise
    does not hold: ``2 sigma^2 tau dt`` (the long-time growth of the position error of a
    first-order Gauss-Markov velocity error of variance ``sigma^2`` and time constant ``tau``),
    m^2."""
    return 2.0 * sigma_m_s**2 * correlation_s * dt_s


def own_measurements(
    scn: CoopScenario, truth: TeamTruth, seed: int, runs: tuple[int, ...]
) -> OwnMeasurements:
    """Sample every vehicle's compass, log and pressure sensor, the leader's GPS start and USBL
    fixes (through the scenario's ``sound``), and the followers' starts, for some runs (module
    docstring).

    Returns:
        The measurements, as the filters receive them.
    """
    s = scn.sensors
    n, v, k = len(runs), len(truth.names), len(truth.t_s)
    dt = scn.team.tick_s
    steps = np.arange(k - 1)
    sig_h = s.compass.heading.to_model().noise_std
    sig_s = s.log.speed.to_model().noise_std
    q = unmodelled_q_m2(scn.filters.unmodelled_speed_m_s, scn.filters.correlation_s, dt)
    dr = np.empty((n, v, k - 1, 2))
    dr_cov = np.empty((n, v, k - 1, 2, 2))
    depth = np.empty((n, v, k))
    start = np.empty((n, v, 2))
    start_cov = np.empty((n, v, 2, 2))
    for i, (name, tr) in enumerate(zip(truth.names, truth.vehicles, strict=True)):
        head = Compass(s.compass, seed, runs, f"{name}/compass").sample(tr, steps)
        speed = Log(s.log, seed, runs, f"{name}/log").sample(tr, steps)
        h = _hold_last(head.values, head.produced, "sensors.compass")
        sp = _hold_last(speed.values, speed.produced, "sensors.log")
        dr[:, i] = dr_increment(h.ravel(), sp.ravel(), dt).reshape(n, k - 1, 2)
        cov = dr_increment_covariance(h.ravel(), sp.ravel(), dt, sig_h, sig_s)
        dr_cov[:, i] = cov.reshape(n, k - 1, 2, 2) + q * np.eye(2)
        dep = Pressure(s.pressure, seed, runs, f"{name}/pressure").sample(tr, np.arange(k))
        depth[:, i] = _hold_last(dep.values, dep.produced, "sensors.pressure")
        if i == 0:
            sigma = s.gps.position.to_model().noise_std
            err = s.gps.position
            what = f"{name}/gps"
        else:
            sigma = s.follower_start_sigma_m
            err = LengthErrorConfig(sigma_m=sigma)
            what = f"{name}/start"
        for axis in range(2):
            proc = ErrorProcess(err.to_model(), seed, runs, ("sensor", what, "en"[axis]))
            true0 = np.broadcast_to(tr.pos_world_m[:, 0, axis], (n, 1))
            start[:, i, axis] = proc.apply(np.ascontiguousarray(true0), tr.t_s[:1])[0][:, 0]
        start_cov[:, i] = sigma**2 * np.eye(2)
    fix_tick, fix, fix_cov, present = usbl_fixes(scn, truth, seed, runs, scn.sound.propagation())
    return OwnMeasurements(
        dr_step_m=dr,
        dr_step_cov_m2=dr_cov,
        depth_m=depth,
        start_m=start,
        start_cov_m2=start_cov,
        fix_tick=fix_tick,
        fix_m=fix,
        fix_cov_m2=fix_cov,
        fix_present=present,
    )


def usbl_fixes(
    scn: CoopScenario,
    truth: TeamTruth,
    seed: int,
    runs: tuple[int, ...],
    propagation: Propagation | None,
) -> tuple[NDArray[np.intp], Array, Array, NDArray[np.bool_]]:
    """The leader's USBL fixes through the sea's true medium (:class:`bauv_sim.sensors.Usbl`:
    with a medium, the range is the nominal speed times the travel time and the elevation the
    bent ray's arrival), turned into horizontal positions along the straight line at the
    nominal speed with the first-order covariance of the device's stated noise
    (:meth:`nav.models.UsblMeasurement.invert`, :meth:`~nav.models.UsblMeasurement.
    fix_covariance`): what a USBL that assumes its nominal speed reports.

    Returns:
        ``fix_tick (f,)``, ``fix_m (n, f, 2)`` m, ``fix_cov_m2 (n, f, 2, 2)`` m^2, ``present
        (n, f)``.
    """
    s = scn.sensors
    u = s.usbl
    every = round(u.period_s / scn.team.tick_s)
    fix_tick = periodic_indices(len(truth.t_s), every)
    transceiver = np.asarray(s.usbl_transceiver_m, float)
    usbl = Usbl(u, transceiver, seed, runs, f"{truth.names[0]}/usbl", propagation=propagation)
    sam = usbl.sample(truth.vehicles[0], fix_tick)
    model = UsblMeasurement(
        transceiver,
        u.range.to_model().noise_std,
        u.azimuth.to_model().noise_std,
        u.elevation.to_model().noise_std,
    )
    fix = model.invert(sam.values)[..., :2]
    fix_cov = model.fix_covariance(sam.values)[..., :2, :2]
    if not np.isfinite(fix).all():
        raise ConfigError("sensors.usbl: a fix is not finite (the leader in a shadow zone?)")
    return fix_tick, fix, fix_cov, sam.produced
