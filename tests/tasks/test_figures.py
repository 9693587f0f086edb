"""Figures: every valid batch draws its figures (issue 12, defect 2) in the project style."""

import json

import pytest

from tasks.core import figures, style
from tasks.core.runner import run

NO_RECORDING = ["report.recording=false"]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("n_runs", "overrides"),
    [
        (1, []),  # one passage: one route, one single-passage figure
        (2, []),  # two passages: the route opacity was 3/2 = 1.5 (matplotlib: alpha outside 0-1)
        (3, ["report.routes_max=0"]),  # no route kept: 3 / 0 raised ZeroDivisionError
    ],
)
def test_small_batches_draw_every_figure(n_runs, overrides, tmp_path):
    out = tmp_path / "run"
    run(
        "paper-000/test-1",
        n_runs=n_runs,
        seed=0,
        out_dir=out,
        overrides=NO_RECORDING + overrides,
        progress=False,
    )
    assert json.loads((out / "run.json").read_text())["state"] == "complete"
    names = ["distance", "histogram", "nees"] + [
        f"distance-passage-{i + 1}" for i in range(min(n_runs, 3))
    ]
    if "report.routes_max=0" not in overrides:
        names.append("routes")
    else:
        assert not (out / "routes.png").exists()  # nothing to draw: no empty figure
    for name in names:
        for suffix in (".png", ".pdf"):
            f = out / f"{name}{suffix}"
            assert f.is_file() and f.stat().st_size > 1000, f
    assert (out / "nees.pdf").read_bytes().startswith(b"%PDF")


@pytest.mark.parametrize("n", [0, 1, 2, 3, 7, 100, 10**6])
def test_route_opacity_is_a_valid_alpha_for_any_count(n):
    a = figures.route_alpha(n)
    assert 0.25 <= a <= 0.9
    assert figures.route_alpha(1) == 0.9 and figures.route_alpha(10**6) == 0.25


def test_method_colours_are_fixed_and_distinct():
    from tasks.core import registry

    registry.names()  # every experiment package imported: every look declared
    # the methods that share a figure never share a colour (DR/EKF/USBL/GPS/truth; CP1/CP2)
    together = [
        ("truth", "DR", "EKF", "USBL", "GPS", "waypoint", "current", "command"),
        ("truth", "DR", "CP1", "CP2", "GPS", "baseline", "waypoint", "current"),
    ]
    for group in together:
        cols = [style.color(m) for m in group]
        assert len(set(cols)) == len(cols), group
    assert style.line("EKF")["color"] == style.PALETTE["blue"]
    assert style.color("no such method") == style.PALETTE["grey"]


def test_styled_restores_the_callers_settings(tmp_path):
    import matplotlib

    before = matplotlib.rcParams["font.size"]

    @style.styled
    def draw():
        assert matplotlib.rcParams["font.size"] == style.RC["font.size"]
        fig, ax = style.subplots("column")
        ax.plot([0, 1], [0, 1], **style.line("DR"))
        return style.save(fig, tmp_path / "x.png")

    assert draw() == ["x.png", "x.pdf"]
    assert matplotlib.rcParams["font.size"] == before
    w = (tmp_path / "x.pdf").read_bytes()
    assert w.startswith(b"%PDF")


SAVE_UNDER_A_FILE_SIZE_LIMIT = """
import resource, signal, sys
from pathlib import Path
import numpy as np
from tasks.core import style

out, limit = Path(sys.argv[1]), int(sys.argv[2])
fig, ax = style.subplots("column")
rng = np.random.default_rng(0)
ax.plot(rng.random(20000), rng.random(20000), ",")  # 20,000 vector marks: a big PDF, a small PNG
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))  # a write past it fails (EFBIG)
try:
    style.save(fig, out / "f.png")
except OSError as exc:
    print("OSError", exc.errno)
"""


@pytest.mark.slow
def test_a_figure_whose_write_fails_part_way_leaves_no_partial_file(tmp_path):
    """The PDF cannot be written whole (a file-size limit stands in for a full disk): a plain
    OSError, the PNG written whole, no PDF and no temporary file. Before the fix matplotlib wrote
    into the final name and a truncated PDF of exactly the limit was left (and on a real full
    disk, a traceback from its PDF writer)."""
    import errno
    import subprocess
    import sys

    whole, limited = tmp_path / "whole", tmp_path / "limited"
    whole.mkdir()
    limited.mkdir()
    res = [
        subprocess.run(
            [sys.executable, "-c", SAVE_UNDER_A_FILE_SIZE_LIMIT, str(d), str(limit)],
            capture_output=True,
            text=True,
            check=False,
        )
        for d, limit in ((whole, 2**40), (limited, 100_000))
    ]
    assert res[0].returncode == 0 and res[0].stdout == "", res[0].stderr
    png, pdf = (whole / "f.png").stat().st_size, (whole / "f.pdf").stat().st_size
    assert png < 100_000 < pdf  # the limit falls inside the PDF
    assert res[1].returncode == 0 and res[1].stderr == "", res[1].stderr
    assert res[1].stdout.split() == ["OSError", str(errno.EFBIG)]
    assert sorted(p.name for p in limited.iterdir()) == ["f.png"]
    assert (limited / "f.png").read_bytes() == (whole / "f.png").read_bytes()


def test_the_packages_declarations_make_one_table_and_the_framework_names_no_method():
    """Every experiment package's looks are in the one table (importing them all raises no
    clash), and tasks/core spells none of the methods the packages declare."""
    from pathlib import Path

    from tasks.core import registry

    registry.names()
    declared = {n for n, owner in style._OWNERS.items() if owner != style.FRAMEWORK}
    assert {"DR", "EKF", "USBL", "GPS", "GA1", "UPMF"} <= declared
    core = Path(style.__file__).parent
    for path in sorted(core.glob("*.py")):
        text = path.read_text(encoding="utf-8")
        for name in sorted(declared):
            assert f'"{name}"' not in text and f"'{name}'" not in text, (path.name, name)


@pytest.fixture
def saved_styles():
    styles, owners = dict(style._STYLES), dict(style._OWNERS)
    yield
    style._STYLES.clear()
    style._STYLES.update(styles)
    style._OWNERS.clear()
    style._OWNERS.update(owners)


def test_a_method_declared_with_another_look_is_refused(saved_styles):
    blue, red = style.PALETTE["blue"], style.PALETTE["vermillion"]
    style.declare("pkg.a", {"r22-filter": style.MethodStyle(blue)})
    style.declare("pkg.b", {"r22-filter": style.MethodStyle(blue)})  # the same look: fine
    with pytest.raises(style.StyleClash, match=r"'r22-filter': pkg\.c declares .*pkg\.a"):
        style.declare(
            "pkg.c", {"r22-other": style.MethodStyle(red), "r22-filter": style.MethodStyle(red)}
        )
    assert "r22-other" not in style.METHODS  # all or nothing
    assert style.line("r22-filter") == {"color": blue, "ls": "-", "label": "r22-filter"}
    with pytest.raises(style.StyleClash, match="'truth'"):  # the framework's own looks too
        style.declare("pkg.d", {"truth": style.MethodStyle(red)})
    with pytest.raises(ValueError, match="#RRGGBB"):
        style.MethodStyle("blue")


def test_one_colour_per_method_in_the_figures_and_in_rerun():
    """A recording's colour of a method is the figures' colour of it (dead reckoning was red-ish
    (214, 39, 40) in rerun and vermillion in the PNGs)."""
    import matplotlib.colors

    from tasks.core import recording, registry

    registry.names()
    assert len(recording.COLORS) == len(style.METHODS)
    for name in style.METHODS:
        want = tuple(round(255 * c) for c in matplotlib.colors.to_rgb(style.color(name)))
        assert style.rgb(name) == want
        assert recording.COLORS[name] == want and recording.COLORS[name.lower()] == want
    assert recording.COLORS["dr"] == (0xD5, 0x5E, 0x00)
    grey = style.MethodStyle(style.PALETTE["grey"]).rgb
    assert recording.COLORS["no such method"] == style.rgb("no such method") == grey
    assert "dr" in recording.COLORS and "no such method" not in recording.COLORS
