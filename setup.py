"""Build of the three C libraries; everything else is declared in ``pyproject.toml``.

* The MuJoCo engine plugin ``bauv.hydro`` (``bauv_sim/plugin/hydro.c``): a shared library that
  MuJoCo loads with ``mj_loadPluginLibrary`` (``bauv_sim.hydro.load_plugin``); it is compiled
  against the headers of the MuJoCo release pinned in ``pyproject.toml`` (its ``mjModel``/``mjData``
  layouts) and linked to that release's library, found in the ``mujoco`` package of the build
  environment.
* The harmonic seabed's ray march (``bauv_sim/sensors/harmonic_rays.c``): a plain C library (no
  Python API) that ``bauv_sim.sensors.multibeam`` loads with ``ctypes`` through ``nav.clib``. No
  fast-math and no FMA contraction (its ranges are those of the numpy code it replaced, to
  rounding, on any machine), no ``-march`` (the build runs on any x86_64).
* The seabed shift's per-path arithmetic (``nav/seabed/seabed_shift.c``: Appendix A's slope fit
  and eq. 15 of seed 004 with its covariance): a plain C library that ``nav.seabed`` loads with
  ``ctypes`` through ``nav.clib``, compiled as the ray march.

The two ctypes libraries include the shared header ``nav/clib.h`` (their entry points' argument
structs, mirrored in ``nav/clib.py``, which checks the layout when it loads them).
"""

from __future__ import annotations

import glob
import os

from setuptools import Extension, setup


def _mujoco() -> tuple[str, str, str]:
    import mujoco

    root = os.path.dirname(mujoco.__file__)
    libs = sorted(glob.glob(os.path.join(root, "libmujoco.so*")))
    if not libs:
        raise RuntimeError(f"no libmujoco.so in {root}: is the mujoco wheel complete?")
    return os.path.join(root, "include"), root, os.path.basename(libs[-1])


_include, _libdir, _lib = _mujoco()

setup(
    ext_modules=[
        Extension(
            "bauv_sim.plugin._bauv_hydro",
            sources=["bauv_sim/plugin/hydro.c"],
            include_dirs=[_include],
            library_dirs=[_libdir],
            libraries=[":" + _lib],
            extra_compile_args=["-O2", "-std=c11", "-D_POSIX_C_SOURCE=200809L", "-Wall"],
        ),
        Extension(
            "bauv_sim.sensors._harmonic_rays",
            sources=["bauv_sim/sensors/harmonic_rays.c"],
            include_dirs=["nav"],
            depends=["nav/clib.h"],
            extra_compile_args=["-O2", "-std=c11", "-ffp-contract=off", "-Wall"],
            libraries=["m"],
        ),
        Extension(
            "nav.seabed._seabed_shift",
            sources=["nav/seabed/seabed_shift.c"],
            include_dirs=["nav"],
            depends=["nav/clib.h"],
            extra_compile_args=["-O2", "-std=c11", "-ffp-contract=off", "-Wall"],
            libraries=["m"],
        ),
    ]
)
