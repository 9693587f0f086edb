"""Declared configuration: frozen, typed models, TOML files and ``key=value`` overrides.

Every scenario, sensor and vehicle setting is a field of a :class:`Config` model (pydantic), frozen
after validation, with its unit in its name or docstring. Loading goes through one function,
:func:`load_config`, so that an unknown field, a wrong type, a value out of range or a non-finite
number always produce the same kind of one-line error naming the field, the value and what is
allowed (:class:`~bauv_sim.errors.ConfigError`).
"""

from __future__ import annotations

import copy
import os
import re
import tomllib
import types
import typing
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, TypeVar

import pydantic
import pydantic_core
from pydantic import BaseModel, ConfigDict

from bauv_sim.errors import ConfigError
from bauv_sim.field_names import nearest, user_loc

C = TypeVar("C", bound="Config")

MAX_NESTING = 32
"""The deepest nesting of tables and arrays a scenario may have (a mission scenario uses 5:
``guidance.waypoints`` is an array of tables inside a table). Checked on the text before TOML is
parsed and on the data before it is merged or validated: both recurse once per level, and a
5,000-deep array would exhaust Python's recursion limit."""
MAX_TOML_BYTES = 4 * 2**20
"""The largest scenario file or ``--set`` value, bytes (a 10,000-way-point mission is ~0.8 MB)."""
MAX_ARRAY_ITEMS = 100_000
"""The most elements of one array in a scenario."""
MAX_STRING_CHARS = 10_000
"""The longest string (value or key) in a scenario, characters."""


def check_structure(data: Any, source: str) -> None:
    """Refuse data too deep, too long or too large to be a scenario, before anything recurses
    into it (an iterative walk: no recursion of its own).

    Args:
        data: nested mappings, lists, tuples and scalars (as read from TOML or given in Python).
        source: how messages name where the data came from, e.g. ``"scenario file 'a.toml'"``.

    Raises:
        ConfigError: naming the path of the first offending element, what it holds and the
            limit (:data:`MAX_NESTING`, :data:`MAX_ARRAY_ITEMS`, :data:`MAX_STRING_CHARS`).
    """
    stack: list[tuple[Any, tuple[str, ...]]] = [(data, ())]
    while stack:
        node, path = stack.pop()
        where = ".".join(path) or "(top level)"
        if isinstance(node, str):
            if len(node) > MAX_STRING_CHARS:
                raise ConfigError(
                    f"{source}: {where} is a string of {len(node)} characters; at most "
                    f"{MAX_STRING_CHARS} allowed"
                )
            continue
        if not isinstance(node, Mapping | list | tuple):
            continue
        if len(path) >= MAX_NESTING:
            raise ConfigError(
                f"{source}: tables or arrays nested more than {MAX_NESTING} deep at "
                f"{'.'.join(path[:3])}...; at most {MAX_NESTING} levels allowed"
            )
        if isinstance(node, Mapping):
            for key, value in node.items():
                if isinstance(key, str) and len(key) > MAX_STRING_CHARS:
                    raise ConfigError(
                        f"{source}: a key of {len(key)} characters in {where}; at most "
                        f"{MAX_STRING_CHARS} allowed"
                    )
                stack.append((value, (*path, str(key)[:40])))
        else:
            if len(node) > MAX_ARRAY_ITEMS:
                raise ConfigError(
                    f"{source}: {where} is an array of {len(node)} elements; at most "
                    f"{MAX_ARRAY_ITEMS} allowed"
                )
            stack.extend((v, (*path, str(i))) for i, v in enumerate(node))


_TOML_SPECIAL = re.compile(r"[][{}\"'#\n]")
_BASIC_END = re.compile(r'["\\\n]')
_ML_BASIC_END = re.compile(r'["\\]')


def check_toml_text(text: str, source: str) -> None:
    """Refuse TOML text whose arrays and inline tables nest deeper than :data:`MAX_NESTING`,
    before :mod:`tomllib` (which recurses once per level, without a limit) parses it.

    Brackets are counted outside strings and comments, following TOML's string grammar (basic
    strings with escapes, literal strings, their multi-line forms whose closing delimiter may be
    preceded by one or two quotes of the content). Where the text is not valid TOML the count
    may differ from a parser's only after the first error, where :mod:`tomllib` stops.

    Raises:
        ConfigError: naming the line where the nesting exceeds the limit.
    """
    depth, i, n = 0, 0, len(text)
    while True:
        m = _TOML_SPECIAL.search(text, i)
        if m is None:
            return
        ch, i = m.group(), m.end()
        if ch in "[{":
            depth += 1
            if depth > MAX_NESTING:
                line = text.count("\n", 0, i) + 1
                raise ConfigError(
                    f"{source}: arrays or inline tables nested more than {MAX_NESTING} deep at "
                    f"line {line}; at most {MAX_NESTING} levels allowed"
                )
        elif ch in "]}":
            depth = max(depth - 1, 0)
        elif ch == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif ch == "'":
            if text.startswith("''", i):  # multi-line literal: ends at a run of 3 to 5 quotes
                j = text.find("'''", i + 2)
                i = n if j < 0 else j + 3
                while i < n and text[i] == "'":
                    i += 1
            else:
                j = min(k for k in (text.find("'", i), text.find("\n", i), n) if k >= 0)
                i = j + 1
        elif ch == '"':
            if text.startswith('""', i):  # multi-line basic: escapes; ends at 3 to 5 quotes
                i += 2
                while True:
                    e = _ML_BASIC_END.search(text, i)
                    if e is None:
                        i = n
                        break
                    if e.group() == "\\":
                        i = e.end() + 1
                        continue
                    run = e.start()
                    while run < n and text[run] == '"':
                        run += 1
                    i = run
                    if run - e.start() >= 3:
                        break
            else:
                while True:
                    e = _BASIC_END.search(text, i)
                    if e is None:
                        i = n
                        break
                    if e.group() == "\\":
                        i = e.end() + 1
                        continue
                    i = e.end()
                    break
        if i >= n:
            return


def loads_toml(text: str, source: str) -> dict[str, Any]:
    """Parse TOML text after the structure checks (:func:`check_toml_text`, then
    :func:`check_structure` on the result: dotted keys nest without brackets).

    Args:
        text: the TOML document.
        source: how messages name it.

    Raises:
        ConfigError: on text too large (:data:`MAX_TOML_BYTES`), nested too deep, or not TOML.
    """
    if len(text) > MAX_TOML_BYTES:
        raise ConfigError(
            f"{source}: {len(text)} characters; a scenario is at most {MAX_TOML_BYTES} bytes"
        )
    check_toml_text(text, source)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    check_structure(data, source)
    return data


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


def _shown(value: Any) -> str:
    """``repr`` of a value for a message, cut to 60 characters."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def check_model(model: Any) -> None:
    """Refuse a ``model`` argument that is not a :class:`Config` subclass.

    Raises:
        ConfigError: naming the argument, its value and type, and what is allowed.
    """
    if not (isinstance(model, type) and issubclass(model, Config)):
        what = "an instance" if isinstance(model, Config) else type(model).__name__
        raise ConfigError(
            f"model = {_shown(model)} ({what}): must be a Config subclass (a scenario type, "
            "e.g. get_experiment(name).scenario_type)"
        )


def check_overrides(overrides: Any, name: str = "overrides") -> tuple[str, ...]:
    """The ``dotted.key=value`` overrides as a tuple, after checking their types.

    A single string is refused rather than read one character at a time (or guessed to be one
    override): the argument is a list, ``["a.b=1"]``.

    Args:
        overrides: an iterable of strings (not a string itself).
        name: the argument's name in messages.

    Raises:
        ConfigError: naming the argument, its value's type and what is allowed.
    """
    if isinstance(overrides, str | bytes):
        raise ConfigError(
            f"{name} = {_shown(overrides)}: a single {type(overrides).__name__}; must be a list "
            f"of KEY=VALUE strings, e.g. [{overrides!r:.40}]"
        )
    if overrides is None or not isinstance(overrides, Iterable) or isinstance(overrides, Mapping):
        raise ConfigError(
            f"{name} = {_shown(overrides)} ({type(overrides).__name__}): must be a list of "
            "KEY=VALUE strings, e.g. ['sensors.usbl.period_s=20'] (or () for none)"
        )
    out = tuple(overrides)
    for i, text in enumerate(out):
        if not isinstance(text, str):
            raise ConfigError(
                f"{name}[{i}] = {_shown(text)} ({type(text).__name__}): must be a KEY=VALUE "
                "string, e.g. 'sensors.usbl.period_s=20'"
            )
    return out


def check_files(files: Any, name: str = "files") -> tuple[str | Path, ...]:
    """The scenario files as a tuple, after checking their types.

    Raises:
        ConfigError: for a single path (a ``str`` or ``Path``: the argument is a list,
            ``["a.toml"]``), a non-iterable, or an element that is not a path.
    """
    if isinstance(files, str | bytes | os.PathLike):
        raise ConfigError(
            f"{name} = {_shown(files)}: a single path; must be a list of TOML files, e.g. "
            f"[{str(files)!r:.40}]"
        )
    if files is None or not isinstance(files, Iterable) or isinstance(files, Mapping):
        raise ConfigError(
            f"{name} = {_shown(files)} ({type(files).__name__}): must be a list of TOML file "
            "paths (or () for none)"
        )
    out = tuple(files)
    for i, f in enumerate(out):
        if not isinstance(f, str | os.PathLike):
            raise ConfigError(
                f"{name}[{i}] = {_shown(f)} ({type(f).__name__}): must be a path (str or Path)"
            )
    return out


def parse_override(text: str) -> tuple[list[str], Any]:
    """Parse one ``dotted.key=value`` override.

    The value is read as a TOML value (``20``, ``0.5``, ``true``, ``"a"``, ``[1, 2]``); a bare word
    that is not valid TOML is taken as a string (``noise=uniform``).

    Args:
        text: the override as typed on the command line.

    Returns:
        ``(path, value)`` with the dotted key split into its parts.

    Raises:
        ConfigError: if ``text`` is not a string, there is no ``=`` or the key is empty.
    """
    if not isinstance(text, str):
        raise ConfigError(
            f"override = {_shown(text)} ({type(text).__name__}): must be a KEY=VALUE string, "
            "e.g. 'sensors.usbl.period_s=20'"
        )
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key or any(not part for part in key.split(".")):
        raise ConfigError(
            f"override {text!r}: expected KEY=VALUE with a dotted KEY, e.g. usbl.period_s=20"
        )
    raw = raw.strip()
    source = f"override {key}"
    if len(raw) > MAX_TOML_BYTES:
        raise ConfigError(f"{source}: a value of {len(raw)} characters; at most {MAX_TOML_BYTES}")
    check_toml_text(raw, source)
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    check_structure(value, source)
    return key.split("."), value


def apply_overrides(data: Mapping[str, Any], overrides: Iterable[str]) -> dict[str, Any]:
    """Return a deep copy of ``data`` with ``key=value`` overrides applied.

    Args:
        data: nested mapping (as read from TOML).
        overrides: ``dotted.key=value`` strings, applied in order.

    Returns:
        A new nested dict.

    Raises:
        ConfigError: if an override is not a string, or addresses inside a value that is not a
            table.
    """
    overrides = check_overrides(overrides)
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

    Before :mod:`tomllib` parses the file: at most :data:`MAX_TOML_BYTES` are read, and the
    nesting of its arrays and inline tables is checked (:func:`loads_toml`).

    Raises:
        ConfigError: naming the file when it is missing, unreadable, not UTF-8, not TOML, larger
            than :data:`MAX_TOML_BYTES`, or too deep, long or large to be a scenario
            (:func:`check_structure`).
    """
    source = f"scenario file {str(Path(path))!r}"
    text = read_text_file(
        path,
        MAX_TOML_BYTES,
        source,
        too_large=", the most a scenario file may hold",
        not_utf8="; TOML files are UTF-8",
    )
    return loads_toml(text, source)


def read_text_file(
    path: str | Path,
    max_bytes: int,
    source: str,
    *,
    encoding: str = "utf-8",
    too_large: str = "",
    not_utf8: str = "",
) -> str:
    """A user's text file, read whole but never beyond ``max_bytes`` (a hostile file is refused
    before it is held).

    Args:
        path: the file.
        max_bytes: the most it may hold, bytes.
        source: how messages name it (e.g. ``"scenario file 'x.toml'"``).
        encoding: ``"utf-8"``, or ``"utf-8-sig"`` to drop a byte-order mark.
        too_large, not_utf8: what the messages add after their own words.

    Raises:
        ConfigError: one line naming ``source``: not found, unreadable, larger than
            ``max_bytes``, or not UTF-8 (the byte and its offset).
    """
    try:
        with Path(path).open("rb") as fh:
            raw = fh.read(max_bytes + 1)
    except FileNotFoundError:
        raise ConfigError(f"{source}: not found") from None
    except OSError as exc:
        raise ConfigError(f"{source}: cannot read it ({exc.strerror})") from None
    if len(raw) > max_bytes:
        raise ConfigError(f"{source}: larger than {max_bytes} bytes{too_large}")
    try:
        return raw.decode(encoding)
    except UnicodeDecodeError as exc:
        raise ConfigError(
            f"{source}: not UTF-8 text (byte {exc.object[exc.start]:#04x} at offset "
            f"{exc.start}){not_utf8}"
        ) from None


def validate(model: type[C], data: Mapping[str, Any], what: str = "scenario") -> C:
    """Validate nested data into a frozen model.

    Args:
        model: the :class:`Config` subclass.
        data: nested mapping.
        what: how the caller names this configuration in messages.

    Returns:
        The validated model instance.

    Raises:
        ConfigError: naming the first invalid field, its value and what is allowed; or data too
            deep, long or large to be a configuration (:func:`check_structure`); or a ``model``
            that is not a :class:`Config` subclass or ``data`` that is not a mapping.
    """
    check_model(model)
    if not isinstance(data, Mapping):
        raise ConfigError(
            f"data = {_shown(data)} ({type(data).__name__}): must be a mapping of field names "
            "to values (a dict, as read from TOML)"
        )
    check_structure(data, what)
    try:
        return model.model_validate(data)
    except pydantic.ValidationError as exc:
        raise ConfigError(format_validation_error(exc, what, model)) from None


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
        ConfigError: on a bad file, override or value; or an argument of the wrong type (a
            ``model`` that is not a :class:`Config` subclass, a ``base`` that is not a mapping,
            a single string given for ``files`` or ``overrides``, which take lists), naming the
            argument, its type and what is allowed.
    """
    check_model(model)
    if base is not None and not isinstance(base, Mapping):
        raise ConfigError(
            f"base = {_shown(base)} ({type(base).__name__}): must be a mapping of scenario "
            "fields (an experiment's preset, a dict) or None"
        )
    files = check_files(files)
    overrides = check_overrides(overrides)
    check_structure(base or {}, "base")
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


def _annotation_at(model: type[BaseModel] | None, loc: tuple[Any, ...]) -> Any:
    """The type annotation of the field at ``loc`` (field names and array indices) under
    ``model``, or ``None`` where it cannot be told (a union of models, an unknown name)."""
    ann: Any = model
    for part in loc:
        ann = _without_none(ann)
        if isinstance(ann, type) and issubclass(ann, BaseModel):
            field = ann.model_fields.get(str(part))
            if field is None:
                return None
            ann = field.annotation
        elif typing.get_origin(ann) is tuple and isinstance(part, int):
            args = typing.get_args(ann)
            if len(args) == 2 and args[1] is Ellipsis:
                ann = args[0]
            elif part < len(args):
                ann = args[part]
            else:
                return None
        else:
            return None
    return _without_none(ann)


def _without_none(ann: Any) -> Any:
    """``X`` for ``X | None``; the annotation itself otherwise."""
    if typing.get_origin(ann) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(ann) if a is not type(None)]
        if len(args) == 1:
            return args[0]
    return ann


def _table_of(model: type[BaseModel]) -> str:
    """``a table with fields a, b (required) and c, d`` for a model's fields."""
    required = [n for n, f in model.model_fields.items() if f.is_required()]
    optional = [n for n, f in model.model_fields.items() if not f.is_required()]
    text = "a table"
    if required:
        text += f" with {', '.join(required)} (required)"
        if optional:
            text += f" and {', '.join(optional)}"
    elif optional:
        text += f" of {', '.join(optional)}"
    return text


def _kind_of(ann: Any) -> str:
    """What a value of annotation ``ann`` is, in a scenario file's words."""
    ann = _without_none(ann)
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        return _table_of(ann)
    if typing.get_origin(ann) is tuple:
        args = typing.get_args(ann)
        if len(args) == 2 and args[1] is Ellipsis:
            return f"an array of {_plural(args[0])}"
        if len({_plural(a) for a in args}) == 1:
            return f"an array of {len(args)} {_plural(args[0])}"
        return f"an array of {len(args)} elements"
    return {float: "a number", int: "an integer", bool: "true or false", str: "a string"}.get(
        ann, "a value of another type"
    )


def _plural(ann: Any) -> str:
    """Elements of annotation ``ann``, plural (``numbers``, ``tables with ...``)."""
    ann = _without_none(ann)
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        return "tables" + _table_of(ann).removeprefix("a table")
    return {float: "numbers", int: "integers", bool: "booleans", str: "strings"}.get(ann, "values")


def _shape_message(err: Mapping[str, Any], model: type[BaseModel] | None) -> tuple[tuple, str]:
    """The location and the words of a type or length error, in terms of the scenario's types
    (pydantic's "Input should be a valid tuple" names Python types, not TOML's)."""
    loc, kind, ctx = tuple(err["loc"]), err["type"], err.get("ctx") or {}
    if kind in ("too_short", "too_long"):
        bound = ctx.get("min_length") if kind == "too_short" else ctx.get("max_length")
        word = "at least" if kind == "too_short" else "at most"
        items = "element" if bound == 1 else "elements"
        return loc, f"must have {word} {bound} {items}, has {ctx.get('actual_length')}"
    if kind == "missing" and loc and isinstance(loc[-1], int):
        parent = _annotation_at(model, loc[:-1])
        has = f", has {len(err['input'])}" if isinstance(err.get("input"), list | tuple) else ""
        return loc[:-1], (
            f"must be {_kind_of(parent)}" if parent is not None else "too short"
        ) + has
    ann = _annotation_at(model, loc)
    if ann is None:
        return loc, err["msg"]
    return loc, f"must be {_kind_of(ann)}"


_SHAPE_ERRORS = {
    "tuple_type",
    "list_type",
    "model_type",
    "model_attributes_type",
    "dict_type",
    "too_short",
    "too_long",
    "float_type",
    "int_type",
    "bool_type",
    "bool_parsing",
    "string_type",
}


def format_validation_error(
    exc: pydantic.ValidationError, what: str, model: type[BaseModel] | None = None
) -> str:
    """One line: the first problem, ``what: field.path = value: what is allowed``, and how many
    more there are.

    A length error that pydantic adds to an array whose elements failed ("Tuple should have at
    least 1 item after validation, not 0", counted over the valid elements) is dropped: the
    elements' own errors say what is wrong. Type and length errors are worded in the scenario
    file's terms (arrays, tables with their fields, numbers) when ``model`` is given; then a field
    is named as the user types it (no union tags) and an unknown one with the nearest valid names
    (:mod:`bauv_sim.field_names`).
    """

    def typed(raw: Iterable[Any]) -> tuple[Any, ...]:
        return user_loc(model, tuple(raw)) if model is not None else tuple(raw)

    errors = exc.errors(include_url=False)
    locs = [tuple(e["loc"]) for e in errors]
    errors = [
        e
        for e in errors
        if not (
            e["type"] in ("too_short", "too_long")
            and any(len(o) > len(e["loc"]) and o[: len(e["loc"])] == tuple(e["loc"]) for o in locs)
        )
    ]
    lines = []
    for err in errors:
        loc = ".".join(str(p) for p in typed(err["loc"])) or "(top level)"
        msg = err["msg"]
        if err["type"] == "extra_forbidden":
            near = nearest(model, err["loc"]) if model is not None else []
            hint = f"; did you mean {' or '.join(near)}?" if near else ""
            lines.append(f"{what}: unknown field {loc!r} (value {_shown(err['input'])}){hint}")
            continue
        if msg.startswith("Value error, "):
            msg = msg[len("Value error, ") :]
        if err["type"] == "number_type":
            ctx = err.get("ctx") or {}
            where = ".".join([*(str(p) for p in typed(err["loc"])), str(ctx.get("field"))])
            lines.append(f"{what}: {where} = {ctx.get('value')}: {msg}")
            continue
        val = err.get("input")
        if err["type"] in _SHAPE_ERRORS or (
            err["type"] == "missing" and err["loc"] and isinstance(err["loc"][-1], int)
        ):
            at, msg = _shape_message(err, model)
            loc = ".".join(str(p) for p in typed(at)) or "(top level)"
            if err["type"] == "missing":
                lines.append(f"{what}: {loc} = {_shown(val)}: {msg}")
                continue
        if err["type"] == "missing":
            lines.append(f"{what}: {loc}: required field is missing")
            continue
        if not err["loc"]:
            lines.append(f"{what}: {msg}")
        elif isinstance(val, dict):
            lines.append(f"{what}: {loc}: {msg}")
        else:
            lines.append(f"{what}: {loc} = {_shown(val)}: {msg}")
    lines = list(dict.fromkeys(lines))
    if len(lines) > 1:
        more = len(lines) - 1
        return f"{lines[0]} (and {more} more problem{'s' if more > 1 else ''})"
    return lines[0] if lines else f"{what}: invalid"
