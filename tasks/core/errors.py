"""Errors of a batch, apart from the runner so that the command line can tell them without
importing it (where a fork server is used, ``bauv`` starts it before the project's
imports)."""

from __future__ import annotations

from bauv_sim.errors import BauvSimError


class BatchInterrupted(BauvSimError):
    """The batch was interrupted (SIGINT); finished blocks are kept; ``--resume`` completes it."""


class BatchFailed(BauvSimError):
    """One or more blocks raised; the others were kept."""


class OutputError(BauvSimError):
    """A file of the run folder could not be written during the batch (e.g. the disk is full);
    the blocks saved before are kept and ``--resume`` completes the batch."""
