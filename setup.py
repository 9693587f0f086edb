"""Build of the one C library, the MuJoCo engine plugin; everything else is declared in
``pyproject.toml``.

* The MuJoCo engine plugin ``bauv.hydro`` (``bauv_sim/plugin/hydro.c``): a shared library that
  MuJoCo loads with ``mj_loadPluginLibrary`` (``bauv_sim.hydro.load_plugin``); it is compiled
  against the headers of the MuJoCo release in the build environment (its ``mjModel``/``mjData``
  layouts) and linked to that release's library, found in its ``mujoco`` package. The release is
  written beside the library (``_bauv_hydro.build.json``: the header's ``mjVERSION_HEADER``), and
  ``bauv_sim.hydro.load_plugin`` refuses another MuJoCo at run time.

A wheel also carries the data files the package reads through ``bauv_sim.PROJECT_ROOT`` (the
vehicle model ``models/``, the seabed and site files ``assets/``) under ``bauv_sim/_data/``
(:class:`BuildPy`); an editable install reads them from the source tree.

The seabed's hot loops (the harmonic ray march, the seabed shift) were two more C libraries
loaded with ctypes until issue 26; they are numba functions now (``pyproject.toml``: numba), with
the same numbers bit for bit and within 1.5 times the C's time (``benchmarks/bench_kernels.py``).
"""

from __future__ import annotations

import glob
import json
import os
import re
import shutil

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

PLUGIN = "bauv_sim.plugin._bauv_hydro"
"""The plugin's extension name (``bauv_sim.hydro.plugin_path`` finds its library)."""

PLUGIN_RECORD = "_bauv_hydro.build.json"
"""File written beside the plugin library: the MuJoCo release it was compiled against."""

DATA_TREES = ("models", "assets")
"""Folders of the source tree a wheel carries under ``bauv_sim/_data/``."""

DATA_SKIP = ("tools", "__pycache__", "*.pyc", "*.so", "*.png")
"""What of them a wheel leaves out (the model's design-time scripts and picture, build products)."""


def _mujoco() -> tuple[str, str, str]:
    import mujoco

    root = os.path.dirname(mujoco.__file__)
    libs = sorted(glob.glob(os.path.join(root, "libmujoco.so*")))
    if not libs:
        raise RuntimeError(f"no libmujoco.so in {root}: is the mujoco wheel complete?")
    return os.path.join(root, "include"), root, os.path.basename(libs[-1])


def _header_version(include: str) -> int:
    """``mjVERSION_HEADER`` of the MuJoCo headers the plugin is compiled against (3017000 for
    3.17.0)."""
    path = os.path.join(include, "mujoco", "mujoco.h")
    with open(path, encoding="utf-8") as fh:
        found = re.search(r"^#define\s+mjVERSION_HEADER\s+(\d+)", fh.read(), re.MULTILINE)
    if found is None:
        raise RuntimeError(f"no mjVERSION_HEADER in {path}: is the mujoco wheel complete?")
    return int(found.group(1))


class BuildExt(build_ext):
    """``build_ext`` that writes, beside the plugin library, the MuJoCo release it was compiled
    against (``bauv_sim.hydro.load_plugin`` compares it with the MuJoCo loaded at run time)."""

    def build_extension(self, ext: Extension) -> None:
        super().build_extension(ext)
        if ext.name != PLUGIN:
            return
        import mujoco

        record = {"mujoco": mujoco.__version__, "mjVERSION_HEADER": _header_version(_include)}
        path = os.path.join(os.path.dirname(self.get_ext_fullpath(ext.name)), PLUGIN_RECORD)
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(json.dumps(record, indent=2) + "\n")
        self._plugin_record = path

    def copy_extensions_to_source(self) -> None:
        """An editable install: the record goes beside the library copied into the source tree."""
        super().copy_extensions_to_source()
        built = getattr(self, "_plugin_record", None)
        if built is not None:
            package_dir = self.get_finalized_command("build_py").get_package_dir("bauv_sim.plugin")
            self.copy_file(built, os.path.join(package_dir, PLUGIN_RECORD), level=self.verbose)


class BuildPy(build_py):
    """``build_py`` that copies the data trees into ``bauv_sim/_data/`` of a wheel (not in an
    editable install, which reads the source tree)."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        dest = os.path.join(self.build_lib, "bauv_sim", "_data")
        for tree in DATA_TREES:
            target = os.path.join(dest, tree)
            if os.path.isdir(target):
                shutil.rmtree(target)
            shutil.copytree(tree, target, ignore=shutil.ignore_patterns(*DATA_SKIP))


_include, _libdir, _lib = _mujoco()

setup(
    cmdclass={"build_ext": BuildExt, "build_py": BuildPy},
    ext_modules=[
        Extension(
            PLUGIN,
            sources=["bauv_sim/plugin/hydro.c"],
            include_dirs=[_include],
            library_dirs=[_libdir],
            libraries=[":" + _lib],
            extra_compile_args=["-O2", "-std=c11", "-D_POSIX_C_SOURCE=200809L", "-Wall"],
        ),
    ],
)
