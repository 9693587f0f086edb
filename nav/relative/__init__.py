"""Positioning relative to a swarm leader from one acoustic range (seed 003, Naus & Piskur 2022).

A follower F dead-reckons from course C and speed S (eq. 1) and accumulates the covariance of its
DR displacement (eq. 5-6). Every few seconds it receives from the leader L the range D_h between
them and L's position, and adjusts its own position by least squares constrained to the circle of
radius D_h around L (eq. 2-4): the candidates are ``X_F0(phi) = X_L + D_h (sin phi, cos phi)``
(the reading notes: the printed ``x_L * D_h * sin(phi)`` means ``x_L + D_h sin(phi)``), ``phi`` the
bearing of the candidate from L, and the fix is the candidate that minimises ``V^T P V`` where the
"measurements" are the bearing B_r and the distance D_r of the DR segment from its start
``X_F(k)`` to its end ``X_DR(k+n)`` and the range D_h:

* **GA1** (eq. 3): ``V = A d + L`` with ``d = X_F0 - X_DR(k+n)``, A the rows of eq. 2 at the
  candidate and ``L = (B_F0 - B_r, D_F0 - D_r, D_L0 - D_h)``;
* **GA2** (eq. 4): ``V = L``.

The weights are ``P = diag(1/delta_Br^2, 1/delta_Dr^2, 1/delta_Dh^2)`` with ``delta_Dr = M_xy``
and ``delta_Br = atan(M_xy / D_r)`` from the DR covariance since the last fix (eq. 6), and
``delta_Dh`` the modem's range error. The geometry's quality is the HDOP of eq. 7-8, computed with
the unweighted A at the fix.

Readings this module had to choose (the printed equations leave them open; ``../shared/seeds/
README.md`` lists them), each an option of :class:`GaOptions` where it is a real choice:

* **A's columns** (``GaOptions.jacobian``). Eq. 2 prints ``a_Br = (dx/D^2, -dy/D^2)``,
  ``a_Dr = (-dy/D, -dx/D)``, ``a_Dh = (-dy_L/D_L, -dx_L/D_L)`` with ``(dx, dy) = X_F(k) - X_F0``
  and ``(dx_L, dy_L) = X_L - X_F0``. The derivatives of the printed B, D with respect to
  ``(x_F0, y_F0)`` (x east) are those rows with their two columns swapped: the rows are the
  Jacobian in geodetic axes (x north, y east) while ``d`` is written in the paper's (x east,
  y north). ``"printed"`` applies the rows as printed to ``d = (dx, dy)``; ``"true"`` uses the
  Jacobian of the printed functions in the paper's own axes. With ``"true"``, ``A d`` is the first-
  order change of the functions from ``X_DR`` to the candidate, so near the circle ``A d ~ L`` and
  GA1 picks (almost) the candidate GA2 picks.
* **Restart** (``GaOptions.restart``): whether DR restarts from the GA position after each fix
  (then ``X_F(k)`` is the previous fix) or runs on undisturbed (then ``X_F(k)`` is the DR position
  at the previous fix and the GA positions are a separate output). The caller applies it
  (:class:`FollowerNavigator`, the paper-003 experiments); :func:`ga_fix` takes ``start`` and
  ``dr_end`` as given.
* **Bearings** use ``atan2`` (the printed ``atan`` loses the quadrant) and bearing residuals are
  wrapped to (-pi, pi].
* **Degenerate rows**: with ``D_r`` below ``min_step_m`` (no displacement since the last fix) the
  bearing row has no meaning and gets weight 0; ``M_xy`` is floored at ``min_sigma_m`` so that
  ``P`` stays finite right after a fix; a range below ``min_range_m`` (or one not received) makes
  no fix (``GaFix.valid`` False, the position stays the DR one).
* **Minimisation over phi**: a grid of ``grid`` candidates on the circle, then golden-section
  search within one grid step either side of each of the (up to four) lowest local minima of the
  grid, keeping the lowest result (to ``_PHI_TOL`` = 1e-9 rad, 1e-8 m on a 10 m circle; GA1's
  criterion can have several narrow basins, and the test compares with a brute-force
  minimisation). The criterion is evaluated fused (``_criterion_sc``: no V or A arrays built)
  with the grid's sines computed once per adjustment: the adjustment's hot path.
* **Stated accuracy** (beyond the paper): ``covariance = delta_0^2 (A^T P A)^-1`` with the true
  Jacobian (a covariance must use the true geometry), ``delta_0^2 = V^T P V`` at the fix (the
  redundancy is 3 - 2 = 1); ``covariance_prior = (A^T P A)^-1``, the same without the a-posteriori
  variance factor.

Beyond the paper: :class:`CourseSpeedMotion` and :class:`RangeMeasurement` make the same problem
an EKF (state: the follower's horizontal position; predict with eq. 1 and Q = eq. 5; update with
the range to the broadcast leader position, whose own covariance may be added to R), run with the
estimators of :mod:`nav.ekf`.

All arrays carry a leading run axis n (n = 1 for one vehicle); positions are (east, north) in m,
angles in rad in the navigation convention (course clockwise from north).

The package, one module per responsibility:

* :mod:`nav.relative.motion`: eq. 1's displacement, eq. 5-6, the batched DR track with its
  covariance (:func:`dr_track`, through :mod:`nav.dead_reckoning`), the EKF motion model;
* :mod:`nav.relative.adjustment`: GA1 and GA2 (:func:`ga_fix`) and the HDOP (eq. 7-8);
* :mod:`nav.relative.ranging`: the range as an EKF measurement (:func:`range_update`);
* :mod:`nav.relative.follower`: one follower online (:class:`FollowerNavigator`);
* :mod:`nav.relative.tracks`: the methods over a batch of runs and whole tracks
  (:func:`ga_track`, :func:`ekf_track`);
* :mod:`nav.relative.metrics`: the reductions to the paper's statistics and consistency sums.
"""

from nav.relative.adjustment import (
    GaFix,
    GaMethod,
    GaOptions,
    Jacobian,
    candidates,
    criterion,
    design_rows,
    ga_fix,
    hdop,
    hdop_after_step,
    residuals,
)
from nav.relative.follower import (
    FOLLOWER_METHODS,
    FixOutcome,
    FollowerMethod,
    FollowerNavigator,
)
from nav.relative.metrics import (
    consistency_sums,
    distance_sums,
    distances,
    longest_gaps,
    pooled_stats,
)
from nav.relative.motion import (
    CourseSpeedMotion,
    dr_increment,
    dr_increment_covariance,
    dr_step,
    dr_track,
    mean_position_error,
)
from nav.relative.ranging import RangeMeasurement, range_update
from nav.relative.tracks import (
    FixedTrack,
    LeaderRanges,
    RangeEkfOptions,
    ekf_track,
    ga_track,
)

__all__ = [
    "FOLLOWER_METHODS",
    "CourseSpeedMotion",
    "FixOutcome",
    "FixedTrack",
    "FollowerMethod",
    "FollowerNavigator",
    "GaFix",
    "GaMethod",
    "GaOptions",
    "Jacobian",
    "LeaderRanges",
    "RangeEkfOptions",
    "RangeMeasurement",
    "candidates",
    "consistency_sums",
    "criterion",
    "design_rows",
    "distance_sums",
    "distances",
    "dr_increment",
    "dr_increment_covariance",
    "dr_step",
    "dr_track",
    "ekf_track",
    "ga_fix",
    "ga_track",
    "hdop",
    "hdop_after_step",
    "longest_gaps",
    "mean_position_error",
    "pooled_stats",
    "range_update",
    "residuals",
]
