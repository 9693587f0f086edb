"""The run data's contract over every registered mission (issue 28): a short batch of two runs of
each mission writes its Parquet run data (``data/``, ``docs/run-data.md``), which
``tasks.core.export.open_dataset`` reads, with, for every run, every variant the mission flies
and every vehicle of its scene, the truth and every estimate the mission computes (with its
covariance where it has one).

Truth: what a mission flies is read from its scenario here, not from the files: the variants
(``mission/swarm``'s ``navigation.methods``, ``mission/correction``'s two course laws,
``mission/seed004``'s filters), the vehicles (the swarm's leader and ``followers.count``
followers) and the estimates (``mission/trn``'s methods, the swarm's team methods on the
acoustic network). A mission registered without an entry
in :data:`EXPECTED` fails :func:`test_every_registered_mission_has_a_contract`: its author adds
what it must write."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pyarrow.compute as pc
import pytest

from tasks.closed_loop.experiment import MissionExperiment
from tasks.core import registry
from tasks.core.export import open_dataset
from tasks.core.runner import plan_batch, run

pytestmark = pytest.mark.slow

RUNS = 2
SHORT = ["timing.max_duration_s=20", "report.figures=false", "report.recording=false"]
STANDARD = (("ekf_pos", "ekf_P"), ("dr_pos", None))
"""Every vehicle's estimates of the standard navigation part: the EKF with its covariance, DR."""

Estimates = tuple[tuple[str, str | None], ...]
"""(position column, its covariance column or None)."""


@dataclass(frozen=True)
class Contract:
    """What a mission's run data must hold.

    Attributes:
        overrides: a short scenario (a minute or less per flight).
        expected: from the scenario, per variant (``None``: the mission flies none), per
            vehicle, the estimates.
    """

    overrides: tuple[str, ...]
    expected: Callable[[object], dict[str | None, dict[str, Estimates]]]


def _one(scn) -> dict[str | None, dict[str, Estimates]]:
    return {None: {"bauv": STANDARD}}


def _correction(scn) -> dict[str | None, dict[str, Estimates]]:
    dr = tuple((c, None) for c in ("dr_uncorrected", "dr_corrected", "dr_baseline"))
    return {law: {"bauv": STANDARD + dr} for law in ("compensated", "direct")}


def _swarm(scn) -> dict[str | None, dict[str, Estimates]]:
    from tasks.missions.swarm.team import TEAM_METHODS, track_column

    vehicles = ["leader", *(f"f{i + 1}" for i in range(scn.followers.count))]
    team: Estimates = ()
    if scn.followers.network.enabled:  # the team methods' estimates of every vehicle
        team = tuple((track_column(m), track_column(m)[: -len("pos")] + "P") for m in TEAM_METHODS)
    return {m: {v: STANDARD + team for v in vehicles} for m in scn.methods()}


def _trn(scn) -> dict[str | None, dict[str, Estimates]]:
    from tasks.missions.trn.scenario import METHODS

    own = tuple((m, None if m == "dr_log" else f"{m}_P") for m in METHODS)
    return {None: {"bauv": STANDARD + own}}


def _seed004(scn) -> dict[str | None, dict[str, Estimates]]:
    from tasks.missions.seed004.scenario import flown_filters

    return {f: {"bauv": STANDARD} for f in flown_filters(scn)}


EXPECTED: dict[str, Contract] = {
    "mission/short": Contract(tuple(SHORT), _one),
    "mission/survey": Contract(tuple(SHORT), _one),
    "mission/surfacing": Contract(tuple(SHORT), _one),
    # cut at 20 s, before leg 3: the run data is whole, the leg-3 metrics are left out (no NaN)
    "mission/correction": Contract(tuple(SHORT), _correction),
    "mission/swarm": Contract(
        (
            *SHORT,
            "followers.count=2",
            'navigation.methods=["ekf","ga1","ga2","dr"]',
            "followers.network.enabled=true",
        ),
        _swarm,
    ),
    "mission/trn": Contract(tuple(SHORT), _trn),
    "mission/seed004": Contract(
        (
            *SHORT,
            "seed004.duration_s=20",
            "seed004.train_paths=200",
            "seed004.surrogate_test_paths=100",
        ),
        _seed004,
    ),
}


def _missions() -> list[str]:
    return [n for n in registry.names() if isinstance(registry.get(n), MissionExperiment)]


def test_every_registered_mission_has_a_contract():
    assert sorted(_missions()) == sorted(EXPECTED)


def check_run_data(out, n_runs: int, expected: dict[str | None, dict[str, Estimates]]) -> None:
    """The batch's ``data/ticks`` has, for every run, variant and vehicle of ``expected``, and
    none other, rows with the truth and every expected estimate (and covariance) all present.

    Raises:
        AssertionError: naming the run, variant, vehicle and what is missing.
    """
    t = open_dataset(out, "ticks")
    names = set(t.column_names)
    variants = set(expected)
    if variants == {None}:
        assert "variant" not in names
        keys = t.select(["run", "vehicle"]).to_pandas().drop_duplicates()
        got = {(int(r), None, str(v)) for r, v in keys.itertuples(index=False)}
    else:
        keys = t.select(["run", "variant", "vehicle"]).to_pandas().drop_duplicates()
        got = {(int(r), str(a), str(v)) for r, a, v in keys.itertuples(index=False)}
    want = {(r, a, v) for r in range(n_runs) for a, vs in expected.items() for v in vs}
    assert got == want, (
        f"missing {sorted(want - got, key=str)}, extra {sorted(got - want, key=str)}"
    )
    for r, a, v in sorted(want, key=str):
        mask = pc.and_(pc.equal(t["run"], r), pc.equal(pc.cast(t["vehicle"], "string"), v))
        if a is not None:
            mask = pc.and_(mask, pc.equal(pc.cast(t["variant"], "string"), a))
        rows = t.filter(mask)
        where = f"run {r}, variant {a}, vehicle {v}"
        assert rows.num_rows > 1, where
        fields = ["truth_pos_east", "truth_pos_north", "truth_pos_up"]
        for col, cov in expected[a][v]:
            fields += [f"{col}_east", f"{col}_north"]
            if cov is not None:
                fields += [f"{cov}_east_east", f"{cov}_north_north", f"{cov}_east_north"]
        for f in fields:
            assert f in names, f"{where}: no field {f}"
            x = rows[f]
            assert x.null_count == 0, f"{where}: {f} has {x.null_count} nulls"
            assert np.isfinite(x.to_numpy()).all(), f"{where}: {f}"
        for _, cov in expected[a][v]:
            if cov is not None:
                assert (rows[f"{cov}_east_east"].to_numpy() >= 0).all(), f"{where}: {cov}"


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_every_run_variant_and_vehicle_has_the_truth_and_every_estimate(tmp_path, name):
    c = EXPECTED[name]
    out = tmp_path / "run"
    run(name, n_runs=RUNS, seed=1, out_dir=out, overrides=list(c.overrides), progress=False)
    scn = plan_batch(name, overrides=list(c.overrides)).scenario
    check_run_data(out, RUNS, c.expected(scn))
    # NaN never reaches an output: metrics.json is strict JSON (written with allow_nan=False),
    # and the tables print a dash for a value that does not exist
    json.loads((out / "metrics.json").read_text(), parse_constant=_refuse)
    assert not re.search(r"\bnan\b", (out / "tables.md").read_text(), re.IGNORECASE)


def _refuse(name: str):
    raise AssertionError(f"metrics.json holds {name}")
