"""Where a batch's blocks are computed: the executors of the runner.

``local``: in this process for one worker (:class:`InlineExecutor`: a block is computed when the
runner asks for its result, so each block is saved as soon as it is computed), else a
:class:`~concurrent.futures.ProcessPoolExecutor` whose workers are forked from ``bauv`` itself,
which has imported the experiment, before it starts any thread, or from a fork server with the
experiment preloaded where that is not safe, or spawned where there is neither
(:mod:`tasks.core.workers`). ``dask``: ``distributed.Client(address)``, or a local cluster with
``workers`` single-threaded processes when no address is given. :func:`check_executor` checks
the options without starting or connecting to anything.
"""

from __future__ import annotations

import collections
import concurrent.futures as cf
import contextlib
import os
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from bauv_sim.errors import ConfigError
from tasks.core import workers as workers_mod


class InlineExecutor(cf.Executor):
    """One local worker: each submitted call runs in the calling thread when its result is asked
    for (:meth:`~concurrent.futures.Future.result` of the returned future), not in ``submit``.

    The runner asks for the blocks one by one in its save loop, so each block is saved and the
    progress bar moves as soon as that block is computed, and Ctrl-C keeps the finished blocks, as
    with a process pool.
    """

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future:
        return LazyFuture(fn, args, kwargs)


class LazyFuture(cf.Future):
    """A future whose call runs, in the calling thread, the first time its result is asked for."""

    def __init__(self, fn: Callable[..., Any], args: tuple[Any, ...], kwargs: dict[str, Any]):
        super().__init__()
        self._call: tuple[Callable[..., Any], tuple[Any, ...], dict[str, Any]] | None = (
            fn,
            args,
            kwargs,
        )

    def _run(self) -> None:
        if self._call is None or not self.set_running_or_notify_cancel():
            return
        fn, args, kwargs = self._call
        self._call = None
        try:
            value = fn(*args, **kwargs)
        except Exception as exc:
            self.set_exception(exc)
        else:
            self.set_result(value)

    def result(self, timeout: float | None = None) -> Any:
        self._run()
        return super().result(timeout)

    def exception(self, timeout: float | None = None) -> BaseException | None:
        self._run()
        return super().exception(timeout)


def completed(futures: dict[cf.Future, int]) -> Iterator[cf.Future]:
    """The futures as they finish: in submission order for lazy (inline) futures, which run when
    asked for, else in completion order (:func:`concurrent.futures.as_completed`)."""
    if all(isinstance(f, LazyFuture) for f in futures):
        pending = collections.deque(futures)
        while pending:  # held here only until handed out, so a saved block can be freed
            yield pending.popleft()
    else:
        yield from cf.as_completed(futures)  # which drops its references as it yields


EXECUTORS = ("local", "dask")
DASK_CONNECT_TIMEOUT_S = 10.0
"""How long ``--executor dask --address ...`` waits for the scheduler before giving up, s."""


def check_executor(kind: str, workers: int, address: str | None) -> None:
    """Check the executor options without starting or connecting to anything.

    Args:
        kind: ``"local"`` or ``"dask"``.
        workers: worker processes on this machine, an integer from 1 to
            :func:`tasks.core.workers.usable_cpus` (each computes one block at a time on one
            CPU; more would only share the CPUs and multiply the memory held). Not used with an
            ``address``: the scheduler's workers compute the blocks.
        address: a Dask scheduler address ``[scheme://]host:port`` or ``None``.

    Raises:
        ConfigError: naming the option, its value and what is allowed.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ConfigError(f"workers = {workers!r}: must be an integer >= 1")
    if kind not in EXECUTORS:
        raise ConfigError(f"executor = {kind!r}: must be 'local' or 'dask'")
    if address is None:
        cpus = workers_mod.usable_cpus()
        if workers > cpus:
            raise ConfigError(
                f"workers = {workers}: at most {cpus} on this machine (the CPUs this process may "
                "run on; each worker computes one block on one CPU)"
            )
        return
    if kind == "local":
        raise ConfigError(
            f"address = {address!r}: --address is for --executor dask (the local executor "
            "takes none)"
        )
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        scheme, where = parse_address(address, strict=False)
        if scheme in ("tcp", "tls"):
            host, port = parse_host_port(where)
            if not host or port is None:
                raise ValueError("no host")
    except (ValueError, TypeError):
        raise ConfigError(
            f"address = {address!r}: must be a Dask scheduler address such as tcp://host:8786"
        ) from None


@contextlib.contextmanager
def make_executor(
    kind: str, workers: int, address: str | None, preload: Sequence[str] = ()
) -> Iterator[cf.Executor]:
    """Open an executor of the given kind.

    Args:
        kind: ``"local"`` or ``"dask"``.
        workers: worker processes (local, and local Dask cluster), >= 1; the runner asks for no
            more than the blocks it has to compute.
        address: a Dask scheduler address (``tcp://host:8786``) or ``None``.
        preload: modules local workers import before they are forked (the experiment's), see
            :func:`tasks.core.workers.pool_context`.

    Yields:
        The executor; it is shut down on exit.

    Raises:
        ConfigError: on invalid options (:func:`check_executor`), or when the Dask scheduler at
            ``address`` does not answer within :data:`DASK_CONNECT_TIMEOUT_S`.
    """
    check_executor(kind, workers, address)
    if kind == "local":
        if workers == 1:
            yield InlineExecutor()
            return
        ex = cf.ProcessPoolExecutor(
            max_workers=workers,
            mp_context=workers_mod.pool_context(preload),
            initializer=workers_mod.init_worker,
            initargs=(os.getpid(),),
        )
        try:
            yield ex
        except BaseException:
            # interrupted or failed: stop the blocks being computed now, not after they finish
            workers_mod.terminate_workers(ex)
            raise
        else:
            ex.shutdown(wait=False, cancel_futures=True)
        return
    import logging

    from distributed import Client, LocalCluster

    logging.getLogger("distributed").setLevel(logging.ERROR)
    cluster = None
    if address is None:
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )
        client = Client(cluster)
    else:
        try:
            client = Client(address, timeout=f"{DASK_CONNECT_TIMEOUT_S}s")
        except (OSError, TimeoutError, ValueError) as exc:
            what = " ".join(str(exc).split())
            raise ConfigError(
                f"address = {address!r}: no Dask scheduler answered within "
                f"{DASK_CONNECT_TIMEOUT_S:g} s ({what})"
            ) from None
    try:
        yield client.get_executor(pure=False)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
