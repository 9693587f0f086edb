"""Dead reckoning from multibeam seabed ranges ("acoustic images"), seed 004 section 4 and
Appendix A, batched over paths.

Frame and angles are seed 004's: world x, y horizontal, z up; the direction of motion is
``(gamma, theta)``, theta from the x axis counter-clockwise, gamma up from the horizontal
(:func:`nav.angles`-free here: the seed's angles are used as they are). Every array carries a
leading axis of paths ``P``.

**Beams (eq. 8).** Beam ``(i, j)`` points at ``(gamma_k + gamma^i, theta_k + theta^j)`` with the
unit vector

    e = (cos(g) cos(t), cos(g) sin(t), sin(g)),   g = gamma_k + gamma^i,  t = theta_k + theta^j,

and reaches the seabed at ``x^ij = X_k + L^ij e``. Seed 004's elevations "(42, 82) deg" point
*down* (z is up), so :meth:`BeamGeometry.seed004` uses ``gamma^i`` from -42 to -82 deg.

**Shift (eq. 9-15).** On a seabed ``psi(x) = 0`` the total change of ``psi`` at a beam's foot
vanishes, which linearised between two images gives one equation per beam,

    grad psi(x_k^ij) . (dX + de^ij L_k^ij + e_k^ij dL^ij) = 0,                   (eq. 11-12)

stacked into ``A dX = B`` (eq. 14: the rows of A are ``(dpsi/dx, dpsi/dy, dpsi/dz)``; the printed
matrix repeats d/dx, a typo) and solved by least squares (eq. 15). ``de`` is eq. 10 with the
printed typo corrected: the d(theta) term of ``de^Y`` is ``+cos(g) cos(t) dtheta``. The position
then dead-reckons as ``X_{k+1} = X_k + dX`` (eq. 16, :func:`seabed_track`).

**Slopes (Appendix A).** The seabed's gradient at the beam feet is not known; it is estimated
from the image itself: the feet ``x^ij = X_k + L^ij e`` (with the *estimated* position) are
fitted by ``psi(x) = z + sum_l p_l psi_l(x)`` in least squares. The coefficient of ``z`` is
fixed to 1 (Appendix A's minimisation without that constraint is solved by ``p = 0``). The
basis (:class:`SlopeBasis`) is the harmonic one of eq. 24 (a constant plus sines and cosines of
the known periods), a plane or a quadratic. Both bases are invariant under a shift of the
points, so an error in the estimated position does not change the slopes at the feet.

**Beam attitude between two images (reading notes).** The text takes ``L_{k+1}`` with the
attitude of ``u_{k+1}``, which needs the estimate that needs ``L_{k+1}``. Two readings are offered
(:data:`BeamAttitude`): ``"one_attitude"``: both images of a shift are taken at the attitude of
``u_k`` (the second one just before the vehicle turns; ``de = 0``); ``"turning"``: the second
image is taken at the next attitude and eq. 10 accounts for the turn (linearised, or exactly with
``delta_e="exact"``).

**Beams without echo** (no seabed within the sonar's range) are masked: a beam is used when it
has an echo in both images (the slope fit uses every echo of image k). A shift with fewer usable
beams than the fit needs is not produced (``ok = False``; the shift is zero, or the commanded
displacement when given, and the covariance ``fallback_var_m2 * I``, never NaN).

**Conditioning.** Eq. 15 is solved by SVD; singular values of A below ``rcond`` (relative) or
:data:`SINGULAR_FLOOR` (absolute) count as zero: the shift has no component along them and
the covariance states them unobserved, and ``rank`` says how many directions were observed.

**Error covariance.** Eq. 15 comes with no covariance. :func:`shift_estimate` offers
``"residual"``: the least-squares covariance ``s^2 (A^T A)^-1`` with ``s^2`` the residual variance
of eq. 13 (``RSS / (m - 3)``), floored by the range-noise propagation; and ``"range_noise"``: the
propagation of independent range noise ``sigma_range_m`` through B alone (a lower bound that
ignores slope and linearisation errors, which dominate on the seed's seabed). Directions the
beams do not observe (a plane seabed leaves the two directions along it unobserved) get the
variance ``fallback_var_m2``; the shift has no component along them (minimum-norm solution).

**Implementation.** The per-path arithmetic of :func:`fit_slopes` and :func:`shift_estimate` (the
basis, the fit's normal equations, eq. 12-15 and the covariance) is compiled by numba
(:mod:`nav.seabed.kernel`, at first use, cached beside the module); numpy keeps the input checks,
the beam vectors (eq. 8, 10) and the rare branches (fits whose scaled Gram matrix may have a
condition number above :data:`FIT_C_CONDITION`, ``rcond < 1e-8``). The numpy implementation it
replaced is the tests' reference (``tests/nav/seabed_reference.py``); the two agree to rounding
times the condition numbers of the fit and of eq. 15 (about 1e-11 relative on seed 004's images),
not bit for bit.

References:
    Seed 004 (Miller, Miller & Miller 2019), eq. 8-16 and Appendix A (A1).
"""

from nav.seabed.fit import (
    FIT_C_CONDITION,
    FIT_MAX_FUNCTIONS,
    FIT_RCOND,
    GRAM_CONDITION,
    fit_slopes,
)
from nav.seabed.geometry import BeamGeometry, SlopeBasis, check_basis
from nav.seabed.shift import (
    SINGULAR_FLOOR,
    BeamAttitude,
    CovarianceKind,
    ShiftEstimate,
    seabed_track,
    shift_estimate,
)

__all__ = [
    "FIT_C_CONDITION",
    "FIT_MAX_FUNCTIONS",
    "FIT_RCOND",
    "GRAM_CONDITION",
    "SINGULAR_FLOOR",
    "BeamAttitude",
    "BeamGeometry",
    "CovarianceKind",
    "ShiftEstimate",
    "SlopeBasis",
    "check_basis",
    "fit_slopes",
    "seabed_track",
    "shift_estimate",
]
