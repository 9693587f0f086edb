"""The framework: registry, runner, store, report, figures, recording, run-data export, CLI.

Nothing here knows a particular experiment or mission."""

_EXPORTS: dict[str, tuple[str, str]] = {
    "BatchFailed": ("tasks.core.runner", "BatchFailed"),
    "BatchInterrupted": ("tasks.core.runner", "BatchInterrupted"),
    "BatchPlan": ("tasks.core.runner", "BatchPlan"),
    "Column": ("tasks.core.export", "Column"),
    "Experiment": ("tasks.core.registry", "Experiment"),
    "ExportError": ("tasks.core.export", "ExportError"),
    "Recording": ("tasks.core.recording", "Recording"),
    "ReportContext": ("tasks.core.registry", "ReportContext"),
    "ReportSummary": ("tasks.core.registry", "ReportSummary"),
    "Table": ("tasks.core.report", "Table"),
    "all_experiments": ("tasks.core.registry", "all_experiments"),
    "get": ("tasks.core.registry", "get"),
    "names": ("tasks.core.registry", "names"),
    "plan_batch": ("tasks.core.runner", "plan_batch"),
    "read_parquet": ("tasks.core.export", "read_parquet"),
    "read_text_log": ("tasks.core.recording", "read_text_log"),
    "read_time_series": ("tasks.core.recording", "read_time_series"),
    "register": ("tasks.core.registry", "register"),
    "run": ("tasks.core.runner", "run"),
    "scenario_doc": ("tasks.core.doc", "scenario_doc"),
    "write_metrics": ("tasks.core.report", "write_metrics"),
    "write_parquet": ("tasks.core.export", "write_parquet"),
    "write_tables": ("tasks.core.report", "write_tables"),
}
"""Public name -> (module, attribute), imported on first use."""

__all__ = [
    "BatchFailed",
    "BatchInterrupted",
    "BatchPlan",
    "Column",
    "Experiment",
    "ExportError",
    "Recording",
    "ReportContext",
    "ReportSummary",
    "Table",
    "all_experiments",
    "get",
    "names",
    "plan_batch",
    "read_parquet",
    "read_text_log",
    "read_time_series",
    "register",
    "run",
    "scenario_doc",
    "write_metrics",
    "write_parquet",
    "write_tables",
]


def __getattr__(name: str):
    """Import a public name from its module on first use (PEP 562): importing the package stays
    cheap (no MuJoCo, no matplotlib) and every name of ``__all__`` resolves."""
    target = _EXPORTS.get(name)
    if target is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    module, attr = target
    value = getattr(importlib.import_module(module), attr)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
