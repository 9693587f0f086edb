"""A block of ``trn/relief`` runs: kinematic truth, DVL, dead reckoning, TRN and the PCRB.

Per run ``i`` (its own streams, :mod:`bauv_sim.rng`, so a run's numbers do not depend on its
block or worker):

1. the truth (:func:`lawnmower_truth`): a lawn-mower from a random start and first heading at
   constant speed and depth, sampled at the DVL's period;
2. per relief of the sweep, the true seabed (:func:`bauv_sim.seabed.generate`, the run's own
   wave directions and phases at every relief), the DVL's pings against its triangles
   (:meth:`bauv_sim.sensors.dvl.Dvl.sample`) and the heading
   (:class:`bauv_sim.sensors.Compass`); dead reckoning on the DVL from the estimated start
   (:func:`nav.dvl.velocity_world_from_dvl`, :func:`nav.dvl.dvl_increments`,
   :func:`nav.dead_reckoning.track`); the PCRB (:func:`nav.trn.trn_pcrb`) from the true track
   and the TRUE seabed's gradients at the beams' footprints;
3. per map error of the sweep, the navigator's map (:func:`nav.trn.degraded` of the true grid)
   and the two filters, :class:`nav.trn.ParticleTrn` and :class:`nav.trn.PointMassTrn`, fed the
   DR displacement between updates and the soundings of one ping every
   ``filters.update_every`` (every beam with an echo, with or without bottom lock: a range
   stands alone; a ping with no echo gives a prediction only).

The block keeps per setting the sums over its runs of each method's squared error and of the
PCRB's trace at every update (the curves against time), and per run and setting the final,
mean and RMS error of each method and the filters' counters (the statistics over runs).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bauv_sim.errors import ConfigError
from bauv_sim.rng import generator
from bauv_sim.seabed import Seabed, generate
from bauv_sim.sensors import Compass
from bauv_sim.sensors.dvl import Dvl, DvlSamples
from bauv_sim.truth import Truth
from nav import dead_reckoning
from nav.dvl import dvl_increment_covariance, dvl_increments, velocity_world_from_dvl
from nav.errors import NavInputError
from nav.trn import (
    ParticleTrn,
    PointMassTrn,
    TerrainMap,
    TrnOptions,
    degraded,
    soundings,
    trn_pcrb,
)
from tasks.trn.scenario import FiltersConfig, TrackConfig, TrnReliefScenario

Array = NDArray[np.float64]

METHODS = ("DR-DVL", "TRN-PF", "TRN-PMF")
"""The estimates compared, in the order of the block's arrays."""


def trn_options(f: FiltersConfig) -> TrnOptions:
    """The filters' options from the scenario (:class:`nav.trn.TrnOptions`; its other fields
    keep their defaults).

    Raises:
        ConfigError: naming the scenario field, when ``nav.trn`` refuses the value.
    """
    try:
        return TrnOptions(
            particles=f.particles,
            grid_points=f.grid_points,
            sigma_bias_m=f.sigma_bias_m,
        )
    except NavInputError as exc:
        raise ConfigError(f"filters: {exc}") from None


def lawnmower_truth(track: TrackConfig, dt_s: float, seed: int, run: int) -> Truth:
    """The kinematic truth of one run: a lawn-mower at constant speed and depth.

    Legs of ``track.leg_m`` along the first heading and back, joined by moves of
    ``track.spacing_m`` at 90 deg (headings ``h, h + 90, h + 180, h + 90, h, ...``), from a start
    uniform in ``+-track.start_box_m`` around the origin with ``h`` uniform in [0, 360) deg
    (stream ``(seed, run, "trn", "track")``). Sample ``k`` flies the heading of the leg it is on;
    between samples the velocity changes linearly (a turn takes one sample period), so the
    positions are the trapezoid rule's (:func:`nav.dead_reckoning.track` of the steps), the rule
    of :func:`nav.dvl.dvl_increments`: noise-free dead reckoning is exact.

    Args:
        track: the lawn-mower.
        dt_s: sample period, s (the DVL's).
        seed: batch seed.
        run: run index.

    Returns:
        The truth, one run, ``K + 1`` samples with ``K = floor(duration / dt)``; no current,
        level attitude.
    """
    g = generator(seed, run, "trn", "track")
    start_en = g.uniform(-track.start_box_m, track.start_box_m, 2)
    h0 = g.uniform(0.0, 2.0 * np.pi)
    k = math.floor(track.duration_s / dt_s + 1e-9)
    t = dt_s * np.arange(k + 1)
    leg, gap = track.leg_m, track.spacing_m
    u = np.mod(track.speed_m_s * t, 2.0 * (leg + gap))
    turn = np.select([u < leg, u < leg + gap, u < 2 * leg + gap], [0.0, 0.5, 1.0], 0.5)
    heading = np.mod(h0 + np.pi * turn, 2.0 * np.pi)
    v = track.speed_m_s * np.column_stack([np.sin(heading), np.cos(heading), np.zeros(k + 1)])
    x0 = np.array([[start_en[0], start_en[1], -track.depth_m]])
    pos = dead_reckoning.track(x0, (0.5 * dt_s * (v[:-1] + v[1:]))[None])
    return Truth(
        t_s=t,
        pos_world_m=pos,
        vel_ground_world_m_s=v[None],
        vel_water_world_m_s=v[None],
        heading_rad=heading[None],
        roll_pitch_rad=np.zeros((1, k + 1, 2)),
        current_world_m_s=np.zeros((1, k + 1, 3)),
    )


def true_map(seabed: Seabed) -> TerrainMap:
    """The true seabed as a :class:`nav.trn.TerrainMap` (its grid points, bilinear between)."""
    c = seabed.config
    ax = np.linspace(-c.half_extent_m, c.half_extent_m, c.n)
    return TerrainMap(ax, ax, seabed.depth_m)


def horizontal_velocity_sigma(sigma_beam_m_s: float, beam_angle_deg: float) -> float:
    """Standard deviation of each horizontal component of a Janus DVL's velocity, m/s.

    With four beams at ``a`` off the vertical, least squares gives ``(A^T A)^-1 = diag(1 /
    (2 sin^2 a), 1 / (2 sin^2 a), 1 / (4 cos^2 a))`` in the instrument frame (any mounting yaw
    keeps the horizontal part isotropic), so each horizontal component has ``sigma / (sqrt(2)
    sin a)``.
    """
    return sigma_beam_m_s / (math.sqrt(2.0) * math.sin(math.radians(beam_angle_deg)))


def increment_covariance(
    velocity_en_m_s: Array, dt_s: float, sigma_v_m_s: float, sigma_heading_rad: float, every: int
) -> Array:
    """Covariance of the DR displacement between two TRN updates, m^2: the sum of ``every``
    pings' :func:`nav.dvl.dvl_increment_covariance` (white velocity and heading errors; the pings
    are independent).

    Args:
        velocity_en_m_s: (east, north) velocity of every ping, shape (K + 1, 2), m/s.
        dt_s: ping period, s.
        sigma_v_m_s: each horizontal velocity component's noise, m/s.
        sigma_heading_rad: heading noise per ping, rad.
        every: pings per update.

    Returns:
        Shape (J, 2, 2) for the ``J = K // every`` updates.
    """
    n = (len(velocity_en_m_s) - 1) // every
    v = velocity_en_m_s[: n * every].reshape(n, every, 2)
    return dvl_increment_covariance(v, dt_s, sigma_v_m_s, sigma_heading_rad).sum(axis=1)


def _filter_errors(
    filt: ParticleTrn | PointMassTrn,
    nav_map: TerrainMap,
    pings: list,
    disp: Array,
    q: Array,
    sigma_m: float,
    truth_en: Array,
) -> tuple[Array, int, int]:
    """Run one filter over the updates; its horizontal error at each (``J + 1``, the start
    first), its re-initialisations and its updates flagged diverged."""
    err = np.zeros(len(pings) + 1)
    mean, _ = filt.estimate()
    err[0] = float(np.hypot(*(mean - truth_en[0])))
    diverged = 0
    for j, snd in enumerate(pings):
        filt.predict(disp[j], q[j])
        up = filt.update(nav_map, snd, sigma_m)
        diverged += bool(up.diverged)
        mean, _ = filt.estimate()
        err[j + 1] = float(np.hypot(*(mean - truth_en[j + 1])))
    return err, int(filt.reinitialisations), diverged


def run_one(scenario: TrnReliefScenario, seed: int, run: int) -> dict[str, Array]:
    """Every setting of one run (module docstring).

    Returns:
        ``errors`` (S, 3, J + 1) m, horizontal error of DR-DVL, PF, PMF at the start and each
        update; ``pcrb`` (S, 2, J + 1) m^2, trace of the PCRB without and with the filters'
        per-ping bias marginalised; ``reinit`` and ``diverged`` (S, 2)
        for PF and PMF; ``no_lock`` (S,) pings without bottom lock; ``no_update`` (S,) updates
        with no sounding.
    """
    scn = scenario
    dcfg, f = scn.sensors.dvl, scn.filters
    dt = dcfg.period_s
    truth = lawnmower_truth(scn.track, dt, seed, run)
    n_ping = len(truth.t_s)
    every = f.update_every
    upd = every * np.arange(1, (n_ping - 1) // every + 1)
    at = np.concatenate([[0], upd])
    truth_en = truth.pos_world_m[0, at, :2]
    g = generator(seed, run, "trn", "initial")
    x0_est = truth.pos_world_m[0, 0] + np.array([*(f.initial_sigma_m * g.standard_normal(2)), 0.0])
    p0 = f.initial_sigma_m**2 * np.eye(2)
    heading = Compass(scn.sensors.compass, seed, (run,)).sample(truth, np.arange(n_ping))
    psi = heading.values[0]
    rph = np.column_stack([np.zeros((n_ping, 2)), psi])
    lever = np.asarray(dcfg.transducer_body_m, float)
    # the white noise of the devices (gaussian or uniform), what the filters and the PCRB model
    sig_v = horizontal_velocity_sigma(dcfg.beam.to_model().noise_std, dcfg.beam_angle_deg)
    sig_psi = scn.sensors.compass.heading.to_model().noise_std
    sig_range = dcfg.range.to_model().noise_std * math.cos(math.radians(dcfg.beam_angle_deg))
    true_q = increment_covariance(truth.vel_ground_world_m_s[0, :, :2], dt, sig_v, sig_psi, every)
    settings = scn.settings()
    options = trn_options(f)
    n_set, n_upd = len(settings), len(upd)
    out = {
        "errors": np.zeros((n_set, len(METHODS), n_upd + 1)),
        "pcrb": np.zeros((n_set, 2, n_upd + 1)),
        "reinit": np.zeros((n_set, 2), np.int64),
        "diverged": np.zeros((n_set, 2), np.int64),
        "no_lock": np.zeros(n_set, np.int64),
        "no_update": np.zeros(n_set, np.int64),
    }
    seabed_seed = int(generator(seed, run, "trn", "terrain").integers(0, 2**31 - 1))
    for relief in scn.sweep.relief_std_m:
        seabed = generate(scn.terrain.seabed(relief, seabed_seed))
        sam: DvlSamples = Dvl(dcfg, seed, (run,)).sample(truth, np.arange(n_ping), seabed)
        mode = sam.mode[0]
        vel = velocity_world_from_dvl(sam.velocity_body_m_s[0], rph, None, lever)
        inc = dvl_increments(vel[None], truth.t_s, (mode > 0)[None])
        dr = dead_reckoning.track(x0_est[None], inc[:, 1:])[0]
        dr_en = dr[at, :2]
        disp = np.diff(dr_en, axis=0)
        q = increment_covariance(vel[:, :2], dt, sig_v, sig_psi, every)
        depth = truth.depth_m[0]
        pings = [
            soundings(
                sam.beam_ranges_m[0, k],
                sam.beam_echo[0, k],
                sam.beam_directions_body,
                rph[k],
                lever,
                float(depth[k]),
            )
            for k in upd
        ]
        truth_snd = [
            soundings(
                sam.beam_ranges_m[0, k],
                sam.beam_echo[0, k],
                sam.beam_directions_body,
                np.array([0.0, 0.0, truth.heading_rad[0, k]]),
                lever,
                float(depth[k]),
            )
            for k in upd
        ]
        tmap = true_map(seabed)
        foot = truth_en[1:, None, :] + np.stack([s.offset_m for s in truth_snd])
        grad, on_map = tmap.gradient(foot[..., 0], foot[..., 1])
        active = np.stack([s.valid for s in truth_snd]) & on_map
        grad = np.where(active[..., None], grad, 0.0)
        for map_sigma in scn.sweep.map_sigma_m:
            s = settings.index((relief, map_sigma))
            sigma_pcrb = np.full(active.shape, math.hypot(sig_range, map_sigma))
            out["pcrb"][s, :, 0] = np.trace(p0)
            for b, bias in enumerate((0.0, f.sigma_bias_m)):
                bound = trn_pcrb(
                    np.eye(2) / f.initial_sigma_m**2,  # J0 = P0^-1
                    true_q,
                    grad,
                    sigma_pcrb,
                    active,
                    sigma_bias_m=bias,
                )
                out["pcrb"][s, b, 1:] = np.trace(bound, axis1=1, axis2=2)
            out["errors"][s, 0] = np.hypot(*(dr_en - truth_en).T)
            out["no_lock"][s] = int(np.count_nonzero(mode != 1))
            out["no_update"][s] = sum(snd.count == 0 for snd in pings)
            nav_map = degraded(
                tmap,
                scn.map.cell_m,
                map_sigma,
                scn.map.offset_m,
                generator(seed, run, "trn", "map"),
            )
            # the filters add the map's own sigma (map_sigma) in quadrature; the measurement
            # sigma holds the range error, the model floor and what the map's bilinear
            # interpolation misses, estimated from its second differences
            sigma = math.hypot(sig_range, f.map_model_sigma_m, nav_map.interpolation_sigma_m())
            for m, cls in enumerate((ParticleTrn, PointMassTrn)):
                stream = generator(seed, run, "trn", METHODS[m + 1])
                filt = cls(options, x0_est[:2], p0, stream)
                err, reinit, div = _filter_errors(filt, nav_map, pings, disp, q, sigma, truth_en)
                out["errors"][s, m + 1] = err
                out["reinit"][s, m] = reinit
                out["diverged"][s, m] = div
    return out


def run_block(scenario: TrnReliefScenario, seed: int, runs: tuple[int, ...]) -> dict[str, Array]:
    """A block of runs reduced (module docstring).

    Returns:
        ``runs`` (n,); per setting and update, summed over the block's runs: ``sq_err_sum`` (S,
        3, J + 1) m^2 over the finite errors, ``count`` (S, 3, J + 1) of them, ``pcrb_sum`` (S,
        2, J + 1) m^2; per run: ``final_m``, ``mean_m``, ``rms_m``
        (n, S, 3) m (mean and RMS over the updates 1..J), ``reinit``, ``diverged`` (n, S, 2),
        ``no_lock``, ``no_update`` (n, S).
    """
    per = [run_one(scenario, seed, r) for r in runs]
    err = np.stack([p["errors"] for p in per])  # (n, S, 3, J + 1)
    finite = np.isfinite(err)
    return {
        "runs": np.asarray(runs, np.int64),
        "sq_err_sum": np.where(finite, err, 0.0).__pow__(2).sum(axis=0),
        "count": finite.sum(axis=0).astype(np.int64),
        "pcrb_sum": np.stack([p["pcrb"] for p in per]).sum(axis=0),
        "final_m": err[..., -1],
        "mean_m": err[..., 1:].mean(axis=-1),
        "rms_m": np.sqrt((err[..., 1:] ** 2).mean(axis=-1)),
        "reinit": np.stack([p["reinit"] for p in per]),
        "diverged": np.stack([p["diverged"] for p in per]),
        "no_lock": np.stack([p["no_lock"] for p in per]),
        "no_update": np.stack([p["no_update"] for p in per]),
    }


def runs(n: int, noun: str = "run") -> str:
    """``"1 run"``, ``"8 runs"`` (or another noun)."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def update_times(scenario: TrnReliefScenario) -> Array:
    """Times of the start and of every TRN update, s (J + 1,)."""
    dt = scenario.sensors.dvl.period_s
    n_ping = math.floor(scenario.track.duration_s / dt + 1e-9) + 1
    every = scenario.filters.update_every
    return dt * every * np.arange((n_ping - 1) // every + 1)


def check_filters(f: FiltersConfig) -> None:
    """Build the filters' options once (their own validation), so that bad options are refused
    before a batch starts."""
    trn_options(f)
