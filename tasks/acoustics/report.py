"""The report of ``acoustics/sound-speed``: what a sound-speed mismatch costs (acceptance check 5
of issue 24), for the USBL (position error) and the modem (range error), with the nominal speed
against the profile, with the harmonic-mean-speed correction, and with the profile known.

Two figures per navigator: the **systematic** error (the devices without their random errors:
the cost of the profile alone) and the **Monte Carlo** error over the runs (with the devices'
errors). A fix or range that does not exist (not produced by the device, or no ray through the
known profile) is counted, never a NaN.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from nav.acoustics import LayeredMedium
from tasks.acoustics.run import METHODS, exact, links, medium
from tasks.acoustics.scenario import SoundSpeedScenario
from tasks.core.registry import ReportContext, ReportSummary
from tasks.core.report import Table, write_metrics, write_tables

Array = NDArray[np.float64]


class ErrorStats(BaseModel):
    """An error over the runs and the samples where it exists (no data: None)."""

    samples: int = Field(description="samples with an estimate")
    mean_m: float | None = Field(None, description="mean error, m")
    rms_m: float | None = Field(None, description="RMS error, m")
    max_m: float | None = Field(None, description="largest error, m")


class UsblMethod(BaseModel):
    """One navigator's USBL positions."""

    systematic_mean_m: float | None = Field(
        description="horizontal error without the device's errors, mean over the passage, m"
    )
    systematic_max_m: float | None = Field(description="the same, largest along the passage, m")
    horizontal: ErrorStats = Field(description="horizontal error with the device's errors")
    error_3d: ErrorStats = Field(description="3D error with the device's errors")
    absent: int = Field(description="fixes without a position (no fix, or no ray), all runs")


class UsblMetrics(BaseModel):
    """The USBL passage."""

    transceiver_depth_m: float
    depth_m: float
    closest_approach_m: float
    half_length_m: float
    fixes: int
    nominal_speed_m_s: float
    methods: dict[str, UsblMethod]


class LinkMethod(BaseModel):
    """One navigator's ranges on one modem link (signed errors: estimate minus truth)."""

    systematic_m: float | None = Field(description="range error without the device's errors, m")
    mean_m: float | None = Field(description="mean range error with the device's errors, m")
    rms_m: float | None = Field(description="RMS range error with the device's errors, m")
    absent: int = Field(description="ranges without an estimate, all runs")


class ModemLink(BaseModel):
    """One modem link geometry."""

    sender_depth_m: float
    receiver_depth_m: float
    horizontal_m: float
    slant_m: float
    methods: dict[str, LinkMethod]


class ProfileSummary(BaseModel):
    """The sea's profile over the depths of the experiment."""

    kind: str
    min_speed_m_s: float
    max_speed_m_s: float


class SoundSpeedMetrics(BaseModel):
    """``metrics.json`` of ``acoustics/sound-speed``."""

    schema_version: Literal[1] = 1
    experiment: str
    n_runs: int
    seed: int
    profile: ProfileSummary
    usbl: UsblMetrics
    modem_nominal_speed_m_s: float
    modem: list[ModemLink]
    warnings: list[str]


def _stats(err: Array, ok: NDArray[np.bool_]) -> ErrorStats:
    e = err[ok]
    if e.size == 0:
        return ErrorStats(samples=0)
    return ErrorStats(
        samples=int(e.size),
        mean_m=float(e.mean()),
        rms_m=float(np.sqrt((e**2).mean())),
        max_m=float(np.abs(e).max()),
    )


def _pool(blocks: Iterator[dict[str, Array]]) -> dict[str, Array]:
    parts: dict[str, list[Array]] = {}
    for block in blocks:
        for k, v in block.items():
            parts.setdefault(k, []).append(v)
    return {k: np.concatenate(v) for k, v in parts.items()}


def metrics_of(
    name: str,
    scn: SoundSpeedScenario,
    n_runs: int,
    seed: int,
    p: dict[str, Array],
    sys_: dict[str, Array],
) -> SoundSpeedMetrics:
    """The metrics from the pooled blocks ``p`` and the error-free measurements ``sys_``
    (:func:`tasks.acoustics.run.exact`)."""
    usbl_methods = {}
    for i, meth in enumerate(METHODS):
        ok0 = sys_["usbl_present"][:, i]
        h0 = sys_["usbl_horizontal_m"][ok0, i]
        ok = p["usbl_present"][..., i]
        usbl_methods[meth] = UsblMethod(
            systematic_mean_m=float(h0.mean()) if h0.size else None,
            systematic_max_m=float(h0.max()) if h0.size else None,
            horizontal=_stats(p["usbl_horizontal_m"][..., i], ok),
            error_3d=_stats(p["usbl_error_3d_m"][..., i], ok),
            absent=int((~ok).sum()),
        )
    u = scn.usbl
    sender, receiver = links(scn)
    slant = np.linalg.norm(receiver - sender, axis=-1)
    rows = []
    for g in range(len(slant)):
        methods = {}
        for i, meth in enumerate(METHODS):
            ok = p["modem_present"][:, g, i]
            e = p["modem_error_m"][ok, g, i]
            methods[meth] = LinkMethod(
                systematic_m=float(sys_["modem_error_m"][g, i])
                if sys_["modem_present"][g, i]
                else None,
                mean_m=float(e.mean()) if e.size else None,
                rms_m=float(np.sqrt((e**2).mean())) if e.size else None,
                absent=int((~ok).sum()),
            )
        rows.append(
            ModemLink(
                sender_depth_m=float(-sender[g, 2]),
                receiver_depth_m=float(-receiver[g, 2]),
                horizontal_m=float(receiver[g, 0]),
                slant_m=float(slant[g]),
                methods=methods,
            )
        )
    depths = np.linspace(0.0, max(u.depth_m, u.transceiver_depth_m, *(-receiver[:, 2])), 201)
    true = medium(scn, u.device.sound_speed_m_s)
    speeds = (
        true.profile.speed(depths)
        if isinstance(true, LayeredMedium)
        else np.full(depths.shape, true.speed_m_s)
    )
    m = SoundSpeedMetrics(
        experiment=name,
        n_runs=n_runs,
        seed=seed,
        profile=ProfileSummary(
            kind=scn.sound.kind,
            min_speed_m_s=float(speeds.min()),
            max_speed_m_s=float(speeds.max()),
        ),
        usbl=UsblMetrics(
            transceiver_depth_m=u.transceiver_depth_m,
            depth_m=u.depth_m,
            closest_approach_m=u.closest_approach_m,
            half_length_m=u.half_length_m,
            fixes=u.fixes,
            nominal_speed_m_s=u.device.sound_speed_m_s,
            methods=usbl_methods,
        ),
        modem_nominal_speed_m_s=scn.modem.device.sound_speed_m_s,
        modem=rows,
        warnings=[],
    )
    return m.model_copy(update={"warnings": warnings_of(m)})


def warnings_of(m: SoundSpeedMetrics) -> list[str]:
    """Fixes and ranges that have no estimate (out of range, lost, or in a profile's shadow)."""
    out = []
    for meth, st in m.usbl.methods.items():
        if st.absent:
            out.append(f"USBL {meth}: {st.absent} fixes without a position (no fix or no ray)")
    for link in m.modem:
        for meth, st in link.methods.items():
            if st.absent:
                out.append(
                    f"modem {link.sender_depth_m:g} m -> {link.receiver_depth_m:g} m at "
                    f"{link.horizontal_m:g} m, {meth}: {st.absent} ranges without an estimate"
                )
    return out


def tables(m: SoundSpeedMetrics) -> list[Table]:
    """Table 1: the USBL's position error per navigator; table 2: the modem's range error per
    link and navigator."""
    u = m.usbl
    rows1 = [
        [
            meth,
            st.systematic_mean_m,
            st.systematic_max_m,
            st.horizontal.mean_m,
            st.horizontal.rms_m,
            st.horizontal.max_m,
            st.error_3d.rms_m,
            st.absent,
        ]
        for meth, st in u.methods.items()
    ]
    t1 = Table(
        f"USBL position error: nominal speed, harmonic mean, profile known ({m.n_runs} runs, "
        f"seed {m.seed})",
        [
            "navigator",
            "systematic mean (m)",
            "systematic max (m)",
            "horizontal mean (m)",
            "horizontal RMS (m)",
            "horizontal max (m)",
            "3D RMS (m)",
            "absent",
        ],
        rows1,
        digits=3,
        note=(
            f"Profile {m.profile.kind} ({m.profile.min_speed_m_s:.1f}-"
            f"{m.profile.max_speed_m_s:.1f} m/s over the experiment's depths); nominal speed "
            f"{u.nominal_speed_m_s:g} m/s. Transceiver at {u.transceiver_depth_m:g} m, "
            f"transponder at {u.depth_m:g} m passing {u.closest_approach_m:g} m off, +-"
            f"{u.half_length_m:g} m, {u.fixes} fixes. Systematic: without the device's errors; "
            "the rest with them, over runs and fixes. nominal: straight ray at the nominal "
            "speed; harmonic: straight ray, range scaled by the harmonic mean speed between the "
            "depths; profile: the ray traced back through the known profile."
        ),
        slug="usbl-sound-speed",
    )
    cols2 = ["sender depth (m)", "receiver depth (m)", "horizontal (m)", "slant (m)"]
    for meth in METHODS:
        cols2 += [f"{meth} systematic (m)", f"{meth} mean (m)", f"{meth} RMS (m)"]
    rows2 = []
    for link in m.modem:
        row: list = [link.sender_depth_m, link.receiver_depth_m, link.horizontal_m, link.slant_m]
        for meth in METHODS:
            st = link.methods[meth]
            row += [st.systematic_m, st.mean_m, st.rms_m]
        rows2.append(row)
    t2 = Table(
        f"Modem range error: nominal speed, harmonic mean, profile known ({m.n_runs} runs, "
        f"seed {m.seed})",
        cols2,
        rows2,
        digits=3,
        key=4,  # the depths and the ranges name a row (repeated on a narrow screen)
        note=(
            f"Signed slant-range error (estimate minus truth); nominal speed "
            f"{m.modem_nominal_speed_m_s:g} m/s. nominal: the measured range (nominal speed x "
            "travel time); harmonic: scaled by the harmonic mean speed between the depths over "
            "the nominal; profile: the horizontal range between the two known depths from the "
            "travel time through the known profile, then the slant range. A dash: no data."
        ),
        slug="modem-sound-speed",
    )
    return [t1, t2]


def report_sound_speed(name: str, summary: str, ctx: ReportContext) -> ReportSummary:
    """Write ``metrics.json``, the tables and the figure of a finished batch."""
    scn: SoundSpeedScenario = ctx.scenario  # type: ignore[assignment]
    sys_ = exact(scn)
    m = metrics_of(name, scn, ctx.n_runs, ctx.seed, _pool(ctx.blocks), sys_)
    files = [write_metrics(ctx.out_dir, m)]
    tabs = tables(m)
    files += write_tables(ctx.out_dir, tabs, heading=f"{name}: {summary}")
    if scn.report.figures:
        from tasks.acoustics import figures

        files += figures.systematic(ctx.out_dir / "sound-speed.png", scn, m, sys_)
    text = "".join(t.to_text() for t in tabs)
    text += "".join(f"warning: {w}\n" for w in m.warnings)
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))
