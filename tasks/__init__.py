"""tasks: the framework that runs experiments and missions, and the experiments and missions.

Layers (see ``docs/architecture.md``):

* :mod:`tasks.core`: the framework: registry, Monte Carlo runner, block store, reports, figures,
  recordings, run-data export and the ``bauv`` CLI. It knows no experiment.
* :mod:`tasks.closed_loop`: the mission core: a mission composed of parts (sea; per vehicle a
  sensor rig, a navigator, guidance and an autopilot) for any number of vehicles in one scene.
* :mod:`tasks.paper000`, :mod:`tasks.paper001`: the papers' experiments, one subpackage per paper.
* :mod:`tasks.missions`: the registered closed-loop missions.
* :mod:`tasks.vehicle`: experiments on the vehicle itself (autopilot trials; the model's tooling is
  ``models/bauv/tools``, outside the package).

Each experiment package declares its family of names as an entry point of the group
``bauv_sim.experiments`` (``pyproject.toml``) and the looks of its methods in its ``__init__``
(:func:`tasks.core.style.declare`); importing it registers its experiments. The framework
imports a family's package when a name of it is asked for (:mod:`tasks.core.families`,
:mod:`tasks.core.registry`). ``catalog.json`` here lists every experiment's name and summary for
``bauv list`` (generated: ``python -m tasks.core.catalog``). Depends on :mod:`nav` and
:mod:`bauv_sim`; nothing depends on it.
"""

from nav._exports import lazy_exports

_EXPORTS: dict[str, tuple[str, str]] = {
    "BatchFailed": ("tasks.core.errors", "BatchFailed"),
    "BatchInterrupted": ("tasks.core.errors", "BatchInterrupted"),
    "BatchPlan": ("tasks.core.plan", "BatchPlan"),
    "Column": ("tasks.core.export", "Column"),
    "Experiment": ("tasks.core.registry", "Experiment"),
    "MissionRun": ("tasks.closed_loop.result", "MissionRun"),
    "MissionScenario": ("tasks.closed_loop.scenario", "MissionScenario"),
    "VehicleRun": ("tasks.closed_loop.result", "VehicleRun"),
    "WaypointMission": ("tasks.closed_loop.world", "WaypointMission"),
    "experiment_names": ("tasks.core.registry", "names"),
    "fly": ("tasks.closed_loop.world", "fly"),
    "get_experiment": ("tasks.core.registry", "get"),
    "plan_batch": ("tasks.core.plan", "plan_batch"),
    "read_parquet": ("tasks.core.export", "read_parquet"),
    "register": ("tasks.core.registry", "register"),
    "run": ("tasks.core.runner", "run"),
    "write_parquet": ("tasks.core.export", "write_parquet"),
}
"""Public name -> (module, attribute), imported on first use."""

__all__, __getattr__, __dir__ = lazy_exports(globals(), _EXPORTS)
