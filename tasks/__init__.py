"""tasks: missions and experiments registered by name, the Monte Carlo runner, reports and the CLI.

Depends on :mod:`nav` and :mod:`bauv_sim`; nothing depends on it.
"""
