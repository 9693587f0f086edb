"""Declared configuration: frozen, typed models, TOML files and ``key=value`` overrides.

Every scenario, sensor and vehicle setting is a field of a :class:`Config` model (pydantic), frozen
after validation, with its unit in its name or docstring. Loading goes through one function,
:func:`load_config`, so that an unknown field, a wrong type, a value out of range or a non-finite
number always produce the same kind of one-line error naming the field, the value and what is
allowed (:class:`~bauv_sim.errors.ConfigError`).
"""

from __future__ import annotations

import copy
import types
import typing
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, TypeVar

import pydantic
import pydantic_core
import tomllib
from pydantic import BaseModel, ConfigDict

from bauv_sim.errors import ConfigError

C = TypeVar("C", bound="Config")


class Config(BaseModel):
    """Base of every configuration model: frozen, no unknown fields, finite numbers only.

    Build scenarios with :func:`load_config`, not ``model_validate``: a partial table given to
    ``model_validate`` replaces a sub-model whose defaults come from its parent (e.g. seed 000's
    uniform USBL errors) by that sub-model's bare defaults, while :func:`load_config` merges it over
    the parent's defaults.
    """

    model_config = ConfigDict(
        frozen=True, extra="forbid", allow_inf_nan=False, validate_default=True
    )

    @pydantic.model_validator(mode="before")
    @classmethod
    def _numbers_are_numbers(cls, data: Any) -> Any:
        """A number field takes a number: ``true`` is not 1.0 and ``"1.5"`` is not 1.5 (pydantic's
        lax mode would convert both); in a tuple of numbers, each element.

        Raises:
            ValueError: naming the field (the message becomes one line of :class:`ConfigError`).
        """
        if isinstance(data, Mapping):
            for name, field in cls.model_fields.items():
                if name in data:
                    problem = _number_problem(field.annotation, data[name])
                    if problem is not None:
                        raise pydantic_core.PydanticCustomError(
                            "number_type", problem[1], {"field": name, "value": problem[0]}
                        ) from None
        return data


def _number_kind(annotation: Any) -> str | None:
    """``"float"``/``"int"`` when every alternative of ``annotation`` (``None`` aside) is that
    number type, else ``None`` (the field also takes other values, and pydantic checks them)."""
    if annotation is float:
        return "float"
    if annotation is int:
        return "int"
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        kinds = {_number_kind(a) for a in typing.get_args(annotation) if a is not type(None)}
        return kinds.pop() if len(kinds) == 1 else None
    return None


def _number_problem(annotation: Any, value: Any) -> tuple[str, str] | None:
    """What is wrong with ``value`` for a number field of type ``annotation``: ``(the value as
    shown, what is allowed)``, or ``None``."""
    kind = _number_kind(annotation)
    if kind is not None:
        if isinstance(value, bool | str | bytes):
            what = "a boolean" if isinstance(value, bool) else "a string"
            shown = str(value).lower() if isinstance(value, bool) else repr(value)
            return shown, f"must be {'an integer' if kind == 'int' else 'a number'}, not {what}"
        return None
    if typing.get_origin(annotation) is tuple and isinstance(value, list | tuple):
        args = typing.get_args(annotation)
        if len(args) == 2 and args[1] is Ellipsis:
            args = (args[0],) * len(value)
        if len(args) == len(value):
            for i, (a, v) in enumerate(zip(args, value, strict=True)):
                problem = _number_problem(a, v)
                if problem is not None:
                    return repr(list(value)), f"element {i} {problem[1]}"
    return None


def parse_override(text: str) -> tuple[list[str], Any]:
    """Parse one ``dotted.key=value`` override.

    The value is read as a TOML value (``20``, ``0.5``, ``true``, ``"a"``, ``[1, 2]``); a bare word
    that is not valid TOML is taken as a string (``noise=uniform``).

    Args:
        text: the override as typed on the command line.

    Returns:
        ``(path, value)`` with the dotted key split into its parts.

    Raises:
        ConfigError: if there is no ``=`` or the key is empty.
    """
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key or any(not part for part in key.split(".")):
        raise ConfigError(
            f"override {text!r}: expected KEY=VALUE with a dotted KEY, e.g. usbl.period_s=20"
        )
    raw = raw.strip()
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return key.split("."), value


def apply_overrides(data: Mapping[str, Any], overrides: Iterable[str]) -> dict[str, Any]:
    """Return a deep copy of ``data`` with ``key=value`` overrides applied.

    Args:
        data: nested mapping (as read from TOML).
        overrides: ``dotted.key=value`` strings, applied in order.

    Returns:
        A new nested dict.

    Raises:
        ConfigError: if an override addresses inside a value that is not a table.
    """
    out = copy.deepcopy(dict(data))
    for text in overrides:
        path, value = parse_override(text)
        node: Any = out
        for i, part in enumerate(path):
            where = ".".join(path[: i + 1])
            last = i == len(path) - 1
            if isinstance(node, list):
                # an element of an array of tables: guidance.waypoints.0.surface=true
                if not part.isdigit() or int(part) >= len(node):
                    raise ConfigError(
                        f"override {text!r}: {where}: index must be 0..{len(node) - 1}"
                    )
                if last:
                    node[int(part)] = value
                else:
                    node = node[int(part)]
                continue
            if not isinstance(node, dict):
                parent = ".".join(path[:i])
                raise ConfigError(f"override {text!r}: {parent} is a value, not a table")
            if last:
                if part == "kind" and node.get("kind", value) != value:
                    # a new kind starts from its own defaults, not the old kind's fields
                    node.clear()
                node[part] = value
            else:
                node = node.setdefault(part, {})
    return out


def read_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file.

    Raises:
        ConfigError: naming the file when it is missing, unreadable, not UTF-8 or not TOML.
    """
    p = Path(path)
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ConfigError(f"scenario file {str(p)!r}: not found") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(
            f"scenario file {str(p)!r}: not UTF-8 text (byte {exc.object[exc.start]:#04x} at "
            f"offset {exc.start}); TOML files are UTF-8"
        ) from None
    except OSError as exc:
        raise ConfigError(f"scenario file {str(p)!r}: cannot read it ({exc.strerror})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"scenario file {str(p)!r}: {exc}") from None


def validate(model: type[C], data: Mapping[str, Any], what: str = "scenario") -> C:
    """Validate nested data into a frozen model.

    Args:
        model: the :class:`Config` subclass.
        data: nested mapping.
        what: how the caller names this configuration in messages.

    Returns:
        The validated model instance.

    Raises:
        ConfigError: naming the first invalid field, its value and what is allowed.
    """
    try:
        return model.model_validate(data)
    except pydantic.ValidationError as exc:
        raise ConfigError(format_validation_error(exc, what)) from None


def load_config(
    model: type[C],
    base: Mapping[str, Any] | None = None,
    files: Iterable[str | Path] = (),
    overrides: Iterable[str] = (),
    what: str = "scenario",
) -> C:
    """Merge defaults, TOML files and overrides, then validate.

    Args:
        model: the :class:`Config` subclass to build.
        base: nested defaults applied first (e.g. an experiment's preset).
        files: TOML files merged in order over ``base`` (tables merge, values replace).
        overrides: ``dotted.key=value`` strings applied last.
        what: how messages name this configuration.

    Returns:
        The validated, frozen model.

    Raises:
        ConfigError: on a bad file, override or value.
    """
    data = merge(model_defaults(model), base or {})
    for f in files:
        data = merge(data, read_toml(f))
    data = apply_overrides(data, overrides)
    return validate(model, data, what)


def merge(a: Mapping[str, Any], b: Mapping[str, Any]) -> dict[str, Any]:
    """Deep-merge ``b`` over ``a``: tables merge recursively, other values replace.

    A table of ``b`` whose ``kind`` differs from the ``kind`` of the table it lands on replaces it
    whole (switching ``current.kind`` from ``uniform`` to ``gyre`` must not keep the uniform
    current's fields).
    """
    out = copy.deepcopy(dict(a))
    for k, v in b.items():
        old = out.get(k)
        if (
            isinstance(v, Mapping)
            and isinstance(old, Mapping)
            and not ("kind" in v and v["kind"] != old.get("kind"))
        ):
            out[k] = merge(old, v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def model_defaults(model: type[BaseModel]) -> dict[str, Any]:
    """The model's defaults as nested data, so that a partial table given by a preset, a file or
    an override fills in over the parent's defaults instead of the sub-model's bare defaults.

    Returns an empty dict for a model with required fields.
    """
    try:
        return model().model_dump(mode="json", exclude_none=True)
    except pydantic.ValidationError:
        return {}


def to_plain(cfg: BaseModel) -> dict[str, Any]:
    """The model as plain nested data (for writing the resolved scenario as TOML or JSON)."""
    return cfg.model_dump(mode="json", exclude_none=True)


def format_validation_error(exc: pydantic.ValidationError, what: str) -> str:
    """One line per problem: ``what: field.path = value: message``."""
    lines = []
    for err in exc.errors(include_url=False):
        loc = ".".join(str(p) for p in err["loc"]) or "(top level)"
        msg = err["msg"]
        if err["type"] == "extra_forbidden":
            lines.append(f"{what}: unknown field {loc!r} (value {err['input']!r})")
            continue
        if msg.startswith("Value error, "):
            msg = msg[len("Value error, ") :]
        if err["type"] == "number_type":
            ctx = err.get("ctx") or {}
            where = ".".join([*(str(p) for p in err["loc"]), str(ctx.get("field"))])
            lines.append(f"{what}: {where} = {ctx.get('value')}: {msg}")
            continue
        if err["type"] == "missing":
            lines.append(f"{what}: {loc}: required field is missing")
            continue
        val = err.get("input")
        if not err["loc"]:
            lines.append(f"{what}: {msg}")
        elif isinstance(val, dict):
            lines.append(f"{what}: {loc}: {msg}")
        else:
            lines.append(f"{what}: {loc} = {val!r}: {msg}")
    return "\n".join(lines)
