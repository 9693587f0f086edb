"""The cuts of issue 27's step profile that change no number: lazy imports, the report's modules
imported during the flight, the vector figure drawn with the PNG's layout."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from tasks.core import runner, style


def _modules_after(code: str) -> set[str]:
    out = subprocess.run(
        [sys.executable, "-c", code + "\nimport sys\nprint(' '.join(sorted(sys.modules)))"],
        capture_output=True,
        text=True,
        check=True,
    )
    return set(out.stdout.split())


def test_building_a_scene_imports_neither_trimesh_nor_scipy_integrate():
    # bauv_sim.build takes MODEL_DIR from bauv_sim.hull; the meshes and the quadratures that need
    # trimesh and scipy.integrate are not built by a mission
    mods = _modules_after("import bauv_sim.build")
    assert "bauv_sim.hull" in mods
    assert "trimesh" not in mods
    assert "scipy.integrate" not in mods


def test_hull_still_builds_meshes_and_integrates():
    from bauv_sim import hull

    mesh = hull.hull_mesh(hull.HULL)
    assert mesh.is_watertight
    # the quadrature of the section areas against the closed mesh's volume: two routes
    assert abs(mesh.volume - hull.HULL.volume_m3()) < 0.02 * hull.HULL.volume_m3()


def test_prefetch_imports_the_report_modules_in_a_thread():
    code = (
        "from tasks.core import runner\n"
        "t = runner.prefetch_report_modules(runner.report_modules(None))\n"
        "assert t.daemon\n"
        "t.join(120)\n"
        "assert not t.is_alive()\n"
    )
    mods = _modules_after(code)
    assert set(runner.FIGURE_MODULES) | set(runner.RECORDING_MODULES) <= mods


def test_the_report_modules_follow_the_scenario_report_switches():
    from types import SimpleNamespace as NS

    both = runner.FIGURE_MODULES + runner.RECORDING_MODULES
    assert runner.report_modules(NS()) == both
    assert runner.report_modules(NS(report=NS(figures=True, recording=True))) == both
    assert runner.report_modules(NS(report=NS(figures=False))) == runner.RECORDING_MODULES
    assert runner.report_modules(NS(report=NS(recording=False))) == runner.FIGURE_MODULES
    assert runner.report_modules(NS(report=NS(figures=False, recording=False))) == ()


def test_prefetch_skips_a_module_that_cannot_be_imported():
    t = runner.prefetch_report_modules(("no_such_module_for_the_test", "json"))
    t.join(30)
    assert not t.is_alive()
    assert "json" in sys.modules


def test_the_vector_file_has_the_layout_of_the_png(tmp_path, monkeypatch):
    import matplotlib.figure

    positions: list[np.ndarray] = []
    savefig = matplotlib.figure.Figure.savefig

    def spy(self, *args, **kwargs):
        out = savefig(self, *args, **kwargs)
        positions.append(np.array([ax.get_position().bounds for ax in self.axes]))
        return out

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", spy)
    with style.context():
        fig, axes = style.subplots("page", nrows=2, ncols=2)
        for i, ax in enumerate(axes.flat):
            ax.plot(np.arange(10) * 10.0**i)
            ax.set_ylabel(f"a long label of panel {i}")
            ax.set_title(f"panel {i}")
        names = style.save(fig, tmp_path / "f.png")
    assert names == ["f.png", "f.pdf"]
    assert (tmp_path / "f.png").stat().st_size > 0 and (tmp_path / "f.pdf").stat().st_size > 0
    png_layout, pdf_layout = positions
    # constrained layout ran once, for the PNG; the PDF was drawn with the same axes positions
    assert np.array_equal(png_layout, pdf_layout)


def _figure(i: int):
    fig, ax = style.subplots("column")
    ax.plot(np.arange(20) ** (1 + i), label=f"curve {i}")
    ax.set_title(f"figure {i}")
    style.figure_legend(fig, (ax,))
    return fig


def test_parallel_saves_write_the_same_bytes_as_saves_here(tmp_path):
    (tmp_path / "here").mkdir()
    (tmp_path / "forked").mkdir()
    with style.context():
        here = [style.save(_figure(i), tmp_path / "here" / f"f{i}.png") for i in range(3)]
        with style.parallel_saves():
            forked = [style.save(_figure(i), tmp_path / "forked" / f"f{i}.png") for i in range(3)]
    assert forked == here
    for names in here:
        for n in names:
            assert (tmp_path / "forked" / n).read_bytes() == (tmp_path / "here" / n).read_bytes()


def test_a_failed_forked_save_raises_naming_the_figure(tmp_path):
    (tmp_path / "f1.png").mkdir()  # the child cannot write its PNG over a folder
    with style.context(), pytest.raises(OSError, match=r"f1\.png: .*Error"):
        with style.parallel_saves():
            style.save(_figure(0), tmp_path / "f0.png")
            style.save(_figure(1), tmp_path / "f1.png")
    assert (tmp_path / "f0.png").exists() and (tmp_path / "f0.pdf").exists()
