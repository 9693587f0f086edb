"""Gymnasium environments of the registered missions.

Importing this package registers one environment per closed-loop mission (``bauv list``:
``mission/...``) under the id ``bauv/<family>-<name>-v0``::

    import gymnasium
    import tasks.gym  # registers bauv/mission-survey-v0, bauv/mission-short-v0, ...

    env = gymnasium.make("bauv/mission-survey-v0", overrides=["timing.max_duration_s=300"])
    obs, info = env.reset(seed=1)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

``gymnasium.make("tasks.gym:bauv/mission-survey-v0")`` imports the package itself. The
observation, action, reward, termination, truncation and seeding are those of
:class:`tasks.gym.env.MissionEnv` (its module docstring); the keyword arguments of ``make`` are its
arguments (``overrides``, ``scenario_files``, ``observation``, ``controlled``).

Gymnasium is an optional dependency: ``pip install 'bauv-sim[gym]'``.
"""

from __future__ import annotations

try:
    import gymnasium
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise ImportError(
        "tasks.gym needs Gymnasium, an optional dependency: pip install 'bauv-sim[gym]'"
    ) from exc

from tasks.closed_loop.experiment import MissionExperiment
from tasks.core import registry
from tasks.gym.env import MissionEnv

NAMESPACE = "bauv"
"""The namespace of the environment ids."""

VERSION = 0
"""The version of the environment ids (raised when an environment's definition changes)."""


def env_id(mission: str) -> str:
    """The Gymnasium id of a mission: ``"mission/survey"`` -> ``"bauv/mission-survey-v0"``."""
    return f"{NAMESPACE}/{mission.replace('/', '-')}-v{VERSION}"


def missions() -> tuple[str, ...]:
    """The registered closed-loop missions (every registered
    :class:`~tasks.closed_loop.experiment.MissionExperiment`), sorted."""
    return tuple(n for n in registry.names() if isinstance(registry.get(n), MissionExperiment))


def register_missions() -> dict[str, str]:
    """Register every mission's environment with Gymnasium (once; importing the package does it).

    Returns:
        Gymnasium id -> mission name.
    """
    ids = {}
    for mission in missions():
        i = env_id(mission)
        if i not in gymnasium.registry:
            gymnasium.register(
                id=i, entry_point="tasks.gym.env:MissionEnv", kwargs={"mission": mission}
            )
        ids[i] = mission
    return ids


ENV_IDS = register_missions()
"""Gymnasium id -> mission name, of every registered mission."""

__all__ = ["ENV_IDS", "NAMESPACE", "VERSION", "MissionEnv", "env_id", "missions"]
