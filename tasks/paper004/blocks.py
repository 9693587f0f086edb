"""The blocks of seed 004's kinematic experiments: each case's test paths flown with every filter
of the bank (:func:`tasks.paper004.sim.fly`) and reduced to per-step sums, as plain data."""

from __future__ import annotations

from dataclasses import dataclass, field

from tasks.core import store
from tasks.paper004.scenario import Paper004Scenario, case_gains, cases, setting
from tasks.paper004.sim import LoopSums, fly

# ----------------------------------------------------------------------------------------------
# Blocks


store.plain_data("paper004.LoopSums")(LoopSums)


@store.plain_data("paper004.Paper004Block")
@dataclass
class Paper004Block:
    """A block's sums per case (:class:`tasks.paper004.sim.LoopSums`), in :func:`cases` order.

    Attributes:
        runs: run indices.
        labels: case labels.
        sums: one :class:`LoopSums` per case.
        gains: case label -> the gains' arrays (block with run 0 only), so the report can save
            them without training again.
    """

    runs: tuple[int, ...]
    labels: tuple[str, ...]
    sums: list
    gains: dict = field(default_factory=dict)


def reduce_block(scn: Paper004Scenario, seed: int, runs: tuple[int, ...]) -> Paper004Block:
    """Fly a block of test paths for every case and reduce them."""
    sums, gains = [], {}
    for c in cases(scn):
        g = case_gains(scn, c, seed)
        sums.append(fly(setting(scn, c), seed, runs, g, sample_runs=scn.report.sample_runs))
        if 0 in runs:
            gains[c.label] = {
                "F": g.F,
                "f": g.f,
                "H": g.H,
                "h": g.h,
                "p_tilde": g.p_tilde,
                "p_hat": g.p_hat,
            }
            if g.beta_lo is not None and g.beta_hi is not None:
                gains[c.label] |= {"beta_lo": g.beta_lo, "beta_hi": g.beta_hi}
            gains[c.label] |= {
                "clipped": int(g.info.get("clipped", 0)),
                "top_share": float(g.info.get("top_share", 0.0)),
            }
    return Paper004Block(tuple(runs), tuple(c.label for c in cases(scn)), sums, gains)
