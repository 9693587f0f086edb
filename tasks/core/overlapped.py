"""The report of a batch on worker processes, written while the blocks are computed.

:class:`OverlappedReport` runs :meth:`Experiment.report` in a thread of this process, started
when the blocks are handed to worker processes (local or Dask); :class:`Arrivals` tells it which
blocks are saved. It reads each block as soon as it and the blocks before it are saved, in block
order and from their files, as the report after a batch on one worker does, so its outputs are
the same bytes.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from tasks.core import run_folder
from tasks.core.plan import BatchPlan
from tasks.core.registry import ReportContext, ReportSummary
from tasks.core.report_pool import ReportPool


class Abandoned(BaseException):
    """Raised in an overlapped report when the batch cannot complete (a block failed or could not
    be saved, or the batch was interrupted): the report stops without writing its outputs. Not an
    :class:`Exception`, so that a report's own ``except Exception`` does not swallow it."""


class Arrivals:
    """Which blocks are saved, for a report that reads them in block order while the others are
    still being computed (:class:`OverlappedReport`)."""

    def __init__(self, saved: set[int]):
        self._cond = threading.Condition()
        self._saved = set(saved)
        self._abandoned = False

    def saved(self, index: int) -> None:
        """Block ``index`` is saved (its file and its sha256 file are written)."""
        with self._cond:
            self._saved.add(index)
            self._cond.notify_all()

    def abandon(self) -> None:
        """The batch will not complete: a reader waiting for a block raises :class:`Abandoned`."""
        with self._cond:
            self._abandoned = True
            self._cond.notify_all()

    def wait(self, index: int) -> None:
        """Wait until block ``index`` is saved.

        Raises:
            Abandoned: if the batch was abandoned first.
        """
        with self._cond:
            while index not in self._saved and not self._abandoned:
                self._cond.wait()
            if index not in self._saved:
                raise Abandoned


class OverlappedReport:
    """:meth:`Experiment.report` in a thread of this process, started when the blocks are handed
    to worker processes: it reads each block as soon as it and the blocks before it are saved,
    so its merge (and whatever it does before the merge) overlaps the computation of the later
    blocks instead of following it (issue 13). It reads the blocks in block order, from their
    files, as the report after the batch does, so its outputs are the same bytes; it holds no
    more blocks than that report (the one it merges)."""

    def __init__(
        self,
        plan: BatchPlan,
        out_dir: Path,
        progress: bool,
        arrivals: Arrivals,
        pool: ReportPool | None = None,
    ):
        self._arrivals = arrivals
        self.summary: ReportSummary | None = None
        self.error: BaseException | None = None

        def blocks() -> Iterator[Any]:
            for i in range(len(plan.blocks)):
                arrivals.wait(i)
                yield run_folder.load_block(plan, out_dir, i)

        ctx = ReportContext(
            plan.scenario, plan.seed, plan.n_runs, out_dir, blocks(), quiet=not progress, pool=pool
        )

        def target() -> None:
            try:
                self.summary = plan.experiment.report(ctx)
            except Abandoned:
                pass
            except BaseException as exc:  # handed to the main thread
                self.error = exc

        self._thread = threading.Thread(target=target, name="bauv-report", daemon=True)
        self._thread.start()

    def abandon(self) -> None:
        """Stop the report (it is waiting for a block that will not come) and wait for it."""
        self._arrivals.abandon()
        self._thread.join(timeout=ABANDON_WAIT_S)

    def result(self) -> ReportSummary:
        """Wait for the report once every block is saved; its exception is raised here."""
        self._thread.join()
        if self.error is not None:
            raise self.error
        assert self.summary is not None
        return self.summary


ABANDON_WAIT_S = 10.0
"""How long an abandoned overlapped report may take to stop (it is between two blocks), s."""
