"""The framework: registry, runner, store, report, figures, recording, run-data export, CLI.

Nothing here knows a particular experiment or mission."""

import lazy_loader

# the public names: those of __init__.pyi, each imported from its module on first use
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
