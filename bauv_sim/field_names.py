"""A configuration's field names as the user types them, and the nearest ones to a misspelt name.

pydantic names a field inside a tagged union with the tag: ``--set current.speed=0.3`` fails at
``current.uniform.speed`` (``uniform`` is the current's ``kind``, not a field anyone typed).
:func:`user_loc` drops such tags, and :func:`nearest` finds the valid dotted names closest to an
unknown one (:mod:`difflib`, on the full dotted names), for :mod:`bauv_sim.config`'s messages.
"""

from __future__ import annotations

import difflib
import types
import typing
from collections.abc import Sequence
from typing import Any

from pydantic import BaseModel

Loc = tuple[int | str, ...]
"""A field's location: field names and array indices, outermost first."""


def _plain(ann: Any) -> Any:
    """``X`` for ``Annotated[X, ...]`` and ``X | None``; the annotation itself otherwise."""
    while typing.get_origin(ann) is typing.Annotated:
        ann = typing.get_args(ann)[0]
    if typing.get_origin(ann) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(ann) if a is not type(None)]
        if len(args) == 1:
            return _plain(args[0])
    return ann


def _is_model(ann: Any) -> bool:
    return isinstance(ann, type) and issubclass(ann, BaseModel)


def _union_models(ann: Any) -> list[type[BaseModel]]:
    """The models of a union of models (a tagged union such as ``CurrentConfig``), else ``[]``."""
    if typing.get_origin(ann) not in (typing.Union, types.UnionType):
        return []
    args = [_plain(a) for a in typing.get_args(ann) if a is not type(None)]
    return args if args and all(_is_model(a) for a in args) else []


def _member(members: Sequence[type[BaseModel]], tag: int | str) -> type[BaseModel] | None:
    """The member of a union that pydantic's location part ``tag`` names: its ``kind`` (a tagged
    union) or its class name (a plain one), else ``None``."""
    for m in members:
        kind = m.model_fields.get("kind")
        if (kind is not None and kind.default == tag) or m.__name__ == tag:
            return m
    return None


def _inner(ann: Any, part: int | str) -> Any:
    """The annotation one step inside ``ann`` at ``part`` (a field, an index, a key), or
    ``None`` where it cannot be told."""
    if _is_model(ann):
        f = ann.model_fields.get(str(part))
        return f.annotation if f is not None else None
    origin, args = typing.get_origin(ann), typing.get_args(ann)
    if origin in (tuple, list) and args:
        if origin is list or (len(args) == 2 and args[1] is Ellipsis):
            return args[0]
        return args[part] if isinstance(part, int) and part < len(args) else None
    if origin is dict and len(args) == 2:
        return args[1]
    return None


def user_loc(model: type[BaseModel], loc: Sequence[int | str]) -> Loc:
    """``loc`` as the user typed it: without the tags pydantic adds inside a tagged union.

    Args:
        model: the configuration model the location is in.
        loc: pydantic's location of an error (field names, array indices, union tags).

    Returns:
        The location without union tags, e.g. ``("current", "speed")`` for pydantic's
        ``("current", "uniform", "speed")``.
    """
    out: list[int | str] = []
    ann: Any = model
    for part in loc:
        ann = _plain(ann)
        members = _union_models(ann)
        if members:
            m = _member(members, part)
            if m is not None:
                ann = m
                continue
        out.append(part)
        ann = _inner(ann, part) if ann is not None else None
    return tuple(out)


def _paths(ann: Any, prefix: Loc, along: Loc | None) -> list[str]:
    """Every dotted field name under ``ann``; in a union on the error's path (``along``, the rest
    of pydantic's location) only the member the error is in, elsewhere every member's."""
    ann = _plain(ann)
    members = _union_models(ann)
    if members:
        m = _member(members, along[0]) if along else None
        if m is not None:
            return _paths(m, prefix, along[1:])  # type: ignore[index]
        return list(dict.fromkeys(p for m in members for p in _paths(m, prefix, None)))
    if _is_model(ann):
        out = []
        for name, f in ann.model_fields.items():
            out.append(".".join(str(p) for p in (*prefix, name)))
            on_path = along[1:] if along and str(along[0]) == name else None
            out += _paths(f.annotation, (*prefix, name), on_path)
        return out
    if along and isinstance(along[0], int):  # an array of tables: the element the error is in
        return _paths(_inner(ann, along[0]), (*prefix, along[0]), along[1:])
    return []


def nearest(model: type[BaseModel], loc: Sequence[int | str], n: int = 3) -> list[str]:
    """The valid dotted field names nearest to the unknown one at pydantic's location ``loc``.

    Candidates are every dotted name of ``model`` but the typed name's own tables, scored by
    :class:`difflib.SequenceMatcher` on the full dotted names; kept are those scoring at least
    ``CUTOFF`` whose last part also resembles the typed one's (:data:`LAST_CUTOFF`) and within
    :data:`MARGIN` of the best.

    Args:
        model: the configuration model.
        loc: pydantic's location of the unknown field.
        n: at most this many names.

    Returns:
        Up to ``n`` dotted names (as the user types them), closest first; none when nothing is
        close.
    """
    parts = [str(p) for p in user_loc(model, loc)]
    typed = ".".join(parts)
    ancestors = {".".join(parts[:i]) for i in range(1, len(parts))}
    scored = []
    for name in dict.fromkeys(_paths(model, (), tuple(loc))):
        if name == typed or name in ancestors:
            continue
        last = difflib.SequenceMatcher(None, parts[-1], name.rsplit(".", 1)[-1]).ratio()
        full = difflib.SequenceMatcher(None, typed, name).ratio()
        if full >= CUTOFF and last >= LAST_CUTOFF:
            scored.append((full, name))
    scored.sort(key=lambda s: -s[0])
    return [name for score, name in scored[:n] if score >= scored[0][0] - MARGIN]


CUTOFF = 0.6
"""The least :meth:`difflib.SequenceMatcher.ratio` of a suggestion's full dotted name."""
LAST_CUTOFF = 0.6
"""The least ratio of a suggestion's last part to the typed name's last part."""
MARGIN = 0.05
"""Suggestions score within this of the best one."""
