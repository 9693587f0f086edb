"""Figures that hid data (issue 26, a reviewer): seed 004's nominal path and sample paths had
their legends over a beacon and a trough of the paths and drew one filter's paths over the
others'; seed 003's all-samples route figure left the EKF out. The figures are drawn on small
inputs made here and inspected before they are written."""

from __future__ import annotations

import numpy as np
import pytest

from tasks.core import style


@pytest.fixture
def drawn(monkeypatch, tmp_path):
    """The figures the drawing functions save, kept open (``style.save`` replaced)."""
    figs = []

    def keep(fig, path, vector="pdf"):
        fig.canvas.draw()
        figs.append(fig)
        return [str(path)]

    monkeypatch.setattr(style, "save", keep)
    yield figs
    for fig in figs:
        style.plt.close(fig)


def _legend_clear_of_the_axes(fig):
    """No legend inside an axes; the figure's legend overlaps no axes' area."""
    assert all(ax.get_legend() is None for ax in fig.axes)
    assert len(fig.legends) == 1
    box = fig.legends[0].get_window_extent()
    for ax in fig.axes:
        assert not box.overlaps(ax.get_window_extent()), ax.get_title()
    return [t.get_text() for t in fig.legends[0].get_texts()]


def test_seed004_nominal_and_sample_paths_hide_nothing(drawn, tmp_path):
    from tasks.paper004 import figures
    from tasks.paper004.sim import FILTERS

    t = np.linspace(0.0, 300.0, 301)
    xn = np.column_stack([1.5 * t, 15 * np.sin(t / 12), -10 + 2 * np.sin(t / 32)])
    beacons = np.array([[-100.0, 100.0, 0.0], [200.0, 100.0, 0.0], [500.0, 0.0, 0.0]])
    figures.nominal(tmp_path, xn, beacons, t)
    rng = np.random.default_rng(0)
    runs = {r: {f: xn + rng.normal(0, 1, xn.shape) for f in FILTERS} for r in range(3)}
    figures.sample_paths(tmp_path, "case", xn, t, runs)
    nominal_3d, _components, paths = drawn
    assert _legend_clear_of_the_axes(nominal_3d) == ["nominal path", "beacons"]
    assert sorted(_legend_clear_of_the_axes(paths)) == sorted(["nominal", *FILTERS])
    for ax in paths.axes:  # every filter's paths seen through the others'
        tracks = [ln for ln in ax.get_lines() if ln.get_alpha() is not None]
        assert len(tracks) == 3 * len(FILTERS)
        assert all(ln.get_alpha() < 1 for ln in tracks)


def test_seed003_all_samples_figure_draws_every_method(monkeypatch, tmp_path):
    from tasks.core import figures
    from tasks.core.runner import run

    seen = {}
    routes = figures.routes

    def spy(path, reference_en, tracks, *args, **kwargs):
        seen[path.name] = {k: len(v) for k, v in tracks.items()}
        return routes(path, reference_en, tracks, *args, **kwargs)

    monkeypatch.setattr(figures, "routes", spy)
    out = tmp_path / "run"
    run("paper-003/test-1", n_runs=3, seed=0, out_dir=out, progress=False)
    assert seen["paths-all.png"] == {"DR": 3, "GA1": 3, "GA2": 3, "EKF": 3}
    assert seen["paths-single.png"] == {"DR": 1, "GA1": 1, "GA2": 1, "EKF": 1}
