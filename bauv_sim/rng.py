"""Seeds and independent random streams.

Every random source gets its own stream, addressed by the run's seed, the run's index in a Monte
Carlo batch and a path of component names (``"sensor", "usbl", "noise"``). The stream of a
component therefore does not depend on which other components exist, on the order they are built
in, or on which worker runs which runs of a batch: run ``i`` of seed ``s`` always draws the same
numbers.

A stream is a :class:`numpy.random.Generator` over PCG64, seeded by a
:class:`numpy.random.SeedSequence` with ``entropy=seed`` and ``spawn_key=(run, *crc32(names))``
(Gymnasium's ``utils/seeding.py`` is the model; the names are hashed with CRC-32 so the key is
stable across Python processes).
"""

from __future__ import annotations

import zlib
from collections.abc import Iterable

import numpy as np

from bauv_sim.errors import ConfigError

MAX_SEED = 2**63 - 1


def check_seed(seed: object) -> int:
    """Validate a user seed.

    Args:
        seed: the seed as given.

    Returns:
        The seed as an ``int`` in [0, 2**63 - 1].

    Raises:
        ConfigError: if the seed is not an integer in that range.
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise ConfigError(f"seed = {seed!r}: must be an integer in [0, {MAX_SEED}]")
    if not 0 <= int(seed) <= MAX_SEED:
        raise ConfigError(f"seed = {seed}: must be an integer in [0, {MAX_SEED}]")
    return int(seed)


def component_key(name: str) -> int:
    """Stable 32-bit key of a component name (CRC-32 of its UTF-8 bytes)."""
    return zlib.crc32(name.encode("utf-8"))


def seed_sequence(seed: int, run: int, *names: str) -> np.random.SeedSequence:
    """The seed sequence of one component of one run.

    Args:
        seed: the batch seed, >= 0.
        run: the run's index in the batch, >= 0.
        *names: the component path, e.g. ``("sensor", "usbl", "noise")``.

    Returns:
        A :class:`numpy.random.SeedSequence` unique to ``(seed, run, names)``.
    """
    if run < 0:
        raise ConfigError(f"run index = {run}: must be >= 0")
    return np.random.SeedSequence(
        entropy=check_seed(seed), spawn_key=(int(run), *(component_key(n) for n in names))
    )


def generator(seed: int, run: int, *names: str) -> np.random.Generator:
    """The random generator of one component of one run (see :func:`seed_sequence`)."""
    return np.random.Generator(np.random.PCG64(seed_sequence(seed, run, *names)))


def generators(seed: int, runs: Iterable[int], *names: str) -> list[np.random.Generator]:
    """One generator per run for the same component (see :func:`generator`)."""
    return [generator(seed, r, *names) for r in runs]
