"""Streams are independent of each other, of worker layout and of which components exist."""

import numpy as np
import pytest

from bauv_sim import rng
from bauv_sim.errors import ConfigError


def test_same_address_same_numbers():
    a = rng.generator(7, 3, "sensor", "usbl").normal(size=10)
    b = rng.generator(7, 3, "sensor", "usbl").normal(size=10)
    assert np.array_equal(a, b)


def test_different_runs_components_and_seeds_differ():
    base = rng.generator(7, 3, "sensor", "usbl").normal(size=10)
    for other in [(7, 4, "sensor", "usbl"), (7, 3, "sensor", "ins"), (8, 3, "sensor", "usbl")]:
        assert not np.array_equal(base, rng.generator(*other).normal(size=10))


def test_stream_does_not_depend_on_order_or_neighbours():
    first = [g.normal() for g in rng.generators(1, range(5), "x")]
    shuffled = {r: rng.generator(1, r, "x").normal() for r in [4, 2, 0, 3, 1]}
    assert first == [shuffled[r] for r in range(5)]


def test_component_key_is_stable():
    # CRC-32, not Python's per-process salted hash(): the check value of the CRC-32 standard
    assert rng.component_key("123456789") == 0xCBF43926


@pytest.mark.parametrize("bad", [-1, 1.5, "3", True, 2**64])
def test_bad_seed(bad):
    with pytest.raises(ConfigError, match="seed"):
        rng.check_seed(bad)


@pytest.mark.parametrize("seed", [0, 1, 7, 2**32 - 1, 2**32, 2**40 + 3, rng.MAX_SEED])
@pytest.mark.parametrize("names", [(), ("x",), ("sensor", "usbl", "range", "noise")])
def test_batched_seeding_is_numpys_seed_sequence(seed, names):
    # the independent truth: numpy's own SeedSequence -> PCG64 seeding, run by run
    # one-word run indices are hashed in numpy; a two-word one sends the batch to numpy itself
    for runs in ([0, 1, 2, 99, 12345, 2**31, 2**32 - 1], [3, 2**32, 2**33 + 5]):
        _check_states(seed, runs, names)


def _check_states(seed, runs, names):
    got = rng.pcg64_states(seed, runs, *names)
    for run, (state, inc) in zip(runs, got, strict=True):
        want = np.random.PCG64(rng.seed_sequence(seed, run, *names)).state["state"]
        assert (state, inc) == (want["state"], want["inc"])


@pytest.mark.parametrize("runs", [[4], [3, 1, 4, 1, 5], list(range(60))])
def test_run_streams_draw_what_each_runs_generator_draws(runs):
    streams = rng.RunStreams(11, runs, "sensor", "log")
    gens = rng.generators(11, runs, "sensor", "log")
    # repeated draws of mixed kinds and sizes continue each run's stream exactly
    for kind, size, args in [
        ("uniform", 40, (-1.5, 1.5)),
        ("standard_normal", 33, ()),
        ("random", 7, ()),
        ("standard_normal", 1, ()),
        ("uniform", 2, (0.25, 2.0)),
        ("random", 1, ()),
    ]:
        got = streams.draw(kind, size, *args)
        want = np.stack([getattr(g, kind)(*args, size=size) for g in gens])
        assert got.shape == (len(runs), size)
        assert np.array_equal(got, want)
    with pytest.raises(ValueError, match="kind"):
        streams.draw("poisson", 3)
