"""The cuts of issue 27's step profile that change no number: lazy imports and the vector figure
drawn with the PNG's layout."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from tasks.core import style


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
