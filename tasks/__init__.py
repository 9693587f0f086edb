"""tasks: the framework that runs experiments and missions, and the experiments and missions.

Layers (see ``docs/architecture.md``):

* :mod:`tasks.core`: the framework: registry, Monte Carlo runner, block store, reports, figures,
  recordings, run-data export and the ``bauv`` CLI. It knows no experiment.
* :mod:`tasks.closed_loop`: the mission core: a mission composed of parts (sea; per vehicle a
  sensor rig, a navigator, guidance and an autopilot) for any number of vehicles in one scene.
* :mod:`tasks.paper000`, :mod:`tasks.paper001`: the papers' experiments, one subpackage per paper.
* :mod:`tasks.missions`: the registered closed-loop missions.
* :mod:`tasks.vehicle`: experiments on the vehicle itself (autopilot trials, the model's checks).

Importing an experiment package registers its experiments; :mod:`tasks.core.registry` imports the
packages named in :data:`tasks.core.registry.EXPERIMENT_PACKAGES`. Depends on :mod:`nav` and
:mod:`bauv_sim`; nothing depends on it.
"""
