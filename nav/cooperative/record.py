"""What a team of vehicles measured over a batch of runs, on one sample grid: the input of
:func:`nav.cooperative.team_tracks`.

Built by the experiments (the kinematic team, the swarm mission) from their devices; it holds no
truth. Index 0 of the vehicle axis is the leader (on USBL/GPS fixes, its clock the team's time).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]

RangeKind = Literal["owtt", "twtt"]


def _fail(name: str, msg: str) -> NavInputError:
    return NavInputError(f"TeamRecord.{name} {msg}")


@dataclass(frozen=True)
class TeamRecord:
    """One batch of n runs of v vehicles on k samples, with f position fixes and m ranges.

    Positions are (east, north) in m (world ENU), depths positive down in m, times in s. A range
    event e: ``range_sender[e]`` transmitted at its local time ``range_tx_local_s`` (during
    sample interval ending at or after ``range_tx_tick``: the sample at or before the
    transmission), ``range_receiver[e]`` stamped the arrival at its local time
    ``range_rx_local_s`` and applies it at sample ``range_rx_tick`` (at or after the reception);
    ``range_m = c_nom (rx_local - tx_local)`` for OWTT. For TWTT the receiver is the interrogator
    (both stamps in its clock) and the sender the responder.

    Attributes:
        t_s: sample times, shape (k,), s, strictly increasing (true time).
        dr_step_m: each vehicle's dead-reckoned displacement over ground from sample q to q + 1,
            shape (n, v, k - 1, 2), m.
        dr_step_cov_m2: its covariance, shape (n, v, k - 1, 2, 2), m^2.
        depth_m: measured depth, shape (n, v, k), m.
        start_m: each vehicle's initial position estimate, shape (n, v, 2), m.
        start_cov_m2: its covariance, shape (n, v, 2, 2), m^2.
        fix_tick: sample of each fix, shape (f,).
        fix_vehicle: vehicle of each fix, shape (f,).
        fix_m: the fixes, shape (n, f, 2), m (anything where not present).
        fix_cov_m2: their covariances, shape (n, f, 2, 2), m^2.
        fix_present: whether each fix was received, shape (n, f).
        range_sender: shape (m,).
        range_receiver: shape (m,).
        range_tx_tick: shape (m,).
        range_rx_tick: shape (m,), ``>= range_tx_tick``.
        range_m: the ranges, shape (n, m), m (anything where not present).
        range_tx_local_s: transmission stamps in the sender's clock (TWTT: the interrogator's
            transmission in its own clock), shape (n, m), s.
        range_rx_local_s: reception stamps in the receiver's clock, shape (n, m), s.
        range_present: whether each range was received, shape (n, m).
        kind: ``"owtt"`` or ``"twtt"``.
        sound_speed_m_s: the nominal sound speed that made the ranges, m/s.
        sigma_range_m: the ranges' standard deviation (detection and stamp noise), m.
    """

    t_s: Array
    dr_step_m: Array
    dr_step_cov_m2: Array
    depth_m: Array
    start_m: Array
    start_cov_m2: Array
    fix_tick: NDArray[np.intp]
    fix_vehicle: NDArray[np.intp]
    fix_m: Array
    fix_cov_m2: Array
    fix_present: NDArray[np.bool_]
    range_sender: NDArray[np.intp]
    range_receiver: NDArray[np.intp]
    range_tx_tick: NDArray[np.intp]
    range_rx_tick: NDArray[np.intp]
    range_m: Array
    range_tx_local_s: Array
    range_rx_local_s: Array
    range_present: NDArray[np.bool_]
    kind: RangeKind = "owtt"
    sound_speed_m_s: float = 1500.0
    sigma_range_m: float = 0.1

    def __post_init__(self) -> None:
        ints = {"fix_tick", "fix_vehicle", "range_sender", "range_receiver"}
        ints |= {"range_tx_tick", "range_rx_tick"}
        bools = {"fix_present", "range_present"}
        for f in fields(self):
            if f.name in ("kind", "sound_speed_m_s", "sigma_range_m"):
                continue
            a = np.asarray(getattr(self, f.name))
            if f.name in ints:
                if a.size and not np.issubdtype(a.dtype, np.integer):
                    raise _fail(f.name, f"must hold integers, not dtype {a.dtype}")
                a = a.astype(np.intp)
            elif f.name in bools:
                if a.dtype != np.bool_:
                    raise _fail(f.name, f"must hold booleans, not dtype {a.dtype}")
            else:
                a = a.astype(float)
            object.__setattr__(self, f.name, a)
        self._check_shapes()
        self._check_values()

    def _check_shapes(self) -> None:
        if self.t_s.ndim != 1 or len(self.t_s) < 2:
            raise _fail("t_s", f"must have shape (k,) with k >= 2, not {self.t_s.shape}")
        if self.start_m.ndim != 3 or self.start_m.shape[1] < 1:
            raise _fail("start_m", f"must have shape (n, v, 2), not {self.start_m.shape}")
        n, v, k = self.start_m.shape[0], self.start_m.shape[1], len(self.t_s)
        f, m = len(np.atleast_1d(self.fix_tick)), len(np.atleast_1d(self.range_sender))
        want = {
            "start_m": (n, v, 2),
            "start_cov_m2": (n, v, 2, 2),
            "dr_step_m": (n, v, k - 1, 2),
            "dr_step_cov_m2": (n, v, k - 1, 2, 2),
            "depth_m": (n, v, k),
            "fix_tick": (f,),
            "fix_vehicle": (f,),
            "fix_m": (n, f, 2),
            "fix_cov_m2": (n, f, 2, 2),
            "fix_present": (n, f),
            "range_sender": (m,),
            "range_receiver": (m,),
            "range_tx_tick": (m,),
            "range_rx_tick": (m,),
            "range_m": (n, m),
            "range_tx_local_s": (n, m),
            "range_rx_local_s": (n, m),
            "range_present": (n, m),
        }
        for name, shape in want.items():
            got = np.shape(getattr(self, name))
            if got != shape:
                raise _fail(
                    name,
                    f"must have shape {shape} (n = {n} runs, v = {v} vehicles, k = {k} samples, "
                    f"f = {f} fixes, m = {m} ranges), not {got}",
                )

    def _check_values(self) -> None:
        if self.kind not in ("owtt", "twtt"):
            raise _fail("kind", f"must be 'owtt' or 'twtt', not {self.kind!r}")
        for name in ("sound_speed_m_s", "sigma_range_m"):
            val = getattr(self, name)
            if not (isinstance(val, (int, float)) and np.isfinite(val) and val > 0):
                raise _fail(name, f"must be a finite number > 0, not {val!r}")
        if not (np.all(np.isfinite(self.t_s)) and np.all(np.diff(self.t_s) > 0)):
            raise _fail("t_s", "must be finite and strictly increasing")
        for name in ("dr_step_m", "dr_step_cov_m2", "depth_m", "start_m", "start_cov_m2"):
            if not np.all(np.isfinite(getattr(self, name))):
                raise _fail(name, "must be finite")
        k, v = len(self.t_s), self.n_vehicles
        for name in ("fix_tick", "range_tx_tick", "range_rx_tick"):
            a = getattr(self, name)
            if a.size and (a.min() < 0 or a.max() >= k):
                raise _fail(name, f"must lie in 0..{k - 1} (the samples), not {a.min()}..{a.max()}")
        for name in ("fix_vehicle", "range_sender", "range_receiver"):
            a = getattr(self, name)
            if a.size and (a.min() < 0 or a.max() >= v):
                raise _fail(
                    name, f"must lie in 0..{v - 1} (the vehicles), not {a.min()}..{a.max()}"
                )
        if np.any(self.range_sender == self.range_receiver):
            e = int(np.flatnonzero(self.range_sender == self.range_receiver)[0])
            raise _fail("range_receiver", f"must differ from range_sender (event {e})")
        if np.any(self.range_rx_tick < self.range_tx_tick):
            e = int(np.flatnonzero(self.range_rx_tick < self.range_tx_tick)[0])
            raise _fail("range_rx_tick", f"must be >= range_tx_tick (event {e})")
        for name, present in (
            ("fix_m", self.fix_present[..., None]),
            ("fix_cov_m2", self.fix_present[..., None, None]),
            ("range_m", self.range_present),
            ("range_tx_local_s", self.range_present),
            ("range_rx_local_s", self.range_present),
        ):
            if not np.all(np.isfinite(getattr(self, name)) | ~present):
                raise _fail(name, "must be finite where present")
        if np.any(self.fix_present & ~_positive_definite(self.fix_cov_m2)):
            raise _fail("fix_cov_m2", "must be positive definite where present")
        if not np.all(_positive_semidefinite(self.start_cov_m2)):
            raise _fail("start_cov_m2", "must be symmetric positive semi-definite")
        if not np.all(_positive_semidefinite(self.dr_step_cov_m2)):
            raise _fail("dr_step_cov_m2", "must be symmetric positive semi-definite")

    @property
    def n_runs(self) -> int:
        """n."""
        return int(self.start_m.shape[0])

    @property
    def n_vehicles(self) -> int:
        """v (index 0 the leader)."""
        return int(self.start_m.shape[1])

    @property
    def n_samples(self) -> int:
        """k."""
        return len(self.t_s)

    def velocity_m_s(self) -> Array:
        """Each vehicle's dead-reckoned horizontal velocity over each sample interval, shape
        (n, v, k - 1, 2), m/s (the step over its duration)."""
        return self.dr_step_m / np.diff(self.t_s)[None, None, :, None]


def _positive_definite(C: Array) -> NDArray[np.bool_]:
    c = np.nan_to_num(C)
    det = c[..., 0, 0] * c[..., 1, 1] - c[..., 0, 1] * c[..., 1, 0]
    sym = np.abs(c[..., 0, 1] - c[..., 1, 0]) <= 1e-9 * (
        np.abs(c[..., 0, 0]) + np.abs(c[..., 1, 1])
    )
    return (c[..., 0, 0] > 0) & (det > 0) & sym


def _positive_semidefinite(C: Array) -> NDArray[np.bool_]:
    det = C[..., 0, 0] * C[..., 1, 1] - C[..., 0, 1] * C[..., 1, 0]
    scale = np.abs(C[..., 0, 0]) + np.abs(C[..., 1, 1])
    sym = np.abs(C[..., 0, 1] - C[..., 1, 0]) <= 1e-9 * scale + 1e-300
    return (C[..., 0, 0] >= 0) & (C[..., 1, 1] >= 0) & (det >= -1e-12 * scale**2) & sym
