"""The framework: registry, runner, store, report, figures, recording, run-data export, CLI.

Nothing here knows a particular experiment or mission."""

from nav._exports import lazy_exports

_EXPORTS: dict[str, tuple[str, str]] = {
    "BatchFailed": ("tasks.core.errors", "BatchFailed"),
    "BatchInterrupted": ("tasks.core.errors", "BatchInterrupted"),
    "BatchPlan": ("tasks.core.plan", "BatchPlan"),
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
    "plan_batch": ("tasks.core.plan", "plan_batch"),
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

__all__, __getattr__, __dir__ = lazy_exports(globals(), _EXPORTS)
