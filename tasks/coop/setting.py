"""What each setting of ``coop/team`` and ``coop/sensitivity`` hands the network and the
filters: the network's configuration (clocks, sonar), the sea's true medium, and the options of
:func:`nav.cooperative.team_tracks` from the scenario.

One change at a time from the base (:meth:`tasks.coop.scenario.CoopScenario.settings`):

* ``drift_ppm``: every follower's clock drift is drawn per run with this standard deviation
  (the leader's GPS-disciplined clock keeps its own), and the filters' drift prior says so;
* ``sound_speed_m_s``: the sea is isovelocity at this speed while the network and the filters
  keep the nominal speed (a mismatch of the range scale);
* ``sound_profile``: the sea has Munk's thermocline profile
  (:func:`bauv_sim.acoustics.thermocline_preset`; bent rays, 3 % faster than nominal near the
  surface) for the network and the leader's USBL;
* ``source_level_db``: the sonar equation decides which packets arrive (it is on, at this source
  level; the base has it as the scenario says). At the team's ranges (40-200 m) a modem's usual
  185 dB loses nothing; 125-115 dB stand for any loss of margin (a noisier sea, longer ranges).
"""

from __future__ import annotations

from dataclasses import replace

from bauv_sim.acoustics.network import AcousticNetworkConfig
from bauv_sim.acoustics.sound import thermocline_preset
from bauv_sim.errors import ConfigError
from nav.acoustics import Isovelocity, Propagation
from nav.cooperative import LEADER_CLOCK, ClockOptions, CoopOptions
from nav.errors import NavInputError
from tasks.coop.scenario import CoopScenario


def network_config(scn: CoopScenario, what: str, value: float | None) -> AcousticNetworkConfig:
    """The network of one setting (module docstring)."""
    cfg = scn.network
    if what == "drift_ppm":
        clocks = dict(cfg.clocks)
        for f in scn.team.followers:
            base = cfg.clock_of(f.name)
            clocks[f.name] = base.model_copy(update={"drift_sigma_ppm": value})
        return cfg.model_copy(update={"clocks": clocks})
    if what == "source_level_db":
        sonar = cfg.sonar.model_copy(update={"enabled": True, "source_level_db": value})
        return cfg.model_copy(update={"sonar": sonar})
    return cfg


def propagation(scn: CoopScenario, what: str, value: float | None) -> Propagation | None:
    """The sea's true medium of one setting (the scenario's ``sound`` but in a sound setting;
    None: every device's nominal speed)."""
    if what == "sound_speed_m_s":
        return Isovelocity(float(value))
    if what == "sound_profile":
        return thermocline_preset().propagation()
    return scn.sound.propagation()


def coop_options(scn: CoopScenario, what: str = "base", value: float | None = None) -> CoopOptions:
    """The options of :func:`nav.cooperative.team_tracks` from the scenario's ``filters`` (the
    leader's clock: :data:`nav.cooperative.LEADER_CLOCK`, GPS-disciplined; the random walks of
    the followers' clocks: :class:`nav.cooperative.ClockOptions`' defaults). In a ``drift_ppm``
    setting the filters are told the followers' drift spread (their clocks are known to be that
    kind of oscillator).

    Raises:
        ConfigError: naming the scenario field, when ``nav.cooperative`` refuses a value.
    """
    f = scn.filters
    try:
        clock = ClockOptions(
            offset_sigma_s=f.clock_offset_sigma_ms * 1e-3,
            drift_sigma=(value if what == "drift_ppm" else f.clock_drift_sigma_ppm) * 1e-6,
            estimate_drift=f.estimate_drift,
        )
        leader = replace(LEADER_CLOCK, estimate_drift=f.estimate_drift)
        return CoopOptions(clock=clock, leader_clock=leader, fusion=f.fusion)
    except NavInputError as exc:
        raise ConfigError(f"filters: {exc}") from None
