"""The report of ``mission/swarm``: the tables, the warnings and ``metrics.json``; the figure and
the recording of one run (:mod:`~tasks.missions.swarm.figures`) (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field, model_serializer

from bauv_sim.currents import UniformCurrentConfig
from tasks.closed_loop.experiment import MissionExperiment
from tasks.core.registry import ReportContext, ReportSummary
from tasks.missions.swarm.figures import record_swarm, swarm_figure
from tasks.missions.swarm.run import SwarmRunResult
from tasks.missions.swarm.scenario import FOLLOWERS, LEADER, SwarmScenario, station_offsets

Array = NDArray[np.float64]


# ---------------------------------------------------------------------------------------------
# Report


class FollowerRow(BaseModel):
    """One follower with one method, means over the successful runs."""

    method: str
    follower: str
    relative_bearing_deg: float
    distance_m: float
    values: dict[str, float]


class TeamRow(BaseModel):
    """One vehicle under one team method on the measurements of the flights of one method
    (:mod:`tasks.missions.swarm.team`), means over the successful runs."""

    flight: str = Field(description="the method the followers flew with")
    method: str = Field(description="the team method run on that flight's measurements")
    vehicle: str
    values: dict[str, float]


class SwarmMetrics(BaseModel):
    """``metrics.json`` of ``mission/swarm`` (``team`` only on the acoustic network)."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    n_failed: int
    failures: list[str]
    n_diverged: int = Field(description="aided estimates that diverged (navigation.divergence_m)")
    divergences: list[str]
    methods: list[str]
    current: str
    followers: list[FollowerRow] = Field(description="per follower and method, means over runs")
    leader: dict[str, dict[str, float]] = Field(description="per method, the leader's means")
    warnings: list[str]
    runs: list[dict[str, Any]] = Field(description="per run: method -> vehicle -> metrics")
    team: list[TeamRow] | None = Field(
        None,
        description="on the acoustic network: per flight, team method and vehicle, the error "
        "and NEES on the flight's measurements, means over runs",
    )

    @model_serializer(mode="wrap")
    def _without_absent_team(self, handler):
        out = handler(self)
        if out.get("team") is None:
            out.pop("team", None)
        return out


TEAM_KEYS = (
    ("mean_error_m", "Mean error (m)"),
    ("final_error_m", "Final error (m)"),
    ("max_error_m", "Max error (m)"),
    ("nees", "NEES (2 dof)"),
    ("nees_low", "NEES band lower end"),
    ("nees_high", "NEES band upper end"),
    ("consistent", "Not over-confident (runs)"),
    ("clock_rmse_ms", "Clock offset RMSE (ms)"),
    ("ranges_used", "Ranges used"),
)
"""The team table's values (:func:`tasks.missions.swarm.team.team_comparison`)."""


def team_rows(runs: list[SwarmRunResult], methods: list[str], names) -> list[TeamRow]:
    """Means over the runs of the team comparison, per flight, team method and vehicle
    (``consistent``: the count of runs whose NEES is at or below the band's upper end)."""
    rows = []
    for flight in methods:
        done = [r.team[flight] for r in runs if flight in r.team]
        if not done:
            continue
        for method in done[0]:
            for vehicle in names:
                values = {}
                for key, _ in TEAM_KEYS:
                    vals = [d[method][vehicle][key] for d in done if key in d[method][vehicle]]
                    if vals:
                        values[key] = float(np.sum(vals) if key == "consistent" else np.mean(vals))
                rows.append(TeamRow(flight=flight, method=method, vehicle=vehicle, values=values))
    return rows


def team_table(rows: list[TeamRow], n_ok: int):
    """The table of the team comparison (acceptance 4 of issue 24 on the physical vehicles)."""
    from tasks.core.report import Table

    return Table(
        f"Team navigation on each flight's measurements ({n_ok} run(s), mean over runs)",
        ["Flight", "Vehicle", "Method", *(label for _, label in TEAM_KEYS)],
        [
            [
                row.flight.upper(),
                row.vehicle,
                row.method,
                *(_cell(k, row.values.get(k)) for k, _ in TEAM_KEYS),
            ]
            for row in rows
        ],
        digits=3,
        slug="team",
        note=(
            "Every method on the same data: the measurements the vehicles had in the flight "
            "(each vehicle's dead reckoning, the leader's USBL fixes, every range of the acoustic "
            "network) on the control tick's grid. ga2 and leader-ekf: seed 003 on each "
            "follower's ranges from the leader alone (clocks not modelled); decentralised: "
            "covariance intersection with the clocks in the state; central: one EKF over the "
            "team (the reference). NEES: horizontal position, mean over the samples of a run "
            "(the table: mean over runs); band: two-sided 95 % of one run's NEES "
            "(nav.cooperative.team_metrics on each run); not over-confident: the runs whose "
            "NEES is at or below the band's upper end."
        ),
    )


ROW_KEYS = (
    ("est_mean_error_m", "Estimate mean error (m)"),
    ("est_max_error_m", "Estimate max error (m)"),
    ("relative_mean_error_m", "Relative mean error (m)"),
    ("station_mean_error_m", "Station mean error (m)"),
    ("station_max_error_m", "Station max error (m)"),
    ("dr_mean_error_m", "Pure DR mean error (m)"),
    ("fixes_accepted", "Ranges accepted"),
    ("fixes_refused", "Ranges refused"),
    ("mean_fix_hdop", "Mean HDOP at fixes"),
    ("diverged_runs", "Diverged runs"),
)


COUNT_KEYS = frozenset(
    {"fixes_accepted", "fixes_refused", "usbl_fixes", "diverged_runs", "ranges_used", "consistent"}
)
"""Row keys that count events: printed as whole numbers when the mean over runs is one."""


def _cell(key: str, value: float | None) -> float | int | None:
    """A table cell: a count that is a whole number as an ``int`` (119, not 119.00)."""
    if key in COUNT_KEYS and value is not None and float(value).is_integer():
        return int(value)
    return value


def report_swarm(exp: MissionExperiment, ctx: ReportContext) -> ReportSummary:
    """The table per follower and method, the leader's navigation, warnings, figures, the
    recording of one run and the run data."""
    from tasks.closed_loop.report import export_runs
    from tasks.core.report import Table, write_metrics, write_tables

    scn: SwarmScenario = ctx.scenario  # type: ignore[assignment]
    runs: list[SwarmRunResult] = [r for b in ctx.blocks for r in b]
    ok = [r for r in runs if r.failed is None]
    methods = list(scn.methods())
    stations = station_offsets(scn)
    names = FOLLOWERS[: len(stations)]

    def mean(method: str, vehicle: str, key: str) -> float | None:
        if key == "diverged_runs":  # a count over the runs, not a mean
            if method == "dr":
                return None
            return float(sum("diverged_at_s" in r.metrics[method].get(vehicle, {}) for r in ok))
        vals = [r.metrics[method][vehicle][key] for r in ok if vehicle in r.metrics[method]]
        return float(np.mean(vals)) if vals else None

    rows = []
    for name, st in zip(names, stations, strict=True):
        for m in methods:
            vals = {k: mean(m, name, k) for k, _ in ROW_KEYS}
            rows.append(
                FollowerRow(
                    method=m,
                    follower=name,
                    relative_bearing_deg=st.relative_bearing_deg,
                    distance_m=st.distance_m,
                    values={k: v for k, v in vals.items() if v is not None},
                )
            )
    leader = {
        m: {
            k: v
            for k in ("ekf_mean_error_m", "ekf_max_error_m", "usbl_fixes")
            if (v := mean(m, LEADER, k)) is not None
        }
        for m in methods
    }
    diverged = [w for r in ok for w in r.diverged]
    warnings = diverged + [w for r in runs for w in r.warnings]
    failures = [r.failed for r in runs if r.failed]
    metrics = SwarmMetrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        n_failed=len(failures),
        failures=failures,
        n_diverged=len(diverged),
        divergences=diverged,
        methods=methods,
        current=f"{scn.current.kind}",
        followers=rows,
        leader=leader,
        warnings=warnings,
        runs=[
            {"run": r.run, "failed": r.failed, "metrics": r.metrics}
            | ({"team": r.team} if r.team else {})
            for r in runs
        ],
        team=team_rows(ok, methods, (LEADER, *names)) if scn.followers.network.enabled else None,
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    for m in methods:
        files += export_runs(
            ctx.out_dir, exp.name, [r.flights[m] for r in runs], m, frame=scn.frame()
        )
    cur = scn.current
    cur_text = (
        f"{cur.speed_m_s:g} m/s towards {cur.direction_deg:g} deg"
        if isinstance(cur, UniformCurrentConfig)
        else cur.kind
    )
    t1 = Table(
        f"Followers: navigation and station keeping ({len(ok)} run(s), mean over runs; "
        f"current {cur_text})",
        ["Follower", "Station", "Method", *(label for _, label in ROW_KEYS)],
        [
            [
                row.follower,
                f"{row.relative_bearing_deg:g} deg / {row.distance_m:g} m",
                row.method.upper(),
                *(_cell(k, row.values.get(k)) for k, _ in ROW_KEYS),
            ]
            for row in rows
        ],
        digits=2,
        slug="followers",
        note=(
            "Estimate error: the follower's estimate against its true position (world). "
            "Relative error: the estimated offset from the leader (estimate minus the leader "
            "position it knows) against the true offset. Station error: the true distance to "
            "the true station point (the leader's true position and course). Pure DR: the "
            "compass + log track without any range."
        ),
    )
    t2 = Table(
        "Leader: its own navigation (the position it broadcasts)",
        ["Method flown by the followers", "EKF mean error (m)", "EKF max error (m)", "USBL fixes"],
        [
            [
                m.upper(),
                leader[m].get("ekf_mean_error_m"),
                leader[m].get("ekf_max_error_m"),
                _cell("usbl_fixes", leader[m].get("usbl_fixes")),
            ]
            for m in methods
        ],
        digits=2,
        slug="leader",
    )
    tables = [t1, t2]
    if metrics.team:
        tables.append(team_table(metrics.team, len(ok)))
    if warnings or failures:
        tables.append(Table("Warnings", ["Warning"], [[w] for w in warnings], slug="warnings"))
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    rec = next((r for r in runs if r.run == scn.report.record_run), None)
    if rec is not None:
        flight = rec.flights[methods[0]]
        if flight.vehicles and len(flight.vehicles[LEADER]["t"]) > 1:
            if scn.report.figures:
                files += swarm_figure(exp.name, scn, rec, methods, ctx.out_dir)
            if scn.report.recording:
                files.append(record_swarm(exp.name, scn, rec.flights, ctx.out_dir))
    text = "".join(t.to_text() + "\n" for t in tables)
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files), tuple(failures), tuple(diverged))
