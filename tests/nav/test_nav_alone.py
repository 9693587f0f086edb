"""Each paper's method comes from ``nav`` alone (issue 22, check 3): in an interpreter where
``tasks``, ``bauv_sim``, MuJoCo, dm_control, matplotlib and rerun cannot be imported, every module
of ``nav`` imports, and seed 003's GA2 fix and seed 004's UPMF step run on inputs made by hand,
giving the answers worked out here."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

BLOCKED = ("tasks", "bauv_sim", "mujoco", "dm_control", "matplotlib", "rerun", "pyarrow", "scipy")

PROBE = r"""
import importlib, importlib.abc, json, pkgutil, sys

BLOCKED = set(%(blocked)r)

class Unimportable(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ImportError(f"{name} is made unimportable for this test")
        return None

sys.meta_path.insert(0, Unimportable())

import numpy as np
import nav

out = {"modules": []}
for info in pkgutil.walk_packages(nav.__path__, "nav."):
    importlib.import_module(info.name)
    out["modules"].append(info.name)

# each paper's method, from its place in nav
from nav.usbl import passage_ekf  # seed 000
from nav.surfacing import cp1, cp2  # seed 001
from nav.relative import GaOptions, ga_fix  # seed 003
from nav.bearings import bank, filters  # seed 004
from nav.seabed import shift_estimate  # seed 004, seabed

# seed 003, GA2 (eq. 4) on a hand-made geometry: the segment's start at the origin, the DR end
# 100 m north of it, the leader 150 m north, the range 40 m. The candidates lie on the circle of
# 40 m around the leader; the one due south of the leader, (0, 110), has a zero bearing residual
# and the least distance residual (10 m) of the circle, so it is the fix.
fix = ga_fix(
    "ga2",
    start=np.array([[0.0, 0.0]]),
    dr_end=np.array([[0.0, 100.0]]),
    leader=np.array([[0.0, 150.0]]),
    range_m=np.array([40.0]),
    dr_cov=np.array([np.diag([4.0, 4.0])]),
    options=GaOptions(),
)
out["ga2"] = fix.position[0].tolist()
out["ga2_valid"] = bool(fix.valid[0])

# seed 004, one UPMF step of the filter bank on hand-made inputs: a vehicle at (10, 20, -30) m,
# two beacons, noise-free tangents (tan phi = dy/dx, tan lambda = dz/rho from the vehicle to the
# beacon, eq. 17, worked out here). The pseudo-measurements (eq. 19-20) are then exact linear
# equations in the position. Eq. 21 as printed (the gain's Psi1 at the measured angles), from a
# prediction 7 m off with an uninformative covariance, is their least-squares solution: the
# truth. The unbiased form (the gain's Psi1 at the predicted angles) gives the truth from a
# prediction at the truth.
truth = np.array([10.0, 20.0, -30.0])
beacons = np.array([[200.0, 60.0, 0.0], [150.0, -90.0, -5.0]])
d = beacons - truth
rho = np.hypot(d[:, 0], d[:, 1])
y = np.stack([d[:, 1] / d[:, 0], d[:, 2] / rho], axis=-1)[None]  # (1, B, 2)
x0 = (truth + np.array([4.0, -5.0, 3.0]))[None]
p0 = (1e8 * np.eye(3))[None]
shift = filters.PredictedShift(np.zeros((1, 3)), np.zeros((1, 3, 3)))
res = bank.step(
    "UPMF", 1, x0, p0, shift, y, np.ones((1, 2), bool), beacons,
    bank.BankOptions(s_eps=1e-14 * np.eye(2), upmf_form="printed"),
)
out["upmf"] = res.x_hat[0].tolist()
res = bank.step(
    "UPMF", 1, truth[None], p0, shift, y, np.ones((1, 2), bool), beacons,
    bank.BankOptions(s_eps=1e-14 * np.eye(2)),
)
out["upmf_unbiased"] = res.x_hat[0].tolist()
out["loaded"] = sorted(m for m in sys.modules if m.split(".")[0] in BLOCKED)
print(json.dumps(out))
"""


def _probe() -> dict:
    code = PROBE % {"blocked": BLOCKED}
    res = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=False
    )
    assert res.returncode == 0, res.stderr[-3000:]
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_each_papers_method_runs_from_nav_alone():
    out = _probe()
    # every paper's place in nav imported, and nothing blocked was loaded
    for pkg in ("nav.usbl", "nav.surfacing", "nav.relative", "nav.bearings", "nav.seabed"):
        assert pkg in out["modules"], pkg
    assert out["loaded"] == []
    # seed 003's GA2: the point of the range circle worked out above
    assert out["ga2_valid"]
    assert abs(out["ga2"][0]) < 1e-6 and abs(out["ga2"][1] - 110.0) < 1e-6, out["ga2"]
    # seed 004's UPMF step: the truth, from a prediction 7 m off (as printed) and at the truth
    # (unbiased)
    for key in ("upmf", "upmf_unbiased"):
        for got, want in zip(out[key], (10.0, 20.0, -30.0), strict=True):
            assert abs(got - want) < 1e-6, (key, out[key])
