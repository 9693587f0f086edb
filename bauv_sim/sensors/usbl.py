"""USBL: slant range, azimuth and elevation of the vehicle's transponder seen from a transceiver.

Seed 000 (Tritech MicronNav): sigma_r = 0.2 m, sigma_alpha = sigma_beta = 3 deg, range limit 500 m.
The geometry is seed 000 eq. 15 with world z up (:func:`bauv_sim.frames.range_azimuth_elevation`):
azimuth clockwise from north, elevation positive when the vehicle is above the transceiver.

The measured elevation stays in [-90, 90] deg: an elevation error that carries it past the zenith
(right above the transceiver) gives the direction over the top, 180 deg around in azimuth
(:func:`bauv_sim.frames.fold_azimuth_elevation`), never a clipped 90 deg.

Besides the per-component errors (:mod:`bauv_sim.sensors.errors`), a fix is not produced beyond
``max_range_m``, outside the transceiver's field of view (``min_elevation_deg``), or with
``dropout_probability``; it reaches the vehicle after the acoustic travel time plus a processing
delay (the fix is valid for the moment of the reply).

**The sea's medium.** Given the true medium (``propagation``, a :class:`nav.acoustics.Propagation`
such as a layered sound-speed profile), the fix is what a USBL measures in it: the slant range is
the nominal speed (``sound_speed_m_s``) times the one-way travel time of the reply along the
eigenray, the elevation is the direction the reply arrives from at the transceiver's array (the
bent ray's tangent), the azimuth is the straight line's (a stratified sea bends rays only in the
vertical plane); the field of view is judged on the arrival elevation; the fix reaches the
vehicle after the true travel time. No fix where no direct ray reaches the transceiver (a shadow
zone of the profile). Without a medium (``None``, the default) the sound travels straight at
``sound_speed_m_s``: the numbers are those before sound-speed profiles, bit for bit.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from bauv_sim import rng as rng_mod
from bauv_sim.config import Config
from bauv_sim.frames import fold_azimuth_elevation, range_azimuth_elevation
from bauv_sim.sensors.base import SensorSamples, broadcast_runs, point_world
from bauv_sim.sensors.errors import AngleErrorConfig, ErrorProcess, LengthErrorConfig
from bauv_sim.sensors.online import DeviceBuild, Measurement, TickContext, register_device
from bauv_sim.truth import Truth
from nav.acoustics import Propagation


class UsblConfig(Config):
    """USBL positioning (defaults: Tritech MicronNav as in seed 000)."""

    period_s: float = Field(5.0, gt=0, description="time between fixes, s (seed 000: 5, 20, 100)")
    range: LengthErrorConfig = Field(
        default_factory=lambda: LengthErrorConfig(sigma_m=0.2), description="slant-range error"
    )
    azimuth: AngleErrorConfig = Field(
        default_factory=lambda: AngleErrorConfig(sigma_deg=3.0), description="azimuth error"
    )
    elevation: AngleErrorConfig = Field(
        default_factory=lambda: AngleErrorConfig(sigma_deg=3.0), description="elevation error"
    )
    max_range_m: float = Field(500.0, gt=0, description="no fix beyond this slant range, m")
    min_elevation_deg: float = Field(
        -90.0, ge=-90, le=90, description="no fix below this elevation (field of view), deg"
    )
    dropout_probability: float = Field(0.0, ge=0, lt=1, description="probability a fix is lost")
    sound_speed_m_s: float = Field(
        1500.0,
        gt=0,
        description="for the travel-time latency, m/s (online rigs; seed 000's passage has no "
        "latency and refuses a change)",
    )
    processing_delay_s: float = Field(
        0.0,
        ge=0,
        description="added latency, s (online rigs; seed 000's passage has no latency and "
        "refuses a change)",
    )
    transponder_body_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="transponder relative to the vehicle reference point, m, body"
    )


class Usbl:
    """USBL fixes of a batch of runs.

    Args:
        cfg: configuration.
        transceiver_world_m: transceiver position, shape (3,), m, world frame.
        seed: batch seed.
        runs: run indices of the rows.
        name: stream name of this device.
        propagation: the sea's true medium, or ``None`` (straight rays at ``sound_speed_m_s``;
            module docstring).
    """

    def __init__(
        self,
        cfg: UsblConfig,
        transceiver_world_m: NDArray[np.float64],
        seed: int,
        runs: tuple[int, ...],
        name: str = "usbl",
        propagation: Propagation | None = None,
    ):
        self.cfg = cfg
        self.propagation = propagation
        self.transceiver_world_m = np.asarray(transceiver_world_m, dtype=float)
        self.n = len(runs)
        base = ("sensor", name)
        self._errs = [
            ErrorProcess(cfg.range.to_model(), seed, runs, (*base, "range")),
            ErrorProcess(cfg.azimuth.to_model(), seed, runs, (*base, "azimuth")),
            ErrorProcess(cfg.elevation.to_model(), seed, runs, (*base, "elevation")),
        ]
        self._drop = (
            rng_mod.RunStreams(seed, runs, *base, "fix_dropout")
            if cfg.dropout_probability > 0
            else None
        )

    def sample(self, truth: Truth, index: NDArray[np.intp]) -> SensorSamples:
        """Fix at the given tick indices.

        Returns:
            Samples with values ``(r, alpha, beta)``, shape (n, k, 3): m, rad in [0, 2 pi),
            rad in [-pi/2, pi/2]; ``t_arrival_s`` includes the travel time r / c and the
            processing delay.
        """
        tr = truth.take(index)
        pos = broadcast_runs(point_world(tr, self.cfg.transponder_body_m), self.n)
        true_rae = range_azimuth_elevation(pos - self.transceiver_world_m)
        if self.propagation is not None:
            return self._sample_in_medium(tr.t_s, pos, true_rae)
        meas, produced = self._measure(tr.t_s, true_rae, np.ones(true_rae.shape[:2], dtype=bool))
        produced &= true_rae[..., 0] <= self.cfg.max_range_m
        produced &= true_rae[..., 2] >= np.radians(self.cfg.min_elevation_deg)
        t_arr = tr.t_s + true_rae[..., 0] / self.cfg.sound_speed_m_s + self.cfg.processing_delay_s
        return SensorSamples(tr.t_s, meas, produced, t_arr)

    def measure(
        self, t_s: NDArray[np.float64], transponder_world_m: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.float64]]:
        """Fixes of given transponder positions through straight rays (what :meth:`sample`
        gives without a medium, from positions instead of a truth record): the online form for
        a batch of vehicles that are not in a :class:`~bauv_sim.truth.Truth`.

        Args:
            t_s: times of the replies, shape (k,), s.
            transponder_world_m: the transponders, shape (n, k, 3), m, world.

        Returns:
            ``(values (n, k, 3): r m, alpha rad in [0, 2 pi), beta rad; produced (n, k);
            t_arrival_s (n, k))``, as :meth:`sample`.
        """
        if self.propagation is not None:
            raise ValueError("Usbl.measure: straight rays only (no propagation medium)")
        true_rae = range_azimuth_elevation(transponder_world_m - self.transceiver_world_m)
        meas, produced = self._measure(t_s, true_rae, np.ones(true_rae.shape[:2], dtype=bool))
        produced &= true_rae[..., 0] <= self.cfg.max_range_m
        produced &= true_rae[..., 2] >= np.radians(self.cfg.min_elevation_deg)
        t_arr = t_s + true_rae[..., 0] / self.cfg.sound_speed_m_s + self.cfg.processing_delay_s
        return meas, produced, t_arr

    def _measure(
        self, t_s: NDArray[np.float64], rae: NDArray[np.float64], produced: NDArray[np.bool_]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """The device's errors on ``(range, azimuth, elevation)`` (shape (n, k, 3)) and its
        dropouts: ``(measured (n, k, 3), produced (n, k))``, ``produced`` narrowed by the error
        processes and the dropout. An elevation error past the zenith is the direction over the
        top (not a clip)."""
        comps = []
        for j, err in enumerate(self._errs):
            ref = rae[..., 1] if err.model.needs_reference() else None
            v, ok = err.apply(rae[..., j], t_s, reference_rad=ref)
            comps.append(v)
            produced &= ok
        meas = np.stack(comps, axis=-1)
        meas[..., 0] = np.abs(meas[..., 0])
        meas[..., 1], meas[..., 2] = fold_azimuth_elevation(meas[..., 1], meas[..., 2])
        if self._drop is not None:
            lost = self._drop.draw("random", rae.shape[1]) < self.cfg.dropout_probability
            produced &= ~lost
        return meas, produced

    def _sample_in_medium(
        self, t_s: NDArray[np.float64], pos: NDArray[np.float64], true_rae: NDArray[np.float64]
    ) -> SensorSamples:
        """Fixes through the true medium: range = nominal speed x travel time of the reply,
        elevation = arrival elevation at the transceiver (module docstring)."""
        assert self.propagation is not None
        ray = self.propagation.eigenray(pos, np.broadcast_to(self.transceiver_world_m, pos.shape))
        reached = np.isfinite(ray.travel_time_s)
        travel = np.where(reached, ray.travel_time_s, true_rae[..., 0] / self.cfg.sound_speed_m_s)
        acoustic = np.stack(
            [
                self.cfg.sound_speed_m_s * travel,
                true_rae[..., 1],
                np.where(reached, ray.arrival_elevation_rad, true_rae[..., 2]),
            ],
            axis=-1,
        )
        meas, produced = self._measure(t_s, acoustic, reached.copy())
        produced &= true_rae[..., 0] <= self.cfg.max_range_m
        produced &= acoustic[..., 2] >= np.radians(self.cfg.min_elevation_deg)
        t_arr = t_s + travel + self.cfg.processing_delay_s
        return SensorSamples(t_s, meas, produced, t_arr)


@register_device(UsblConfig)
class UsblDevice:
    """The USBL in a vehicle's rig (event): a fix every ``period_s``, valid at the reply and
    reaching the vehicle after the travel time and the processing delay.

    The transponder's lever arm is the configured one, or the model's site when it is zero.
    Value: ``(range m, azimuth rad, elevation rad)`` from the scene's transceiver, shape (3,).
    With the sea's medium (``build.propagation``) the fix is the one through it (module
    docstring).
    """

    kind = "event"

    def __init__(self, cfg: UsblConfig, build: DeviceBuild):
        cfg = build.with_lever_arm(cfg, "transponder_body_m")
        self.lever_arm_body_m = np.asarray(cfg.transponder_body_m, dtype=float)
        self.transceiver_world_m = build.physics.transceiver_world()
        self.name = build.name
        self.every = build.every(cfg.period_s)
        self._usbl = Usbl(
            cfg,
            self.transceiver_world_m,
            build.seed,
            (build.run,),
            build.stream,
            propagation=build.propagation,
        )

    def step(self, ctx: TickContext) -> Measurement | None:
        """A fix at the USBL's ticks (``None`` when none is produced)."""
        if ctx.k % self.every:
            return None
        u = self._usbl.sample(ctx.record, _FIRST)
        if not u.produced[0, 0]:
            return None
        return Measurement(
            self.name,
            ctx.t_s,
            float(u.t_arrival_s[0, 0]),
            u.values[0, 0],
            ctx.measured_attitude_rad,
        )


_FIRST = np.zeros(1, dtype=np.intp)
