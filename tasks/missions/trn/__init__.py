"""``mission/trn``: a DVL and terrain-relative navigation (TRN) on the physical BAUV, closed loop:
a survey over relief with no USBL fix after the dive.

The package: :mod:`~tasks.missions.trn.scenario` (the scenario: the seabed preset, the DVL, the
navigator's map, the TRN settings), :mod:`~tasks.missions.trn.terrain` (the true seabed as a map,
the navigator's degraded copy, the PCRB along the true track), :mod:`~tasks.missions.trn.parts`
(the navigation part that runs every method on one flight, the design),
:mod:`~tasks.missions.trn.run` (one run flown and reduced), :mod:`~tasks.missions.trn.metrics`,
:mod:`~tasks.missions.trn.report` and :mod:`~tasks.missions.trn.figures`;
:mod:`~tasks.missions.trn.experiment` registers it.

**The flight.** The BAUV starts at depth (4 m) and flies a lawn-mower survey (three 160 m legs
40 m apart, ~570 m at 1 m/s) over the scene's seabed generated with the scenario's ``seabed``
section (:data:`~tasks.missions.trn.scenario.SEABED_PRESET`: 14 m deep, 1.5 m of relief in
wavelengths of 20-120 m), ~10 m above it, in a uniform current of 0.3 m/s. Its rig is the
standard one (compass with a residual 1 deg bias, INS, EM log, pressure, USBL) plus the DVL
(:class:`bauv_sim.sensors.dvl.DvlDevice`: four Janus beams cast by MuJoCo against the
heightfield, 5 Hz). The USBL fixes reach the vehicle's navigator until ``trn.t_dive_s`` (the
first minute, "the dive") and none after; the rig's USBL keeps pinging for the reference only.

**The methods, side by side on the same flight** (:class:`~tasks.missions.trn.parts.
TrnNavigation`), all started at the dive from the USBL-aided EKF's estimate and covariance:

* ``dr_log``: dead reckoning on the compass heading and the log's speed through water (the
  standard navigator's DR track, restarted at the dive): it drifts with the current it cannot
  see (0.3 m/s: ~18 m a minute);
* ``dr_dvl``: dead reckoning on the DVL's velocity over ground, rotated to the world by the
  measured attitude with the lever-arm term (:func:`nav.dvl.velocity_world_from_dvl`), through
  :class:`nav.dead_reckoning.DeadReckoning`: blind to the current, it drifts with the compass
  bias and the DVL's errors only;
* ``trn_pf`` / ``trn_pmf``: :class:`nav.trn.ParticleTrn` / :class:`nav.trn.PointMassTrn`,
  predicting with the DVL displacement and its covariance at every ping and updating every
  ``trn.update_period_s`` with the DVL beams' soundings (:func:`nav.trn.soundings`: measured
  attitude, pressure depth) against the navigator's map, a degraded copy of the true seabed
  (:func:`nav.trn.degraded`: coarser grid, node noise, an offset; never the truth);
* ``ekf_log``: the vehicle's EKF after the dive (log and compass with the current it learnt
  from the fixes before it);
* ``usbl_ekf``: the reference, another standard navigator fed every record of the same rig,
  the USBL fixes after the dive included; it does not steer.

Guidance steers on ``navigation.steer`` (default ``trn_pf``). **The bound**: the TRN PCRB
(:func:`nav.trn.trn_pcrb`) is computed after the flight from the true track: the true beam
footprints (rays from the true pose against the true seabed), the TRUE seabed's gradients there,
the sounding and map sigmas the filters assume, the prediction covariance they were given
(:func:`~tasks.missions.trn.terrain.pcrb_track`).

**Report**: error against time per method beside the PCRB (``errors.png``), final / mean / max
error per method over the runs, DR-DVL against DR-log (check 2), each TRN filter's verdict:
bounded, and within 2x the PCRB (check 4); over a flat seabed (``--set
seabed.relief_std_m=0``) the report says why TRN grows like dead reckoning. Bad input degrades
and is counted (a map smaller than the survey, ``map.half_extent_m``; holes of no data,
``map.nan_holes``; the vehicle above ``sensors.dvl.max_altitude_m``): pings without bottom lock and
TRN updates without a usable beam are counted in the report and its warnings; a scenario that
cannot be flown is refused before anything is written (one line, exit status 2).
"""

from tasks.core.style import PALETTE as P
from tasks.core.style import MethodStyle, declare

declare(
    __name__,
    {
        "DR-log": MethodStyle(P["vermillion"], ls="--"),
        "DR-DVL": MethodStyle(P["orange"]),
        "TRN-PF": MethodStyle(P["blue"]),
        "TRN-PMF": MethodStyle(P["sky_blue"], ls="-."),
        "EKF-log": MethodStyle(P["reddish_purple"], ls=":"),
        "USBL-EKF": MethodStyle(P["bluish_green"]),
    },
)

from tasks.missions.trn import experiment  # noqa: E402
from tasks.missions.trn.experiment import TrnExperiment  # noqa: E402
from tasks.missions.trn.metrics import TrnMetrics  # noqa: E402
from tasks.missions.trn.parts import TrnMission, TrnNavigation, TrnReport  # noqa: E402
from tasks.missions.trn.run import TrnRunResult, fly_run, reduce_flight  # noqa: E402
from tasks.missions.trn.scenario import METHODS, SEABED_PRESET, TrnScenario  # noqa: E402

__all__ = [
    "METHODS",
    "SEABED_PRESET",
    "TrnExperiment",
    "TrnMetrics",
    "TrnMission",
    "TrnNavigation",
    "TrnReport",
    "TrnRunResult",
    "TrnScenario",
    "experiment",
    "fly_run",
    "reduce_flight",
]
