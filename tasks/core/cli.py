"""The ``bauv`` command line.

    bauv --version                          the package version (and git commit), Python,
                                            MuJoCo, numpy, platform
    bauv list
    bauv show NAME [--set k=v ...] [--doc]  print the resolved scenario as TOML (--doc: every
                                            field with its description, unit, allowed range)
    bauv run NAME [--runs N] [--seed S] [--out DIR] [--set k=v ...] [--scenario FILE ...]
                  [--workers K] [--executor local|dask] [--address tcp://host:8786] [--resume]
    bauv view RUN_DIR [--web] [--web-port P] [--grpc-port Q]
    bauv compare RUN... [--metric GLOB ...] [--out DIR]   metrics of run folders side by side

Exit status: 0 on success, 2 on invalid input (one line naming the field, the value and what is
allowed; nothing written: bad options, a batch too big for memory, an out folder that cannot be
created), 1 when a run fails (the message says which run, when and why; the report is written) or
a file cannot be written during the batch (a full disk: the saved blocks are kept), 130 when
interrupted by Ctrl-C, SIGTERM or SIGHUP (finished blocks are kept, workers stopped; ``--resume``
completes the batch).
"""

from __future__ import annotations

import atexit
import contextlib
import gc
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import click
import tomli_w

from bauv_sim.errors import BauvSimError, ConfigError
from nav.errors import NavError

GL_VARIABLE = "MUJOCO_GL"
"""MuJoCo's and dm_control's OpenGL backend variable; ``bauv run`` sets it to ``disable`` unless
it is set."""

EXIT_INPUT = 2
EXIT_FAILED = 1
EXIT_INTERRUPTED = 130


def _print_version(ctx: click.Context, param: click.Parameter, value: bool) -> None:
    if not value or ctx.resilient_parsing:
        return
    from bauv_sim.provenance import version_text

    click.echo(version_text())
    ctx.exit()


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.option(
    "--version",
    is_flag=True,
    expose_value=False,
    is_eager=True,
    callback=_print_version,
    help="Print the version (with the git commit in a checkout) and exit.",
)
def cli() -> None:
    """bauv-sim: a biomimetic AUV and its navigation, simulated."""


@cli.command("list")
def list_cmd() -> None:
    """List the registered experiments and missions."""
    from tasks.core import catalog
    from tasks.core.console import labelled

    entries = catalog.load()  # no experiment package imported (tests keep it equal)
    width = max(len(name) for name, _ in entries)
    for name, summary in entries:
        click.echo(labelled(name, summary, width))


@cli.command("show")
@click.argument("name")
@click.option("--set", "overrides", multiple=True, metavar="KEY=VALUE", help="Override a field.")
@click.option(
    "--scenario",
    "files",
    multiple=True,
    type=click.Path(dir_okay=False),
    help="TOML file merged over the experiment's preset.",
)
@click.option(
    "--doc", is_flag=True, help="Every field with its value, description, unit and allowed range."
)
def show_cmd(name: str, overrides: tuple[str, ...], files: tuple[str, ...], doc: bool) -> None:
    """Print the resolved scenario of NAME as TOML (every field, with its default)."""
    from bauv_sim.config import load_config, to_plain
    from tasks.core import registry

    exp = registry.get(name)
    scn = load_config(exp.scenario_type, exp.preset, files, overrides)
    if doc:
        from tasks.core.doc import scenario_doc

        title = f"{name}: {exp.summary}\nscenario {exp.scenario_type.__name__}; set a field "
        title += "with --set path=value (TOML value)"
        click.echo(scenario_doc(exp.scenario_type, scn, title), nl=False)
        return
    click.echo(tomli_w.dumps(to_plain(scn)), nl=False)


@cli.command("run")
@click.argument("name")
@click.option(
    "--runs", type=int, default=None, help="Monte Carlo runs (default: the experiment's)."
)
@click.option("--seed", type=int, default=None, help="Batch seed (default 0).")
@click.option(
    "--out",
    type=click.Path(file_okay=False),
    default=None,
    help="Run folder (default runs/<name>/<time>-seed<S>).",
)
@click.option(
    "--set",
    "overrides",
    multiple=True,
    metavar="KEY=VALUE",
    help="Override a scenario field, e.g. --set sensors.usbl.period_s=20.",
)
@click.option(
    "--scenario",
    "files",
    multiple=True,
    type=click.Path(dir_okay=False),
    help="TOML file merged over the experiment's preset (before --set).",
)
@click.option("--workers", type=int, default=1, show_default=True, help="Worker processes.")
@click.option(
    "--executor",
    type=click.Choice(["local", "dask"]),
    default="local",
    show_default=True,
    help="Where runs execute.",
)
@click.option("--address", default=None, help="Dask scheduler address (default: a local cluster).")
@click.option("--resume", is_flag=True, help="Complete the interrupted batch in --out.")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def run_cmd(
    name: str,
    runs: int | None,
    seed: int | None,
    out: str | None,
    overrides: tuple[str, ...],
    files: tuple[str, ...],
    workers: int,
    executor: str,
    address: str | None,
    resume: bool,
    quiet: bool,
) -> None:
    """Run experiment or mission NAME and write its run folder."""
    from tasks.core import workers as workers_mod

    workers_mod.prepare_batch_process()  # before numpy is imported, here and in the workers
    # a batch renders nothing through OpenGL (figures: matplotlib; recordings: rerun): MuJoCo and
    # dm_control then skip their search for a GL backend at import (GLFW's library, about 0.05 s
    # of a mission's start-up), here and in the workers, unless the user chose a backend
    os.environ.setdefault(GL_VARIABLE, "disable")
    if executor == "local" and workers > 1:
        # before the project's imports: where workers come from a fork server (not where bauv
        # forks them itself), the server imports the project meanwhile
        workers_mod.start_fork_server(name)
    from tasks.core.console import wrap
    from tasks.core.runner import run

    out_dir, summary = run(
        name,
        n_runs=runs,
        seed=seed,
        out_dir=out,
        overrides=overrides,
        scenario_files=files,
        executor=executor,
        workers=workers,
        address=address,
        resume=resume,
        progress=not quiet,
    )
    click.echo(wrap(summary.text), nl=False)  # tables are fitted already, prose is wrapped
    rec = out_dir / "recording.rrd"
    if rec.is_file():
        click.echo(f"recording: {rec}  (open it with: bauv view {out_dir} [--web])")
    click.echo(f"tables:    {out_dir / 'tables.md'}\nmetrics:   {out_dir / 'metrics.json'}")
    if summary.failures:
        click.echo(
            f"error: {len(summary.failures)} run(s) failed; the report covers the runs that "
            "completed",
            err=True,
        )
    if summary.diverged:
        click.echo(
            f"error: {len(summary.diverged)} estimate(s) diverged, named in the report",
            err=True,
        )
    if summary.failures or summary.diverged:
        sys.exit(EXIT_FAILED)


def rerun_command() -> list[str]:
    """How to start the rerun viewer of the installed rerun-sdk: on Linux its binary itself,
    where the ``rerun_cli`` package ships it (or ``RERUN_CLI_PATH``, which rerun's own launcher
    honours), so that the server is this process's child and :func:`run_viewer` can tie its life
    to ours; else the ``rerun`` launcher, a Python script that starts the binary as its child."""
    binary = os.environ.get("RERUN_CLI_PATH")
    if not binary:
        with contextlib.suppress(ImportError):
            import rerun_cli

            binary = str(Path(rerun_cli.__file__).parent / "rerun")
    if binary and sys.platform.startswith("linux") and os.access(binary, os.X_OK):
        return [binary]
    exe = shutil.which("rerun", path=str(Path(sys.executable).parent)) or shutil.which("rerun")
    return [exe] if exe else [sys.executable, "-m", "rerun"]


PR_SET_PDEATHSIG = 1
"""``prctl`` option: the signal a process receives when the thread that created it ends
(``linux/prctl.h``)."""


def _die_with(parent_pid: int) -> None:
    """In the viewer's process, between fork and exec: have the kernel send it SIGKILL when
    ``bauv`` ends, however it ends (SIGKILL included, which no handler sees), and exit at once
    if ``bauv`` is already gone. The setting survives ``exec`` (``prctl(2)``)."""
    import ctypes

    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent_pid:
        os._exit(1)


def view_command(
    recording: Path, web: bool, web_port: int = 9090, grpc_port: int = 9876
) -> list[str]:
    """The viewer command line; its servers listen on 127.0.0.1 only.

    With ``web`` the rerun process serves the web viewer (``web_port``) and the recording over
    gRPC (``grpc_port``); without, the native viewer still starts a gRPC server (``grpc_port``),
    which rerun binds to 0.0.0.0 unless told otherwise (``rerun --help``: ``--bind``, default
    ``0.0.0.0``).
    """
    cmd = rerun_command()
    if web:
        return [
            *cmd,
            "--serve-web",
            "--bind",
            "127.0.0.1",
            "--web-viewer-port",
            str(web_port),
            "--port",
            str(grpc_port),
            str(recording),
        ]
    return [*cmd, "--bind", "127.0.0.1", "--port", str(grpc_port), str(recording)]


def run_viewer(cmd: list[str]) -> int:
    """Run the viewer in its own process group and take the whole group down with us.

    SIGINT, SIGTERM, SIGHUP (the terminal closed) and normal exit stop the group (where the
    ``rerun`` launcher is used, it starts the viewer binary as a child: stopping only the
    launcher would leave the server running). SIGKILL of ``bauv`` cannot be caught: on Linux the
    viewer starts with ``PR_SET_PDEATHSIG`` set to SIGKILL, and it is the binary itself
    (:func:`rerun_command`; a launcher's child would not inherit the setting), so the server
    ends with ``bauv`` however ``bauv`` ends. Elsewhere a killed ``bauv`` leaves it running.
    """
    linux = sys.platform.startswith("linux")
    parent = os.getpid()
    proc = subprocess.Popen(
        cmd, start_new_session=True, preexec_fn=(lambda: _die_with(parent)) if linux else None
    )

    def stop(*_: object) -> None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGTERM)

    def stop_and_exit(*_: object) -> None:
        stop()
        sys.exit(0)

    previous = {s: signal.signal(s, stop_and_exit) for s in _stop_signals()}
    try:
        return proc.wait()
    except KeyboardInterrupt:
        return 0
    finally:
        stop()
        with contextlib.suppress(subprocess.TimeoutExpired):
            proc.wait(timeout=5)
        for s, handler in previous.items():
            signal.signal(s, handler)


@cli.command("view")
@click.argument("run_dir", type=click.Path(exists=True, file_okay=False))
@click.option("--web", is_flag=True, help="Serve the web viewer on 127.0.0.1 instead.")
@click.option("--web-port", type=int, default=9090, show_default=True)
@click.option("--grpc-port", type=int, default=9876, show_default=True)
def view_cmd(run_dir: str, web: bool, web_port: int, grpc_port: int) -> None:
    """Open RUN_DIR's recording.rrd in the rerun viewer."""
    rec = Path(run_dir) / "recording.rrd"
    if not rec.is_file():
        raise ConfigError(f"run_dir = {run_dir!r}: no recording.rrd in it")
    cmd = view_command(rec, web, web_port, grpc_port)
    if web:
        grpc = f"rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc_port}%2Fproxy"
        click.echo(
            f"serving {rec} on 127.0.0.1 only: open http://127.0.0.1:{web_port}/?url={grpc}"
            " (Ctrl-C to stop)"
        )
    code = run_viewer(cmd)
    if code != 0 and not web:
        click.echo("the native viewer needs a display; try: bauv view RUN_DIR --web", err=True)
    sys.exit(code)


@cli.command("compare")
@click.argument("runs", nargs=-1, required=True, metavar="RUN...")
@click.option(
    "--metric",
    "patterns",
    multiple=True,
    metavar="GLOB",
    help="Metrics by glob on metrics.json's dotted names, e.g. 'aggregate.*.mean' (repeatable; "
    "default: every number outside a list).",
)
@click.option(
    "--out",
    metavar="DIR",
    default=None,
    help="Also write compare.md, compare.csv, compare.png and compare.pdf in DIR (new or empty).",
)
def compare_cmd(runs: tuple[str, ...], patterns: tuple[str, ...], out: str | None) -> None:
    """Show the metrics (metrics.json) of run folders RUN... side by side."""
    from tasks.core import compare

    result = compare.compare(runs, patterns)
    if out is not None:
        compare.check_out(out)
    click.echo(compare.terminal_table(result), nl=False)
    if out is not None:
        click.echo(f"wrote {', '.join(str(p) for p in compare.write(result, out))}")
        if len(result.metrics) > compare.FIGURE_PANELS:
            n = f"{compare.FIGURE_PANELS} of {len(result.metrics)}"
            click.echo(f"compare.png shows the first {n} metrics (choose them with --metric)")


def _stop_signals() -> list[signal.Signals]:
    """SIGTERM and SIGHUP, unless ignored (``nohup bauv run ...`` must survive the terminal)."""
    sigs = [s for s in (signal.SIGTERM, getattr(signal, "SIGHUP", None)) if s is not None]
    return [s for s in sigs if signal.getsignal(s) is not signal.SIG_IGN]


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(signal.Signals(signum).name)


def _exit_now(status: int) -> None:
    """Exit an interrupted ``bauv`` at once, without the interpreter's shutdown.

    What a batch finished is already on disk (each block written atomically). A pool worker
    stopped while it was writing its result into the pool's pipe leaves the executor's manager
    thread waiting for the rest of that message, and the interpreter joins that thread at exit:
    ``sys.exit`` would then hang (seen under load, about one stop in ten). The streams are
    flushed first.
    """
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(status)


def main(argv: list[str] | None = None) -> None:
    """Entry point: run the CLI and map errors to exit statuses without tracebacks.

    SIGTERM and SIGHUP (the terminal closed) stop ``bauv`` as Ctrl-C does: a batch keeps its
    finished blocks and stops its workers, the viewer stops the rerun server it started. A signal
    ignored when ``bauv`` starts (``nohup``) stays ignored.
    """
    from tasks.core.errors import BatchFailed, BatchInterrupted
    from tasks.core.files import os_error_text

    # last at exit (atexit runs last in, first out): the interpreter's final garbage collections
    # would scan every object of the project, ~0.1 s of a kinematic batch (issue 13); whatever
    # bauv writes is closed by then
    atexit.register(gc.freeze)
    for sig in _stop_signals():
        with contextlib.suppress(ValueError):  # not the main thread
            signal.signal(sig, _interrupt)
    try:
        cli.main(args=argv, prog_name="bauv", standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("aborted", err=True)
        sys.exit(EXIT_INTERRUPTED)
    except click.ClickException as exc:
        exc.show()
        sys.exit(EXIT_INPUT)
    except BatchInterrupted as exc:
        click.echo(str(exc), err=True)
        _exit_now(EXIT_INTERRUPTED)
    except ConfigError as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_INPUT)
    except BatchFailed as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_FAILED)
    except (BauvSimError, NavError) as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_FAILED)
    except KeyboardInterrupt:
        click.echo("interrupted", err=True)
        _exit_now(EXIT_INTERRUPTED)
    except OSError as exc:
        click.echo(f"error: {os_error_text(exc)}", err=True)
        sys.exit(EXIT_FAILED)


if __name__ == "__main__":
    main()
