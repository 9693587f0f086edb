"""The framework: registry, runner, store, report, figures, recording, run-data export, CLI.

Nothing here knows a particular experiment or mission."""
