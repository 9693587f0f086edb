"""The families of experiment names and the packages that register them, as the packages'
distributions declare them: Python entry points of the group :data:`GROUP`, one per family, named
by the family (the part of an experiment name before ``/``) and pointing at the package whose
import registers the family's experiments. This project declares its own in ``pyproject.toml``::

    [project.entry-points."bauv_sim.experiments"]
    my-family = "my_package.experiments"

and another installed distribution adds experiments the same way, without a change here. The
framework names no experiment: it reads the declarations (:func:`families`, with
:mod:`importlib.metadata`, once per process) and imports a family's package when it needs it
(:mod:`tasks.core.registry`).

A declaration is read from the installed metadata: after a family is added to ``pyproject.toml``,
``pip install -e .`` writes it there.

This module imports nothing of the project, so that :mod:`tasks.core.workers` can hand a family's
package to the fork server before ``bauv run`` imports anything heavy.
"""

from __future__ import annotations

import functools
import re

GROUP = "bauv_sim.experiments"
"""The entry-point group in which a distribution declares its families of experiments."""

_FAMILY = re.compile(r"[a-z0-9][a-z0-9_-]*")
_MODULE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*")


class FamilyError(ValueError):
    """A declaration of the entry-point group :data:`GROUP` that cannot be used (a bad family
    name or package path, or one family declared by two packages), or no declaration at all."""


@functools.cache
def families() -> dict[str, str]:
    """Family -> the package whose import registers its experiments, from the entry points of
    :data:`GROUP` of the installed distributions, sorted by family (read once per process).

    Raises:
        FamilyError: naming the entry point and what is wrong, or saying how to install the
            declarations when there is none.
    """
    from importlib.metadata import entry_points

    found: dict[str, str] = {}
    for ep in sorted(entry_points(group=GROUP), key=lambda e: (e.name, e.value)):
        where = f"entry point {ep.name!r} = {ep.value!r} of group {GROUP!r}"
        if not _FAMILY.fullmatch(ep.name):
            raise FamilyError(
                f"{where}: the family must be lower-case letters, digits, '-' or '_' (the part "
                "of an experiment name before '/')"
            )
        package = ep.value.strip()
        if not _MODULE.fullmatch(package):
            raise FamilyError(f"{where}: must name a package (dotted module path, no ':attr')")
        if found.get(ep.name, package) != package:
            raise FamilyError(
                f"{where}: family {ep.name!r} is already declared by package "
                f"{found[ep.name]!r}; a family has one package"
            )
        found[ep.name] = package
    if not found:
        raise FamilyError(
            f"no experiment package is declared (entry-point group {GROUP!r} is empty): install "
            "the project with pip install -e . so that its pyproject.toml's entry points are "
            "written to the installed metadata"
        )
    return found


def package_of(name: str) -> str | None:
    """The package of experiment ``name``'s family (``family/name``), or ``None`` if no package
    declares that family."""
    return families().get(name.split("/", 1)[0])
