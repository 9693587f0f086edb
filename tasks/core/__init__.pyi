# The public names of tasks.core, read by type checkers and by lazy_loader.attach_stub in
# __init__.py, which imports each from its module on first use (`name as name`: re-exported).

from .doc import scenario_doc as scenario_doc
from .errors import BatchFailed as BatchFailed, BatchInterrupted as BatchInterrupted
from .export import (
    Column as Column,
    ExportError as ExportError,
    open_dataset as open_dataset,
    read_parquet as read_parquet,
    write_parquet as write_parquet,
)
from .plan import BatchPlan as BatchPlan, plan_batch as plan_batch
from .recording import (
    entity_paths as entity_paths,
    read_static as read_static,
    read_text_log as read_text_log,
    read_time_series as read_time_series,
    Recording as Recording,
)
from .registry import (
    all_experiments as all_experiments,
    Experiment as Experiment,
    get as get,
    names as names,
    register as register,
    register_modules as register_modules,
    ReportContext as ReportContext,
    ReportSummary as ReportSummary,
)
from .report import Table as Table, write_metrics as write_metrics, write_tables as write_tables
from .runner import run as run
