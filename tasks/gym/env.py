"""A registered mission as a Gymnasium environment (:class:`MissionEnv`).

The environment is a thin wrapper of the mission's own dm_control environment
(:func:`tasks.closed_loop.world.build_environment`: the same physics, sea, sensor rigs, navigation
and guidance that ``bauv run`` flies); the agent takes the place of the vehicles' autopilot
(:class:`tasks.closed_loop.parts.Pilot`). One Gymnasium step is one control tick
(``timing.control_tick_s``, 0.2 s in the presets).

* **Observation**: a flat float64 vector (:mod:`tasks.gym.observation`): by default what each
  vehicle's navigation knows and the guidance command; the true state with ``observation="truth"``
  or ``"both"``. ``env.unwrapped.observation_slices`` names every element's slice.
* **Action**: the actuator commands of the controlled vehicles (all by default), five per vehicle
  in the physics setters' units: tail-beat frequency (Hz), tail bias (rad), port and starboard fin
  angles (rad), battery position (m), bounded by the model's command limits
  (``Box(low, high)``; ``env.unwrapped.action_names``). Finite values outside the bounds are
  clipped to them, as MuJoCo clamps a control to its range; a NaN or a wrong shape is refused.
  Vehicles not in ``controlled`` fly on their mission's own autopilot.
  ``env.unwrapped.autopilot_action()`` is what the mission's autopilot would command now (a
  baseline; called at every step it flies the mission exactly as ``bauv run`` does).
* **Reward** (way-point progress, m per step): the sum over the vehicles whose mission is not
  over of the true horizontal distance made good during the step towards the way-point each was
  approaching at the start of the step: ``|w - p_before| - |w - p_after|`` (truth positions,
  east/north, m). A vehicle whose guidance flies no way-points (``mission/seed004``'s locally
  optimal control, ``mission/swarm``'s station keepers) earns the distance made good along the
  course its guidance commanded at the start of the step: ``(p_after - p_before) . u(course)``.
  Over an episode the reward sums to the distance closed towards the way-points.
* **Termination**: every vehicle's mission is over (its guidance is done: the last way-point
  reached by the estimate, or the mission's own end), or a failure (a physics divergence, a
  navigation error: ``info["failure"]`` says which and when; that step's reward is 0 and the
  observation is the last valid one).
* **Truncation**: the scenario's ``timing.max_duration_s`` reached (``--set``-style
  ``overrides=["timing.max_duration_s=60"]`` shortens it).
* **Seeding**: ``reset(seed=s)`` flies run 0 of the batch seeded ``s`` (``options={"run": r}``:
  run ``r``); each ``reset()`` without a seed flies the batch's next run. Run ``r`` of seed ``s``
  is the run ``r`` of ``bauv run MISSION --seed s``: the same streams of random numbers, bit for
  bit. Before any seed is given, the batch seed is drawn from the environment's ``np_random``.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import gymnasium
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from bauv_sim.config import load_config
from bauv_sim.errors import BauvSimError, ConfigError, PhysicsError
from bauv_sim.frames import unit_vector_scalar
from bauv_sim.rng import MAX_SEED, check_seed
from nav.errors import NavError
from tasks.closed_loop.experiment import MissionExperiment
from tasks.closed_loop.parts import ACTIONS
from tasks.closed_loop.result import MissionRun
from tasks.closed_loop.world import MissionWorld, build_environment
from tasks.core import registry
from tasks.gym.observation import LAYOUTS, ObservationLayout

Array = NDArray[np.float64]


def mission_experiment(mission: Any) -> MissionExperiment:
    """The registered mission named ``mission``.

    Raises:
        ConfigError: for a name that is not registered or not a mission, naming the missions.
    """
    exp = registry.get(mission)
    if not isinstance(exp, MissionExperiment):
        known = ", ".join(
            n for n in registry.names() if isinstance(registry.get(n), MissionExperiment)
        )
        raise ConfigError(f"mission = {mission!r}: not a closed-loop mission; missions: {known}")
    return exp


class MissionEnv(gymnasium.Env):
    """A registered mission as a Gymnasium environment (see the module docstring).

    Args:
        mission: the mission's registered name (``bauv list``: ``mission/...``).
        overrides: ``dotted.key=value`` scenario overrides, as ``bauv run --set``.
        scenario_files: TOML scenario files merged over the preset, as ``bauv run --scenario``.
        observation: the observation layout, one of :data:`tasks.gym.observation.LAYOUTS`.
        controlled: the vehicles the agent commands, a subset of the scene's (default: all);
            the action lists them in the scene's order.
        render_mode: ``None`` (no rendering).

    Raises:
        ConfigError: a bad argument or scenario, naming the field, the value and what is allowed.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": []}

    def __init__(
        self,
        mission: str = "mission/survey",
        overrides: Sequence[str] = (),
        scenario_files: Sequence[str] = (),
        observation: str = "navigation",
        controlled: Sequence[str] | None = None,
        render_mode: str | None = None,
    ):
        if render_mode is not None:
            raise ConfigError(f"render_mode = {render_mode!r}: must be None (no rendering)")
        if observation not in LAYOUTS:
            raise ConfigError(
                f"observation = {observation!r:.60}: must be one of {', '.join(LAYOUTS)}"
            )
        self.render_mode = None
        self.mission = mission
        self.experiment = mission_experiment(mission)
        exp = self.experiment
        self.scenario = load_config(exp.scenario_type, exp.preset, scenario_files, overrides)
        exp.check(self.scenario, 1)
        # the spaces, from the run 0 of seed 0 (the vehicles and their limits are the scene's)
        probe = build_environment(*exp.flight(self.scenario, 0, 0), 0, 0)
        world: MissionWorld = probe.task
        self.vehicles: tuple[str, ...] = world.names
        self.controlled = self._check_controlled(controlled)
        spec = probe.action_spec()
        n = len(ACTIONS)
        idx = [self.vehicles.index(v) * n + j for v in self.controlled for j in range(n)]
        self._action_index = np.array(idx, dtype=np.intp)
        self._spec_bounds = (np.array(spec.minimum, float), np.array(spec.maximum, float))
        low, high = (b[self._action_index] for b in self._spec_bounds)
        self.action_space = spaces.Box(low, high, dtype=np.float64)
        self.action_names: tuple[str, ...] = tuple(
            f"{v}/{k} [{u}]" for v in self.controlled for k, u in ACTIONS
        )
        self.layout = ObservationLayout(observation, self.vehicles)
        self.observation_space = spaces.Box(-np.inf, np.inf, (self.layout.size,), np.float64)
        self.observation_names = self.layout.names
        self.observation_slices = dict(self.layout.slices)
        self._dm: Any = None
        self._seed: int | None = None
        self._run = 0
        self._over = False
        self._failure: str | None = None

    def _check_controlled(self, controlled: Sequence[str] | None) -> tuple[str, ...]:
        if controlled is None:
            return self.vehicles
        if isinstance(controlled, str) or not isinstance(controlled, Sequence):
            raise ConfigError(
                f"controlled = {controlled!r:.60}: must be a sequence of vehicle names, a "
                f"subset of {list(self.vehicles)}, or None"
            )
        bad = [v for v in controlled if v not in self.vehicles]
        if bad or not controlled or len(set(controlled)) != len(controlled):
            raise ConfigError(
                f"controlled = {list(controlled)!r:.80}: must name each vehicle once, at least "
                f"one, among {list(self.vehicles)}"
            )
        return tuple(v for v in self.vehicles if v in controlled)

    # -- Gymnasium API -------------------------------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[Array, dict[str, Any]]:
        """Start an episode: run ``options["run"]`` (default 0) of the batch seeded ``seed``, or
        the batch's next run without a seed (see the module docstring).

        Raises:
            ConfigError: a seed outside [0, 2**63 - 1], an unknown option or a bad run index.
        """
        if seed is not None:
            check_seed(seed)
        opts = dict(options or {})
        run = opts.pop("run", None)
        if opts:
            raise ConfigError(f"options = {sorted(opts)}: unknown; the only option is 'run'")
        if run is not None and (
            isinstance(run, bool) or not isinstance(run, numbers.Integral) or run < 0
        ):
            raise ConfigError(f"options['run'] = {run!r:.60}: must be an integer >= 0")
        super().reset(seed=seed)
        if seed is not None:
            self._seed, self._run = int(seed), 0 if run is None else int(run)
        else:
            if self._seed is None:
                self._seed = int(self.np_random.integers(0, MAX_SEED, endpoint=True))
                self._run = -1
            self._run = self._run + 1 if run is None else int(run)
        self._start(self._seed, self._run)
        return self._observation(), self._info()

    def step(self, action: Any) -> tuple[Array, float, bool, bool, dict[str, Any]]:
        """One control tick with the given actuator commands (see the module docstring).

        Raises:
            ConfigError: an action of the wrong shape or with a NaN, naming the element.
            BauvSimError: a step before :meth:`reset` or after the episode ended.
        """
        if self._dm is None:
            raise BauvSimError("step() before reset(): call reset() to start an episode")
        if self._over:
            raise BauvSimError(
                "step() after the episode ended (terminated or truncated): call reset()"
            )
        a = self._check_action(action)
        if len(self.controlled) == len(self.vehicles):
            full = a
        else:
            full = self._autopilot_full().copy()
            full[self._action_index] = a
        physics = self._dm.physics
        try:
            ts = self._dm.step(full)
        except (PhysicsError, NavError, BauvSimError) as exc:
            t = physics.time_s()
            self._over = True
            self._failure = (
                f"run {self._run} (seed {self._seed}) failed at t = {t:.2f} s: "
                f"{type(exc).__name__}: {exc}"
            )
            info = self._info()
            info["failure"] = self._failure
            return self._obs.copy(), 0.0, True, False, info
        self._pilot_out = None
        self._dm_obs = ts.observation
        before = self._positions
        self._truths = {v: physics.truth(v) for v in self.vehicles}
        self._positions = {v: self._truths[v].position_world_m[:2].copy() for v in self.vehicles}
        reward = self._reward(before, self._positions)
        self._aims = self._current_aims()
        self._obs = self.layout.vector(self._dm_obs, self._truths)
        terminated = all(v.guidance.done for v in self.world.parts.vehicles)
        truncated = bool(ts.last()) and not terminated
        self._over = terminated or truncated
        return self._obs.copy(), reward, terminated, truncated, self._info()

    def render(self) -> None:
        """No rendering (``render_mode`` is ``None``)."""
        return None

    def close(self) -> None:
        """Release the episode's physics (idempotent)."""
        self._dm = None

    # -- beyond Gymnasium ----------------------------------------------------------------------

    @property
    def world(self) -> MissionWorld:
        """The episode's mission world (its parts, its logs), after :meth:`reset`."""
        if self._dm is None:
            raise BauvSimError("no episode: call reset() first")
        return self._dm.task

    def autopilot_action(self) -> Array:
        """What the mission's own autopilot commands now for the controlled vehicles, shape like
        the action. The autopilot keeps state (integrators): called once at every step and
        passed to :meth:`step`, it flies the mission exactly as ``bauv run`` does."""
        if self._dm is None:
            raise BauvSimError("no episode: call reset() first")
        return self._autopilot_full()[self._action_index].copy()

    def result(self) -> MissionRun:
        """The episode so far as the mission's run result (per-tick columns, fixes, summary:
        :class:`~tasks.closed_loop.result.MissionRun`), as ``bauv run`` records it."""
        return self.world.result(self._failure)

    # -- internals -----------------------------------------------------------------------------

    def _start(self, seed: int, run: int) -> None:
        design, scn = self.experiment.flight(self.scenario, seed, run)
        self._dm = build_environment(design, scn, seed, run)
        ts = self._dm.reset()
        world: MissionWorld = self._dm.task
        if world.names != self.vehicles:
            raise BauvSimError(
                f"run {run} (seed {seed}) flies vehicles {world.names}, the environment's "
                f"spaces are for {self.vehicles}"
            )
        self._pilot = world.policy(self._dm.action_spec())
        self._pilot_out: Array | None = None
        self._dm_obs = ts.observation
        physics = self._dm.physics
        self._truths = {v: physics.truth(v) for v in self.vehicles}
        self._positions = {v: self._truths[v].position_world_m[:2].copy() for v in self.vehicles}
        self._aims = self._current_aims()
        self._obs = self.layout.vector(self._dm_obs, self._truths)
        self._over = False
        self._failure = None

    def _observation(self) -> Array:
        return self._obs.copy()

    def _info(self) -> dict[str, Any]:
        return {"seed": self._seed, "run": self._run, "t_s": float(self._dm.physics.time_s())}

    def _autopilot_full(self) -> Array:
        """Every vehicle's autopilot action now, computed once per tick (the pilots keep
        state)."""
        if self._pilot_out is None:
            self._pilot_out = np.asarray(self._pilot(self._dm_obs), dtype=float)
        return self._pilot_out

    def _check_action(self, action: Any) -> Array:
        try:
            a = np.array(action, dtype=float)
        except (TypeError, ValueError):
            raise ConfigError(
                f"action = {action!r:.60}: must be an array of shape {self.action_space.shape} "
                f"({', '.join(self.action_names)})"
            ) from None
        if a.shape != self.action_space.shape:
            raise ConfigError(
                f"action of shape {a.shape}: must have shape {self.action_space.shape} "
                f"({', '.join(self.action_names)})"
            )
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            i = int(bad[0])
            raise ConfigError(
                f"action[{i}] ({self.action_names[i]}) = {a[i]}: must be finite, in "
                f"[{self.action_space.low[i]:g}, {self.action_space.high[i]:g}]"
            )
        return np.clip(a, self.action_space.low, self.action_space.high)

    def _current_aims(self) -> dict[str, tuple[str, tuple[float, float]] | None]:
        """Per vehicle, what the next step's reward measures progress towards: ``("waypoint",
        (east, north))`` of the way-point being approached, ``("course", unit vector)`` of the
        commanded course for guidance without way-points, ``None`` once its mission is over."""
        aims: dict[str, tuple[str, tuple[float, float]] | None] = {}
        for v in self.world.parts.vehicles:
            g = v.guidance
            if g.done:
                aims[v.name] = None
                continue
            wps = g.waypoints()
            if wps:
                i = len(g.legs())  # each ended leg moved guidance to the next way-point
                aims[v.name] = ("waypoint", (wps[i][0], wps[i][1])) if i < len(wps) else None
            else:
                course = float(self._dm_obs[f"{v.name}/command"][0])
                aims[v.name] = ("course", unit_vector_scalar(course))
        return aims

    def _reward(self, before: Mapping[str, Array], after: Mapping[str, Array]) -> float:
        """The way-point progress of the step, m (module docstring)."""
        total = 0.0
        for name, aim in self._aims.items():
            if aim is None:
                continue
            (e0, n0), (e1, n1) = before[name], after[name]
            kind, (a, b) = aim
            if kind == "waypoint":
                total += math.hypot(a - e0, b - n0) - math.hypot(a - e1, b - n1)
            else:
                total += (e1 - e0) * a + (n1 - n0) * b
        return float(total)
