"""The framework: registry, runner, store, report, figures, recording, CLI."""
