"""The shared error vocabulary of every sensor.

A measured scalar is built from its true value as

    m = (1 + scale_factor) * x + bias + sector_bias[sector(ref)] + deviation(ref) + walk(t)
        + noise + outlier

and is then dropped (absent) with ``dropout_probability``:

* ``noise``: gaussian N(0, sigma^2), or uniform on [-k sigma, +k sigma] as seed 000 draws it
  (k = ``uniform_k`` = 3; its standard deviation is k sigma / sqrt(3));
* ``bias``: constant;
* ``sector_bias``: four constants chosen by the 90-degree sector of a reference angle (the true
  course), as seed 003's course errors;
* ``deviation``: compass deviation A + B sin(ref) + C cos(ref) + D sin(2 ref) + E cos(2 ref);
* ``scale_factor``: relative error (0.01 = reads 1 % high);
* ``walk``: a random walk with ``random_walk`` per sqrt(second), starting at 0;
* ``outlier``: with ``outlier_probability``, a gross error N(0, outlier_sigma^2).

Units are SI in :class:`ErrorModel`; configuration classes (``AngleErrorConfig``,
``LengthErrorConfig``, ``SpeedErrorConfig``) carry the unit in every field name and convert.

Each error component draws from its own stream (:mod:`bauv_sim.rng`, path ``(*sensor path,
component)``), so switching outliers on does not change the noise, and the numbers of run ``i`` do
not depend on the other runs in the batch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, create_model

from bauv_sim import rng as rng_mod
from bauv_sim.config import Config
from bauv_sim.frames import wrap_2pi

Distribution = Literal["gaussian", "uniform"]


@dataclass(frozen=True)
class ErrorModel:
    """Error model of one scalar measurement, SI units (see the module docstring).

    Attributes:
        distribution: ``"gaussian"`` or ``"uniform"``.
        sigma: noise scale (standard deviation if gaussian; the uniform half-width is
            ``uniform_k * sigma``).
        uniform_k: half-width of the uniform draw in sigmas.
        bias: constant error.
        sector_bias: four constants by 90-degree sector of the reference angle, or ``None``.
        deviation: ``(A, B, C, D, E)`` of the deviation curve of the reference angle, or ``None``.
        scale_factor: relative scale error.
        random_walk: random-walk intensity, unit per sqrt(s).
        outlier_probability: probability of a gross error per sample.
        outlier_sigma: standard deviation of a gross error.
        dropout_probability: probability that a sample is not produced.
    """

    distribution: Distribution = "gaussian"
    sigma: float = 0.0
    uniform_k: float = 3.0
    bias: float = 0.0
    sector_bias: tuple[float, float, float, float] | None = None
    deviation: tuple[float, float, float, float, float] | None = None
    scale_factor: float = 0.0
    random_walk: float = 0.0
    outlier_probability: float = 0.0
    outlier_sigma: float = 0.0
    dropout_probability: float = 0.0

    @property
    def noise_std(self) -> float:
        """Standard deviation of the noise term alone."""
        if self.distribution == "uniform":
            return self.uniform_k * self.sigma / math.sqrt(3.0)
        return self.sigma

    def needs_reference(self) -> bool:
        """Whether :meth:`ErrorProcess.apply` needs a reference angle."""
        return self.sector_bias is not None or self.deviation is not None


class ErrorProcess:
    """An :class:`ErrorModel` applied to a batch of runs, with its streams and random-walk state.

    Call :meth:`apply` once with a whole time series (kinematic worlds) or repeatedly with
    consecutive samples (the physics loop): the random walk continues across calls.

    Args:
        model: the error model.
        seed: batch seed.
        runs: run indices of the batch rows, length n.
        path: stream path of this quantity, e.g. ``("sensor", "usbl", "range")``.
    """

    def __init__(self, model: ErrorModel, seed: int, runs: tuple[int, ...], path: tuple[str, ...]):
        self.model = model
        self.seed = seed
        self.runs = tuple(runs)
        self.path = tuple(path)
        self._gens: dict[str, rng_mod.RunStreams] = {}
        self._walk = np.zeros(len(self.runs))
        self._t_last: float | None = None

    def _draw(self, component: str, k: int, fn: str, *args: Any) -> NDArray[np.float64]:
        gen = self._gens.get(component)
        if gen is None:
            gen = rng_mod.RunStreams(self.seed, self.runs, *self.path, component)
            self._gens[component] = gen
        return gen.draw(fn, k, *args)

    def apply(
        self,
        true_value: NDArray[np.float64],
        t_s: NDArray[np.float64],
        reference_rad: NDArray[np.float64] | None = None,
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Measure true values.

        Args:
            true_value: true values, shape (n, k), SI; n = len(runs), k samples in time order.
            t_s: sample times, shape (k,), s (for the random walk).
            reference_rad: reference angle for sector bias and deviation, shape (n, k), rad.

        Returns:
            ``(measured, produced)``: shape (n, k) floats and booleans. Where ``produced`` is False
            the measurement does not exist (its value is meaningless, not NaN).
        """
        m = self.model
        x = np.asarray(true_value, dtype=float)
        n, k = x.shape
        if n != len(self.runs):
            raise ValueError(f"true_value has {n} rows for {len(self.runs)} runs")
        out = x * (1.0 + m.scale_factor) + m.bias
        if m.needs_reference():
            if reference_rad is None:
                raise ValueError("this error model needs a reference angle")
            ref = np.asarray(reference_rad, dtype=float)
            if m.sector_bias is not None:
                sector = np.minimum((wrap_2pi(ref) // (np.pi / 2)).astype(int), 3)
                out = out + np.asarray(m.sector_bias)[sector]
            if m.deviation is not None:
                a, b, c, d, e = m.deviation
                out = out + a + b * np.sin(ref) + c * np.cos(ref)
                out = out + d * np.sin(2 * ref) + e * np.cos(2 * ref)
        if m.random_walk > 0:
            t = np.asarray(t_s, dtype=float)
            prev = t[0] if self._t_last is None else self._t_last
            dt = np.diff(np.concatenate([[prev], t]))
            steps = self._draw("walk", k, "standard_normal") * (m.random_walk * np.sqrt(dt))
            walk = self._walk[:, None] + np.cumsum(steps, axis=1)
            self._walk = walk[:, -1].copy()
            self._t_last = float(t[-1])
            out = out + walk
        if m.sigma > 0:
            if m.distribution == "uniform":
                h = m.uniform_k * m.sigma
                out = out + self._draw("noise", k, "uniform", -h, h)
            else:
                out = out + m.sigma * self._draw("noise", k, "standard_normal")
        if m.outlier_probability > 0:
            hit = self._draw("outlier", k, "random") < m.outlier_probability
            size = m.outlier_sigma * self._draw("outlier_size", k, "standard_normal")
            out = out + np.where(hit, size, 0.0)
        produced = np.ones((n, k), dtype=bool)
        if m.dropout_probability > 0:
            produced = self._draw("dropout", k, "random") >= m.dropout_probability
        return out, produced

    def apply_one(self, true_value: float, t_s: float) -> tuple[float, bool]:
        """:meth:`apply` of one run and one sample with Python floats, for per-tick devices: the
        same operations in the same order on the same draws, so the same bits (tested). A model
        that needs a reference angle (sector bias, deviation) is measured with :meth:`apply`.

        Args:
            true_value: the true value, SI.
            t_s: the sample's time, s (for the random walk).

        Returns:
            ``(measured, produced)``; where ``produced`` is False the measurement does not exist.

        Raises:
            ValueError: if the process is not of one run, or its model needs a reference angle.
        """
        m = self.model
        if len(self.runs) != 1:
            raise ValueError(f"apply_one is for one run; this process has {len(self.runs)}")
        if m.needs_reference():
            raise ValueError("this error model needs a reference angle: measure with apply()")
        out = float(true_value) * (1.0 + m.scale_factor) + m.bias
        if m.random_walk > 0:
            t = float(t_s)
            prev = t if self._t_last is None else self._t_last
            step = self._draw("walk", 1, "standard_normal")[0, 0] * (
                m.random_walk * math.sqrt(t - prev)
            )
            walk = float(self._walk[0] + step)
            self._walk = np.array([walk])
            self._t_last = t
            out = out + walk
        if m.sigma > 0:
            if m.distribution == "uniform":
                h = m.uniform_k * m.sigma
                out = out + self._draw("noise", 1, "uniform", -h, h)[0, 0]
            else:
                out = out + m.sigma * self._draw("noise", 1, "standard_normal")[0, 0]
        if m.outlier_probability > 0:
            hit = self._draw("outlier", 1, "random")[0, 0] < m.outlier_probability
            size = m.outlier_sigma * self._draw("outlier_size", 1, "standard_normal")[0, 0]
            out = out + (size if hit else 0.0)
        produced = True
        if m.dropout_probability > 0:
            produced = bool(self._draw("dropout", 1, "random")[0, 0] >= m.dropout_probability)
        return float(out), produced


_COMMON_DOC = """Error model of one measured quantity; the unit is in every field name.

See :mod:`bauv_sim.sensors.errors` for how the terms combine."""


class _ErrorConfigBase(Config):
    distribution: Distribution = Field(
        "gaussian", description="noise distribution: gaussian, or uniform on +-uniform_k sigma"
    )
    uniform_k: float = Field(3.0, gt=0, description="uniform half-width in sigmas (seed 000: 3)")
    scale_factor: float = Field(0.0, gt=-1, lt=1, description="relative scale error")
    outlier_probability: float = Field(0.0, ge=0, le=1, description="gross-error probability")
    dropout_probability: float = Field(0.0, ge=0, lt=1, description="probability of no sample")

    unit_name: ClassVar[str] = ""
    unit_to_si: ClassVar[float] = 1.0

    def to_model(self) -> ErrorModel:
        """The SI :class:`ErrorModel`."""
        u, s = self.unit_name, self.unit_to_si
        d = self.model_dump()

        def si(name: str) -> Any:
            v = d.get(f"{name}_{u}")
            return None if v is None else v * s

        def si_tuple(name: str) -> Any:
            v = d.get(f"{name}_{u}")
            return None if v is None else tuple(float(x) * s for x in v)

        return ErrorModel(
            distribution=self.distribution,
            sigma=si("sigma"),
            uniform_k=self.uniform_k,
            bias=si("bias"),
            sector_bias=si_tuple("sector_bias"),
            deviation=si_tuple("deviation") if f"deviation_{u}" in d else None,
            scale_factor=self.scale_factor,
            random_walk=d[f"random_walk_{u}_per_sqrt_s"] * s,
            outlier_probability=self.outlier_probability,
            outlier_sigma=si("outlier_sigma"),
            dropout_probability=self.dropout_probability,
        )


def _error_config(name: str, unit: str, to_si: float, angle: bool) -> type[_ErrorConfigBase]:
    fields: dict[str, Any] = {
        f"sigma_{unit}": (float, Field(0.0, ge=0, description=f"noise sigma, {unit}")),
        f"bias_{unit}": (float, Field(0.0, description=f"constant bias, {unit}")),
        f"sector_bias_{unit}": (
            tuple[float, float, float, float] | None,
            Field(None, description=f"bias by 90-deg sector of the true course, {unit}"),
        ),
        f"random_walk_{unit}_per_sqrt_s": (
            float,
            Field(0.0, ge=0, description=f"random-walk drift, {unit}/sqrt(s)"),
        ),
        f"outlier_sigma_{unit}": (
            float,
            Field(0.0, ge=0, description=f"gross-error sigma, {unit}"),
        ),
    }
    if angle:
        fields[f"deviation_{unit}"] = (
            tuple[float, float, float, float, float] | None,
            Field(None, description=f"compass deviation coefficients A..E, {unit}"),
        )
    cls = create_model(name, __base__=_ErrorConfigBase, __doc__=_COMMON_DOC, **fields)
    cls.unit_name = unit
    cls.unit_to_si = to_si
    return cls


if TYPE_CHECKING:
    # What _error_config builds, spelt out for type checkers, which cannot see the fields of a
    # model made by create_model (tests/test_typing.py checks these match the runtime models).
    _Sector = tuple[float, float, float, float]

    class AngleErrorConfig(_ErrorConfigBase):
        sigma_deg: float = 0.0
        bias_deg: float = 0.0
        sector_bias_deg: _Sector | None = None
        random_walk_deg_per_sqrt_s: float = 0.0
        outlier_sigma_deg: float = 0.0
        deviation_deg: tuple[float, float, float, float, float] | None = None

    class LengthErrorConfig(_ErrorConfigBase):
        sigma_m: float = 0.0
        bias_m: float = 0.0
        sector_bias_m: _Sector | None = None
        random_walk_m_per_sqrt_s: float = 0.0
        outlier_sigma_m: float = 0.0

    class SpeedErrorConfig(_ErrorConfigBase):
        sigma_m_s: float = 0.0
        bias_m_s: float = 0.0
        sector_bias_m_s: _Sector | None = None
        random_walk_m_s_per_sqrt_s: float = 0.0
        outlier_sigma_m_s: float = 0.0

else:
    AngleErrorConfig = _error_config("AngleErrorConfig", "deg", math.pi / 180.0, angle=True)
    """Error of an angle (course, heading, azimuth, elevation, bearing); fields in degrees."""
    LengthErrorConfig = _error_config("LengthErrorConfig", "m", 1.0, angle=False)
    """Error of a length (range, depth, position); fields in metres."""
    SpeedErrorConfig = _error_config("SpeedErrorConfig", "m_s", 1.0, angle=False)
    """Error of a speed; fields in metres per second."""
