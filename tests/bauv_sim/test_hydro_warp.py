"""The Warp kernel of the native formulation (``benchmarks/gpu_hydro_warp.py``) against
:func:`bauv_sim.hydro_native.vehicle_force` at random states, on Warp's CPU device; skipped where
``warp-lang`` is not installed (it is not a dependency of the project)."""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from bauv_sim import build, hydro, hydro_native

from .test_hydrodynamics import _randomise

pytest.importorskip("warp")
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import gpu_hydro_warp


@pytest.fixture(autouse=True)
def _no_callback_left():
    """The callback of a native model makes every later compilation of the process fail
    (hydro_native.compiling): none is left installed for the next test."""
    yield
    hydro_native.uninstall()


def test_warp_kernel_equals_the_callback_at_random_states_in_accelerating_water():
    phys = build.build_physics(build.SceneConfig(), hydrodynamics="native")
    m = phys.model.ptr
    v = hydro_native.native_of(m).vehicles[0]
    inst = hydro.plugin_instances(m)[v.prefix]
    rng = np.random.default_rng(11)
    datas, want = [], []
    for k in range(4):
        d = mujoco.MjData(m)
        _randomise(m, d, rng)
        w = rng.normal(0, 0.3, 3)
        hydro.set_water(m, d, inst, w, rng.normal(0, 0.2, 3) if k % 2 else np.zeros(3))
        mujoco.mj_forward(m, d)
        d.qacc[:] = rng.normal(0, 1.0, m.nv)  # the lagged acceleration
        mujoco.mj_comVel(m, d)
        datas.append(d)
        want.append(hydro_native.vehicle_force(m, d, v))
    got = gpu_hydro_warp.forces(m, datas, v)
    for g, wv in zip(got, want, strict=True):
        scale = np.abs(wv).max()
        assert scale > 10.0
        assert np.allclose(g, wv, rtol=0, atol=2e-5 * scale), np.abs(g - wv).max() / scale
