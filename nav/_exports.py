"""Lazily exported public names of a package (PEP 562), the one implementation that
``bauv_sim``, ``nav``, ``tasks``, ``tasks.core`` and ``tasks.closed_loop`` share.

It lives in :mod:`nav`, the lowest layer, because every package may import it (``nav`` imports
neither :mod:`bauv_sim` nor :mod:`tasks`); it is plain Python with no dependency.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable, Mapping
from typing import Any


def lazy_exports(
    namespace: dict[str, Any],
    exports: Mapping[str, tuple[str, str]],
    eager: Iterable[str] = (),
) -> tuple[list[str], Callable[[str], Any], Callable[[], list[str]]]:
    """``__all__``, ``__getattr__`` and ``__dir__`` for a package that imports its public names
    from their modules on first use, so that importing the package stays cheap (no MuJoCo, no
    matplotlib) and every name of ``__all__`` resolves.

    Args:
        namespace: the package's ``globals()`` (a resolved name is cached there).
        exports: public name -> ``(module, attribute)`` it is read from.
        eager: public names the package defines or imports itself.

    Returns:
        ``(__all__, __getattr__, __dir__)`` to assign in the package's ``__init__``; ``__all__``
        is sorted.
    """
    package = namespace["__name__"]
    names = sorted({*exports, *eager})

    def __getattr__(name: str) -> Any:
        target = exports.get(name)
        if target is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module, attr = target
        value = getattr(importlib.import_module(module), attr)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(names))

    return names, __getattr__, __dir__
