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

import lazy_loader

# the public names: those of __init__.pyi, each imported from its module on first use
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
