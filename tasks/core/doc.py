"""Reference text of a scenario model: every field, nested, with its value, description, unit and
allowed range (``bauv show NAME --doc``).

Everything comes from the pydantic models themselves: the field's description, its type (a
``Literal`` lists the allowed values), its constraints (``gt``, ``ge``, ``lt``, ``le``, lengths)
and its unit, read from the field name's suffix as the project names fields (``_deg``, ``_m_s``,
``_s``...; see ``docs/architecture.md``, Conventions) or given in the description.
"""

from __future__ import annotations

import types
import typing
from typing import Any

from annotated_types import Ge, Gt, Le, Lt, MaxLen, MinLen, MultipleOf
from pydantic import BaseModel

__all__ = ["UNIT_SUFFIXES", "field_rows", "scenario_doc", "unit_of"]

UNIT_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_m_s_per_sqrt_s", "m/s/sqrt(s)"),
    ("_m_per_tick", "m per control tick"),
    ("_deg_s", "deg/s"),
    ("_rad_s", "rad/s"),
    ("_m_s2", "m/s^2"),
    ("_m_s", "m/s"),
    ("_m2", "m^2"),
    ("_kn", "kn"),
    ("_deg", "deg"),
    ("_rad", "rad"),
    ("_hz", "Hz"),
    ("_kg", "kg"),
    ("_pa", "Pa"),
    ("_s", "s"),
    ("_m", "m"),
    ("_n", "N"),
    ("_w", "W"),
    ("_j", "J"),
)
"""Field-name suffix -> unit, longest first (``speed_m_s`` is in m/s, not in s)."""


def unit_of(name: str) -> str | None:
    """The unit a field's name declares (``"sigma_heading_deg"`` -> ``"deg"``), or None."""
    low = name.lower()
    for suffix, unit in UNIT_SUFFIXES:
        if low.endswith(suffix):
            return unit
    return None


def _submodel(tp: Any) -> type[BaseModel] | None:
    return tp if isinstance(tp, type) and issubclass(tp, BaseModel) else None


def _args(tp: Any) -> tuple[Any, ...]:
    return typing.get_args(tp)


def _is_union(tp: Any) -> bool:
    return typing.get_origin(tp) in (typing.Union, types.UnionType)


def _type_text(tp: Any) -> str:
    origin = typing.get_origin(tp)
    if origin is typing.Literal:
        return "one of " + ", ".join(repr(a) for a in _args(tp))
    if _is_union(tp):
        return " or ".join(_type_text(a) for a in _args(tp))
    if origin in (list, tuple):
        inner = [a for a in _args(tp) if a is not Ellipsis]
        return f"{origin.__name__} of " + (" , ".join(_type_text(a) for a in inner) or "any")
    if origin is dict:
        k, v = _args(tp) or (Any, Any)
        return f"table of {_type_text(k)} -> {_type_text(v)}"
    if tp is type(None):
        return "none"
    return getattr(tp, "__name__", str(tp))


def _range_text(metadata: list[Any]) -> str:
    parts = []
    for m in metadata:
        if isinstance(m, Gt):
            parts.append(f"> {m.gt:g}")
        elif isinstance(m, Ge):
            parts.append(f">= {m.ge:g}")
        elif isinstance(m, Lt):
            parts.append(f"< {m.lt:g}")
        elif isinstance(m, Le):
            parts.append(f"<= {m.le:g}")
        elif isinstance(m, MinLen):
            parts.append(f"at least {m.min_length} items")
        elif isinstance(m, MaxLen):
            parts.append(f"at most {m.max_length} items")
        elif isinstance(m, MultipleOf):
            parts.append(f"multiple of {m.multiple_of:g}")
    return ", ".join(parts)


def _nested(tp: Any) -> tuple[type[BaseModel] | None, bool]:
    """The model a field holds (directly, optionally, or as list items) and whether a list."""
    if (m := _submodel(tp)) is not None:
        return m, False
    if _is_union(tp):
        models = [_submodel(a) for a in _args(tp) if a is not type(None)]
        if len(models) == 1 and models[0] is not None:
            return models[0], False
    if typing.get_origin(tp) in (list, tuple):
        inner = [a for a in _args(tp) if a is not Ellipsis]
        if len(inner) == 1 and (m := _submodel(inner[0])) is not None:
            return m, True
    return None, False


def _alternatives(tp: Any) -> list[type[BaseModel]]:
    """The models of a union of several models (empty otherwise)."""
    if not _is_union(tp):
        return []
    models = [_submodel(a) for a in _args(tp) if a is not type(None)]
    return [m for m in models if m is not None] if len(models) > 1 else []


def _value_text(v: Any) -> str:
    if isinstance(v, BaseModel):
        return "{...}"
    if isinstance(v, str):
        return repr(v)
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, (list, tuple)) and v and isinstance(v[0], BaseModel):
        return f"[{len(v)} tables]"
    return str(v)


def field_rows(model: type[BaseModel], value: BaseModel | None = None, prefix: str = ""):
    """Every field of ``model``, depth first: dicts with ``path``, ``value``, ``type``,
    ``unit``, ``range``, ``description`` and ``section`` (True for a nested table)."""
    for name, f in model.model_fields.items():
        path = f"{prefix}{name}"
        v = getattr(value, name, None) if value is not None else None
        sub, many = _nested(f.annotation)
        desc = f.description or ""
        alternatives = _alternatives(f.annotation)
        if sub is None and alternatives and isinstance(v, BaseModel):
            # a union of tables (e.g. the kinds of current): the one the scenario holds
            sub = type(v)
            others = ", ".join(m.__name__ for m in alternatives)
            desc = (desc + "; " if desc else "") + f"one of {others} (its 'kind' field selects)"
        if sub is not None:
            doc = (sub.__doc__ or "").strip().splitlines()
            yield {
                "path": path + ("[]" if many else ""),
                "value": None,
                "type": ("list of " if many else "") + sub.__name__,
                "unit": None,
                "range": _range_text(f.metadata),
                "description": desc or (doc[0] if doc else ""),
                "section": True,
            }
            item = v[0] if many and v else (None if many else v)
            yield from field_rows(sub, item, path + ("[]." if many else "."))
            continue
        yield {
            "path": path,
            "value": None if value is None else _value_text(v),
            "type": _type_text(f.annotation),
            "unit": unit_of(name),
            "range": _range_text(f.metadata),
            "description": desc,
            "section": False,
        }


def scenario_doc(model: type[BaseModel], value: BaseModel | None = None, title: str = "") -> str:
    """The reference text of a scenario model (and a resolved scenario's values).

    Args:
        model: the scenario model (a pydantic model, possibly nested).
        value: a resolved scenario of that model; its values are shown as "= value".
        title: a first line.

    Returns:
        One block per field: ``path = value  [unit]  (type; range)`` then its description,
        indented; nested tables as headers.
    """
    lines = [title, ""] if title else []
    for r in field_rows(model, value):
        depth = r["path"].count(".")
        pad = "  " * depth
        if r["section"]:
            lines.append(
                f"{pad}[{r['path']}]  {r['type']}" + (f" ({r['range']})" if r["range"] else "")
            )
            if r["description"]:
                lines.append(f"{pad}    {r['description']}")
            continue
        head = f"{pad}{r['path'].rsplit('.', 1)[-1]}"
        if r["value"] is not None:
            head += f" = {r['value']}"
        meta = [f"unit: {r['unit']}" if r["unit"] else None, r["type"], r["range"] or None]
        head += "  (" + "; ".join(m for m in meta if m) + ")"
        lines.append(head)
        if r["description"]:
            lines.append(f"{pad}    {r['description']}")
    return "\n".join(lines) + "\n"
