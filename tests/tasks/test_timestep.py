"""The timestep validation script's measures (``models/bauv/tools/timestep.py``) against analytic
cases."""

import math

import numpy as np
import pytest

from tests.model_tools import tool

ts = tool("timestep")


def test_rise_time_of_a_first_order_step_is_tau_ln_9():
    tau = 3.0
    t = np.linspace(0.0, 30.0, 30001)
    y = 10.0 + 5.0 * (1.0 - np.exp(-t / tau))  # 10 m -> 15 m
    assert ts.rise_time_s(t, y, 10.0, 15.0) == pytest.approx(tau * math.log(9.0), rel=1e-6)
    # a downward step, sampled coarsely: the crossings are interpolated
    t = np.arange(0.0, 30.0, 0.2)
    y = 15.0 - 5.0 * (1.0 - np.exp(-t / tau))
    assert ts.rise_time_s(t, y, 15.0, 10.0) == pytest.approx(tau * math.log(9.0), rel=1e-3)


def test_rise_time_of_a_ramp_and_of_a_response_that_never_arrives():
    t = np.linspace(0.0, 10.0, 11)
    assert ts.rise_time_s(t, t / 10.0, 0.0, 1.0) == pytest.approx(8.0)
    assert ts.rise_time_s(t, 0.5 * t / 10.0, 0.0, 1.0) == math.inf


def test_a_preset_holds_only_within_every_threshold():
    ref = ts.TimestepResult(0.001, 1.0, 13.0, 7.7, 7.5, 19.7, 1.7, -0.116)
    fields = list(ts.THRESHOLDS)
    for name in fields:
        kind, bound = ts.THRESHOLDS[name]
        x = getattr(ref, name)
        for factor, ok in ((0.9, True), (1.1, False)):
            step = factor * bound * (abs(x) if kind == "relative" else 1.0)
            res = ts.TimestepResult(**{**ref.__dict__, "timestep_s": 0.004, name: x + step})
            verdict = ts.holds(res, ref)
            assert verdict[name] is ok, (name, factor)
            assert all(v for k, v in verdict.items() if k != name)
    table = ts.render([ref, ts.TimestepResult(**{**ref.__dict__, "timestep_s": 0.004})])
    assert "4 ms holds" in table


def test_flatten_keeps_every_finite_number_by_path():
    doc = {"a": {"b": [1.5, {"c": 2}], "d": True, "e": None, "f": float("nan")}, "g": "x"}
    assert ts.flatten(doc) == {"/a/b[0]": 1.5, "/a/b[1]/c": 2.0}
