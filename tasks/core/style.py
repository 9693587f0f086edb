"""The project's figure style: one look for every figure an experiment writes.

Sizes are those of a two-column journal page (a column about 3.5 in, the page about 7.2 in),
fonts are sized for print at that width, every figure is written as a PNG (200 dpi, for a quick
look) and a vector PDF beside it (for the paper), and each method has a fixed colour and line
style from a colour-blind-safe palette (Okabe and Ito, "Color Universal Design", 2008; black and
grey for truth and commands), the same in the figures and in the rerun recordings
(:func:`rgb`). A new experiment adopts it with one import::

    from tasks.core import style

    @style.styled
    def my_figure(out_dir, t_s, err_m) -> list[str]:
        fig, ax = style.subplots("column", height_in=2.4)
        ax.plot(t_s, err_m, **style.line("my-filter"))
        ax.set_xlabel("time (s)")
        ax.set_ylabel(style.label("horizontal error", "m"))
        return style.save(fig, out_dir / "error.png")  # error.png and error.pdf

``styled`` applies the style's matplotlib settings while the figure is drawn and saved (the
settings of a caller are restored afterwards); ``line(method)`` gives the colour, line style and
legend label of a method, so a method looks the same in every figure, and ``rgb(method)`` its
colour for a recording.

The framework owns only the looks of what every experiment draws (truth, reference, command,
way-points, current, a bound). An experiment package declares the looks of its methods once, in
its ``__init__`` (:func:`declare`)::

    style.declare(__name__, {"my-filter": style.MethodStyle(style.PALETTE["blue"])})

and the declarations of all packages make one table (:data:`METHODS`): two packages may declare
the same method with the same look, a different look is refused (:class:`StyleClash`).
"""

from __future__ import annotations

import functools
import io
import re
import types
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal, ParamSpec, TypeVar

import numpy as np
from cycler import cycler

from tasks.core.files import atomic_write_bytes
from tasks.core.lazy import LazyModule

# matplotlib is imported when the first figure is drawn, not when an experiment is imported
matplotlib = LazyModule("matplotlib", lambda mpl: mpl.use("Agg"))
plt = LazyModule("matplotlib.pyplot", after=(matplotlib,))
ticker = LazyModule("matplotlib.ticker", after=(matplotlib,))

__all__ = [
    "COLUMN_IN",
    "METHODS",
    "PAGE_IN",
    "PALETTE",
    "RC",
    "MethodStyle",
    "StyleClash",
    "color",
    "context",
    "declare",
    "figure_legend",
    "label",
    "legend_outside",
    "line",
    "log_ticks",
    "panel_letters",
    "rgb",
    "save",
    "styled",
    "subplots",
    "title",
]

COLUMN_IN = 3.5
"""Width of one column of a two-column page, inches."""
PAGE_IN = 7.2
"""Width of a full page (both columns), inches."""
PNG_DPI = 200
"""Resolution of the PNG beside each vector file."""

PALETTE: dict[str, str] = {
    "black": "#000000",
    "orange": "#E69F00",
    "sky_blue": "#56B4E9",
    "bluish_green": "#009E73",
    "yellow": "#F0E442",
    "blue": "#0072B2",
    "vermillion": "#D55E00",
    "reddish_purple": "#CC79A7",
    "grey": "#7F7F7F",
    "olive": "#999933",  # Paul Tol's muted olive and wine: two more colours
    "wine": "#882255",
    "dark_grey": "#4D4D4D",
    "light_grey": "#BBBBBB",
}
"""Okabe-Ito colour-blind-safe colours, plus greys and two of Paul Tol's muted colours."""

_P = PALETTE
_HEX = re.compile(r"#[0-9A-Fa-f]{6}")


@dataclass(frozen=True)
class MethodStyle:
    """The look of one method (or drawn thing) in every figure and recording.

    Attributes:
        color: ``"#RRGGBB"``; the figures draw it, a recording uses its :attr:`rgb`.
        ls: matplotlib line style (``"none"`` for fixes drawn as markers).
        label: the legend label (default: the method's name).
        marker: matplotlib marker, or ``None``.
    """

    color: str
    ls: str = "-"
    label: str | None = None
    marker: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.color, str) or not _HEX.fullmatch(self.color):
            raise ValueError(f"color = {self.color!r}: must be a colour '#RRGGBB'")

    @property
    def rgb(self) -> tuple[int, int, int]:
        """The colour as 0-255 integers (red, green, blue), as rerun takes it."""
        return (int(self.color[1:3], 16), int(self.color[3:5], 16), int(self.color[5:7], 16))


class StyleClash(ValueError):
    """A method declared with a look other than the one another package declared for it."""


FRAMEWORK = "tasks.core.style"
"""The owner of the framework's own looks (what every experiment draws)."""

_STYLES: dict[str, MethodStyle] = {}
_OWNERS: dict[str, str] = {}
METHODS: Mapping[str, MethodStyle] = types.MappingProxyType(_STYLES)
"""Every declared look, read only: method -> :class:`MethodStyle` (the framework's own and those
the imported experiment packages declared, :func:`declare`)."""


def declare(owner: str, styles: Mapping[str, MethodStyle]) -> None:
    """Add the looks of a package's methods to :data:`METHODS` (all of them, or none on an error).

    A method may be declared by several packages with the same look; the package that declared it
    first may change it (a reload).

    Args:
        owner: the declaring package (its ``__name__``).
        styles: method name -> its look.

    Raises:
        StyleClash: naming the method, both packages and both looks, if another package declared
            the method with another look.
        ValueError: if a name is not a non-empty string or a look not a :class:`MethodStyle`.
    """
    resolved: dict[str, MethodStyle] = {}
    for name, look in styles.items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"{owner}: method name {name!r}: must be a non-empty string")
        if not isinstance(look, MethodStyle):
            raise ValueError(f"{owner}: style of {name!r} = {look!r:.60}: must be a MethodStyle")
        look = replace(look, label=name) if look.label is None else look
        prior = _STYLES.get(name)
        if prior is not None and prior != look and _OWNERS[name] != owner:
            raise StyleClash(
                f"method {name!r}: {owner} declares {look}, but {_OWNERS[name]} declared "
                f"{prior}; a method has one look in every figure and recording (declare the same "
                "look, or name the method differently)"
            )
        resolved[name] = look
    for name, look in resolved.items():
        _STYLES[name] = look
        _OWNERS.setdefault(name, owner)


declare(
    FRAMEWORK,
    {
        "truth": MethodStyle(_P["black"]),
        "reference": MethodStyle(_P["black"]),
        "command": MethodStyle(_P["grey"], ls="--", label="commanded"),
        "waypoint": MethodStyle(_P["dark_grey"], label="way-point"),
        "current": MethodStyle(_P["wine"]),
        "bound": MethodStyle(_P["blue"], ls=":"),
    },
)

RC: dict[str, Any] = {
    "font.size": 8,
    "axes.titlesize": 8.5,
    "axes.labelsize": 8,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "legend.fontsize": 7,
    "legend.frameon": True,
    "legend.framealpha": 0.85,
    "legend.edgecolor": "0.8",
    "figure.titlesize": 9,
    "lines.linewidth": 1.0,
    "lines.markersize": 3.5,
    "axes.linewidth": 0.6,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.5,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "axes.prop_cycle": cycler(
        color=[_P[k] for k in ("blue", "vermillion", "bluish_green", "orange", "reddish_purple")]
    ),
    "figure.dpi": 100,
    "savefig.dpi": PNG_DPI,
    "savefig.bbox": "tight",
    "savefig.pad_inches": 0.03,
    "pdf.fonttype": 42,  # TrueType in the PDF: text stays text, editable, searchable
    "svg.fonttype": "none",
    "mathtext.default": "regular",
    "figure.constrained_layout.use": True,
}
"""The matplotlib settings applied while a styled figure is drawn."""

P = ParamSpec("P")
R = TypeVar("R")


def styled(fn: Callable[P, R]) -> Callable[P, R]:
    """Decorate a function that draws figures: it runs under :data:`RC` (restored after)."""

    @functools.wraps(fn)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        with matplotlib.rc_context(RC):
            return fn(*args, **kwargs)

    return wrapper


def context():
    """The style as a context manager, for code that imports matplotlib lazily::

    with style.context():
        fig, ax = style.subplots("column")
        ...
    """
    return matplotlib.rc_context(RC)


def subplots(
    width: Literal["column", "page"] | float = "page",
    height_in: float | None = None,
    nrows: int = 1,
    ncols: int = 1,
    **kwargs: Any,
):
    """A figure of a column's or the page's width (``plt.subplots`` otherwise).

    Args:
        width: ``"column"`` (:data:`COLUMN_IN`), ``"page"`` (:data:`PAGE_IN`) or inches.
        height_in: height, inches (default: 0.62 of the width per row, at most 9 in).
        nrows, ncols, kwargs: as ``matplotlib.pyplot.subplots``.

    Returns:
        ``(figure, axes)`` as ``plt.subplots``.
    """
    w = {"column": COLUMN_IN, "page": PAGE_IN}.get(width, width)  # type: ignore[arg-type]
    h = height_in if height_in is not None else min(9.0, 0.62 * float(w) * nrows / max(ncols, 1))
    return plt.subplots(nrows, ncols, figsize=(float(w), h), **kwargs)


FREEZE_LAYOUT = True
"""Draw the vector file of :func:`save` with the layout computed for the PNG (constrained layout
runs once per figure, not once per file): its axes are where the PNG's are, and the default
mission's figures take 10 % less CPU (``benchmarks/README.md``, "Where a step goes"). False
lays the vector file out again at its own resolution (axes up to 0.5 % of the figure elsewhere)."""


def save(fig, path: Path, vector: Literal["pdf", "svg"] = "pdf") -> list[str]:
    """Write ``path`` (PNG, :data:`PNG_DPI`) and the vector file beside it; close the figure.

    Args:
        fig: the figure.
        path: the PNG file (its suffix is replaced by ``.png`` if it has another).
        vector: the vector format written beside it.

    Each file is drawn into memory and then written atomically
    (:func:`tasks.core.files.atomic_write_bytes`): a full disk leaves no truncated file (the
    previous one, if any, stays) and raises a plain :class:`OSError`, and a file of a run folder
    is never written through a symbolic link.

    Returns:
        The names of the files written: ``[name.png, name.pdf]``.

    Raises:
        OSError: if a file cannot be written.
    """
    png = Path(path).with_suffix(".png")
    vec = png.with_suffix(f".{vector}")
    try:
        with matplotlib.rc_context(RC):
            drawn = []
            for target, kwargs in (
                (png, {"dpi": PNG_DPI}),
                (vec, {"metadata": None if vector == "svg" else {"CreationDate": None}}),
            ):
                buf = io.BytesIO()
                fig.savefig(buf, format=target.suffix[1:], **kwargs)
                drawn.append((target, buf))
                if FREEZE_LAYOUT and fig.get_layout_engine() is not None:
                    # the vector file keeps the layout the PNG was drawn with: the layout
                    # engine (constrained layout) is not run a second time
                    fig.set_layout_engine("none")
        for target, buf in drawn:
            atomic_write_bytes(target, buf.getbuffer())
    finally:
        plt.close(fig)
    return [png.name, vec.name]


_UNKNOWN = MethodStyle(_P["grey"])


def color(method: str) -> str:
    """The colour of a method (:data:`METHODS`), grey for an unknown one."""
    return METHODS.get(method, _UNKNOWN).color


def rgb(method: str) -> tuple[int, int, int]:
    """The colour of a method (:data:`METHODS`) as rerun takes it, 0-255 (red, green, blue):
    the figures' colour; grey for an unknown one."""
    return METHODS.get(method, _UNKNOWN).rgb


def line(method: str, label: str | None = None, **overrides: Any) -> dict[str, Any]:
    """Keyword arguments of ``Axes.plot`` for a method: its colour, line style, marker, label.

    Args:
        method: a key of :data:`METHODS` (unknown: grey solid, labelled by the key).
        label: the legend label (default the method's; ``"_"`` hides it from the legend).
        overrides: any other ``plot`` keyword (``lw``, ``alpha``, ``zorder``...).
    """
    m = METHODS.get(method) or replace(_UNKNOWN, label=method)
    out: dict[str, Any] = {"color": m.color, "ls": m.ls, "label": m.label}
    if m.marker is not None:
        out["marker"] = m.marker
    if label is not None:
        out["label"] = label
    out.update(overrides)
    return out


def label(quantity: str, unit: str | None = None) -> str:
    """An axis label ``"quantity (unit)"``; Greek in the quantity as mathtext (``r"$\\sigma$"``)."""
    return quantity if not unit else f"{quantity} ({unit})"


def title(ax, text: str) -> None:
    """A short title in words (never a registry name), left aligned as a panel heading."""
    ax.set_title(text, loc="left")


def panel_letters(axes) -> None:
    """Letter the panels (a), (b), ... in reading order: before the panel's left title if it
    has one (call after :func:`title`), else just above its left corner."""
    for i, ax in enumerate(np.ravel(axes)):
        letter = f"({chr(ord('a') + i)})"
        existing = ax.get_title(loc="left")
        if existing:
            ax.set_title(f"{letter} {existing}", loc="left")
        else:
            ax.set_title(letter, loc="left", fontweight="bold")


def log_ticks(ax, axis: Literal["x", "y"] = "y") -> None:
    """Plain-number ticks on a log axis (1, 2, 5, 10, ... instead of ``2 x 10^0``); only the
    powers of ten when the axis spans more than three decades. Call after plotting."""
    a = ax.yaxis if axis == "y" else ax.xaxis
    lo, hi = ax.get_ylim() if axis == "y" else ax.get_xlim()
    decades = np.log10(max(hi, 1e-300) / max(lo, 1e-300)) if lo > 0 else 10.0
    subs = (1.0, 2.0, 5.0) if decades <= 3 else (1.0,)
    a.set_major_locator(ticker.LogLocator(base=10, subs=subs))
    a.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    a.set_minor_formatter(ticker.NullFormatter())


def legend_outside(ax, ncol: int | None = None, **kwargs: Any):
    """A legend in rows above the axes, so it never hides data or a band.

    Args:
        ax: the axes whose labelled artists go in the legend.
        ncol: columns (default: all entries in one row, at most 4).
    """
    _, labels = ax.get_legend_handles_labels()
    return ax.legend(
        loc="lower left",
        bbox_to_anchor=(0.0, 1.01, 1.0, 0.1),
        mode="expand",
        ncol=ncol or max(1, min(4, len(labels))),
        borderaxespad=0.0,
        **kwargs,
    )


def figure_legend(fig, axes, ncol: int | None = None, **kwargs: Any):
    """One legend for several panels, below them (each label once, in the order first seen)."""
    seen: dict[str, Any] = {}
    for ax in np.ravel(axes):
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            seen.setdefault(lab, h)
    leg = fig.legend(
        list(seen.values()),
        list(seen),
        loc="outside lower center",
        ncol=ncol or max(1, min(5, len(seen))),
        **kwargs,
    )
    for h in leg.legend_handles:  # faint overlaid tracks get an opaque legend entry
        if h is not None and hasattr(h, "set_alpha"):
            h.set_alpha(1.0)
    return leg
