"""``mission/seed004``: seed 004 on the physical BAUV: bearings to beacons, locally optimal control.

The BAUV follows seed 004's 3-D nominal path (eq. 3 with section 6's angle laws ``gamma°(t) =
pi/100 cos(pi t / 100)``, ``theta°(t) = pi/3 cos(pi t / 25)``) flown at the vehicle's speed
``V° = 1 m/s`` instead of 2 m/s: with the same angle laws in time the path is the seed's shape
scaled by ``V° / 2`` (so the depth swings by +-1 m instead of +-2 m, inside the scene's 6 m of
water), started at the scenario's start and cut to ``seed004.duration_s``. The four DOA beacons
are the seed's (section 6) scaled by the same factor about the path's start, moored
``seed004.beacon_depth_m`` below the surface (the seed's beacons are at the surface).

Every ``seed004.dt_s`` (the DOA period, seed 004's 1 s) the chosen filter (``navigation.filter``:
EKF, UPMF or CMNF, one step of :mod:`nav.bearings.bank`; ``"all"`` flies each in turn on the same
run) predicts with the previous control ("by virtue of the system", eq. 1), takes the bearing
tangents of that tick (eq. 17) and the locally optimal control with box limits
(:func:`nav.bearings.local_control.limited_control`, eq. 5-7) is computed on its estimate. The
control ``u = (gamma, theta, V)`` (seed 004's angles: theta counter-clockwise from east, gamma up)
goes to the existing autopilot as set-points held for the step: course ``pi/2 - theta`` (clockwise
from north), speed ``V`` (through water) and, since the autopilot holds a depth, not a pitch, the
depth set-point at which its depth loop settles at the vertical rate ``w = V sin(gamma)`` (up): that
loop is a PD on the depth error, ``pitch = kp e - kd w`` with ``w = V pitch``, so it climbs at ``w``
with the set-point ``e = w (1 + V kd) / (V kp)`` above the measured depth (:func:`depth_setpoint`;
5.3 s of climb at the default gains and 1 m/s). A set-point one step ahead (``w dt``) would be flown
at a fifth of the commanded rate (measured: the vertical residual then adds up to 1.5 m in 160 s).

The CMNF's gains are fitted (CMNF in the loop, :func:`tasks.paper004.sim.train_gains`) on a
kinematic surrogate of the same mission (:mod:`bauv_sim.kinematic.seed004` with the scaled path,
``dt``, beacons, limits, bearing noise and the surrogate's process noise
``seed004.sigma_w_m``) on ``seed004.train_paths`` paths; they are deterministic in (setting,
seed), trained once per process and written to the run folder as plain ``.npz``
(``cmnf-gains.npz``). The report compares the CMNF's J-bar (``max_k E||X°_k - X_k||^2``, seed 004
section 6) on ``seed004.surrogate_test_paths`` fresh surrogate paths with the one on the physics
runs, and gives the physics' own step residual ``X_{k+1} - X_k - V(u_k) dt`` (what the surrogate's
``S^W`` stands for).

**Seabed-sensing prediction** (``navigation.prediction = "seabed"``, Table 1's row 2 on the
vehicle): the rig carries the multibeam (:class:`bauv_sim.sensors.multibeam.MultibeamDevice`,
``multibeam.*``: seed 004's 8 x 8 beams, 0.1 m range noise, an image every filter step), whose
beams MuJoCo casts against the scene's seabed heightfield from the hull's ``sonar`` site. Every
filter predicts with the shift of eq. 15 between the images of ``t_{j-1}`` and ``t_j``
(:class:`SonarShift`: the hull's measured attitudes at the two pings, reading ``"turning"`` with
the exact beam change, Appendix A's fit with ``seed004.slope_basis``, the lever arm's turn
removed) and its stated covariance; the CMNF's alpha is the estimate plus that shift. The CMNF is
trained on a surrogate that images the same heightfield
(:class:`tasks.paper004.seabed.HeightfieldPrediction`, rays by
:meth:`bauv_sim.seabed.Seabed.ray_ranges`, which equal MuJoCo's). The mission's seabed
(:data:`SEABED_PRESET`) has relief at the scale of the multibeam's footprint, and the check
refuses a seabed beyond the multibeam's range along the path. A filter whose estimate leaves the
nominal point by more than ``seed004.diverge_m`` stops its flight with a named divergence
(``failures``); the report gives the shift's own error on the physics and on the surrogate.

**Run data.** A run keeps each filter's flight (:class:`Seed004RunResult`'s ``flights``, plain
:class:`~tasks.closed_loop.result.MissionRun` data: the truth, that filter's estimate and
covariance, DR, the commands and the control per tick, the bearings as the ``doa`` fix table)
and the report exports every run's as Parquet with the filter as the variant
(``data/ticks/run-NNNNNN-<filter>-bauv.parquet``, ``data/doa/...``; ``docs/run-data.md``).
"""

from tasks.missions.seed004 import experiment
from tasks.missions.seed004.experiment import IMAGE_BYTES_PER_PATH_BEAM, Seed004Experiment
from tasks.missions.seed004.metrics import Seed004RunResult, distance_to_polyline
from tasks.missions.seed004.parts import (
    BearingNavigation,
    Seed004Mission,
    SonarShift,
    depth_setpoint,
)
from tasks.missions.seed004.scenario import FILTERS, Seed004Scenario, beacons_world, surrogate

__all__ = [
    "FILTERS",
    "IMAGE_BYTES_PER_PATH_BEAM",
    "BearingNavigation",
    "Seed004Experiment",
    "Seed004Mission",
    "Seed004RunResult",
    "Seed004Scenario",
    "SonarShift",
    "beacons_world",
    "depth_setpoint",
    "distance_to_polyline",
    "experiment",
    "surrogate",
]
