"""A file format for plain data that cannot execute code when it is read.

The runner keeps each finished block of a batch on disk so that ``--resume`` can complete it later;
those files are read back by a later process, possibly from a folder someone else gave us. They are
therefore never pickled (unpickling a crafted file runs arbitrary code): this module encodes *plain
data* only, and decoding only ever builds plain values and instances of classes registered here.

What is plain data:

* ``None``, ``bool``, ``int``, ``float`` (every bit kept: -0.0, NaN payloads, infinities,
  subnormals), ``str``;
* :class:`numpy.ndarray` (not a subclass) of bool, signed or unsigned integer, float, complex or
  unicode dtype, any shape, byte order and memory order (C or Fortran) — never object, structured
  or datetime dtype — and numpy scalars of those dtypes;
* ``list``, ``tuple`` and ``dict`` (exactly those types; keys are any hashable plain value such as
  ``str``, ``int``, ``float`` or tuples of them, and their order is kept);
* instances of dataclasses and pydantic models **registered** with :func:`plain_data` under a
  stable name. A dataclass is stored field by field; a field whose metadata is
  :data:`NOT_STORED` (``field(default=None, metadata=store.NOT_STORED)``) is left out and gets its
  default when the instance is rebuilt, e.g. a live object kept beside the results. A pydantic
  model is stored as its ``model_dump(mode="python")`` and rebuilt with ``model_validate``.

The file is a zip archive, every member stored uncompressed with a fixed time stamp (so the same
value always gives the same bytes)::

    manifest.json        {"format": "bauv-sim/plain-data", "version": 1,
                          "header": NODE, "value": NODE, "arrays": ["arrays/000000.npy", ...]}
    arrays/000000.npy    one .npy file per array (numpy's format, written and read with
    ...                  allow_pickle=False)

A NODE is JSON: ``null``, ``true``/``false``, an integer, a finite float (Python's shortest repr,
which reads back to the same bits), a string, a JSON list (a Python list), or an object tagged by
``"$"``: ``{"$": "float", "bits": "7ff8000000000000"}`` (a non-finite float, its IEEE 754 bits),
``{"$": "tuple", "items": [...]}``, ``{"$": "dict", "items": [[KEY, VALUE], ...]}``,
``{"$": "ndarray", "index": i, "dtype": "<f8", "shape": [...]}``, ``{"$": "scalar", "dtype":
"<f8", "bytes": "hex"}`` (``"value"`` instead of ``"bytes"`` for unicode),
``{"$": "dataclass", "name": "...", "fields": {...}}`` and ``{"$": "model", "name": "...",
"data": NODE}``.

Decoding looks a dataclass or model name up in this module's registry only: it never imports a
module and never calls anything the file names. Any problem (not a zip, truncated, a damaged
member, an unknown tag or type name, a wrong field set, an array whose dtype or shape disagrees
with the manifest, ...) raises :class:`StoreError` naming the file and what is wrong.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
import re
import struct
import zipfile
from collections.abc import Callable, Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any, BinaryIO, NamedTuple, TypeVar

import numpy as np
from pydantic import BaseModel, ValidationError

from bauv_sim.errors import BauvSimError

FORMAT = "bauv-sim/plain-data"
"""The ``format`` of every manifest."""

VERSION = 1
"""The version of the encoding; a file of another version is refused."""

MANIFEST = "manifest.json"
NOT_STORED: Mapping[str, Any] = MappingProxyType({"store": False})
"""Dataclass field metadata of a field that is not stored (it must have a default)."""

_ARRAY_KINDS = "biufcU"
_DTYPE_RE = re.compile(r"[<>|][biufcU][0-9]{1,6}")
_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_.:/-]*")
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)
_NPY_VERSIONS = {
    (1, 0): np.lib.format.read_array_header_1_0,
    (2, 0): np.lib.format.read_array_header_2_0,
}

T = TypeVar("T", bound=type)


class StoreError(BauvSimError, ValueError):
    """A value is not plain data, or a file cannot be read back as plain data.

    The message names the value's path (encoding) or the file (decoding) and what is wrong.
    """


class Stored(NamedTuple):
    """A decoded file.

    Attributes:
        header: the header given to :func:`dumps` (a dict with string keys).
        value: the stored value.
    """

    header: dict[str, Any]
    value: Any


# ---------------------------------------------------------------------------------------------
# The registry of classes


@dataclasses.dataclass(frozen=True)
class _Entry:
    name: str
    cls: type
    is_model: bool
    fields: tuple[str, ...]  # the stored fields of a dataclass, in order


_BY_NAME: dict[str, _Entry] = {}
_BY_CLASS: dict[type, _Entry] = {}


def _entry(name: str, cls: Any) -> _Entry:
    if isinstance(cls, type) and issubclass(cls, BaseModel):
        return _Entry(name, cls, True, ())
    if not (isinstance(cls, type) and dataclasses.is_dataclass(cls)):
        raise TypeError(f"store.plain_data({name!r}): {cls!r} is not a dataclass or pydantic model")
    stored = []
    for f in dataclasses.fields(cls):
        if f.metadata.get("store", True) is False:
            if f.init and f.default is dataclasses.MISSING:
                if f.default_factory is dataclasses.MISSING:
                    raise TypeError(
                        f"store.plain_data({name!r}): field {f.name!r} is not stored, so it needs "
                        "a default"
                    )
            continue
        if not f.init:
            raise TypeError(
                f"store.plain_data({name!r}): field {f.name!r} has init=False; mark it "
                "metadata=store.NOT_STORED or make it an __init__ field"
            )
        stored.append(f.name)
    return _Entry(name, cls, False, tuple(stored))


def plain_data(name: str) -> Callable[[T], T]:
    """Register a dataclass or pydantic model as plain data under a stable name.

    Use it as a class decorator (``@store.plain_data("paper001.MissionBlock")``) or call it on a
    class defined elsewhere (``store.plain_data("nav.metrics.Histogram")(Histogram)``). The name
    is written into files and looked up when they are read: it is part of the file format, so
    keep it when the class moves. It is not a module path and is never imported.

    Args:
        name: the stable name (letters, digits, ``_ . : / -``).

    Returns:
        A decorator that registers the class and returns it unchanged.

    Raises:
        ValueError: if the name is malformed, or taken by another class, or the class is already
            registered under another name.
        TypeError: if the class is neither a dataclass nor a pydantic model, or a field that is
            not stored has no default.
    """
    if not isinstance(name, str) or not _NAME_RE.fullmatch(name):
        raise ValueError(f"store.plain_data: name {name!r} must match {_NAME_RE.pattern}")

    def register(cls: T) -> T:
        entry = _entry(name, cls)
        old = _BY_NAME.get(name)
        if old is not None and old.cls is not cls:
            same = (old.cls.__module__, old.cls.__qualname__) == (cls.__module__, cls.__qualname__)
            if not same:
                raise ValueError(
                    f"store.plain_data: name {name!r} is taken by "
                    f"{old.cls.__module__}.{old.cls.__qualname__}"
                )
            del _BY_CLASS[old.cls]  # the same class, imported again
        prev = _BY_CLASS.get(cls)
        if prev is not None and prev.name != name:
            raise ValueError(
                f"store.plain_data: {cls.__qualname__} is already registered as {prev.name!r}"
            )
        _BY_NAME[name] = entry
        _BY_CLASS[cls] = entry
        return cls

    return register


def registered() -> dict[str, type]:
    """The registered classes by name (a copy)."""
    return {name: e.cls for name, e in _BY_NAME.items()}


# ---------------------------------------------------------------------------------------------
# Encoding


def _dtype_ok(dtype: np.dtype) -> bool:
    return dtype.kind in _ARRAY_KINDS and dtype.fields is None and dtype.subdtype is None


class _Encoder:
    def __init__(self) -> None:
        self.arrays: list[np.ndarray] = []

    def node(self, v: Any, path: str) -> Any:
        t = type(v)
        if v is None or t is bool or t is int or t is str:
            return v
        if t is float:
            if math.isfinite(v):
                return v
            return {"$": "float", "bits": struct.pack(">d", v).hex()}
        if isinstance(v, np.ndarray):
            if t is not np.ndarray:
                raise StoreError(
                    f"{path}: {t.__module__}.{t.__qualname__} is not plain data "
                    "(an ndarray subclass; store np.asarray(...))"
                )
            if not _dtype_ok(v.dtype):
                raise StoreError(
                    f"{path}: an array of dtype {v.dtype} is not plain data "
                    "(bool, int, uint, float, complex or unicode only)"
                )
            self.arrays.append(v)
            return {
                "$": "ndarray",
                "index": len(self.arrays) - 1,
                "dtype": v.dtype.str,
                "shape": list(v.shape),
            }
        if isinstance(v, np.generic):
            if not _dtype_ok(v.dtype):
                raise StoreError(f"{path}: a numpy scalar of dtype {v.dtype} is not plain data")
            if v.dtype.kind == "U":
                return {"$": "scalar", "dtype": v.dtype.str, "value": str(v)}
            return {"$": "scalar", "dtype": v.dtype.str, "bytes": v.tobytes().hex()}
        if t is list:
            return [self.node(x, f"{path}[{i}]") for i, x in enumerate(v)]
        if t is tuple:
            return {"$": "tuple", "items": [self.node(x, f"{path}[{i}]") for i, x in enumerate(v)]}
        if t is dict:
            return {
                "$": "dict",
                "items": [
                    [self.node(k, f"{path} (key {k!r})"), self.node(x, f"{path}[{k!r}]")]
                    for k, x in v.items()
                ],
            }
        entry = _BY_CLASS.get(t)
        if entry is None:
            raise StoreError(
                f"{path}: {t.__module__}.{t.__qualname__} is not plain data (plain values, "
                "arrays, list, tuple, dict and classes registered with store.plain_data only)"
            )
        if entry.is_model:
            data = v.model_dump(mode="python")
            return {"$": "model", "name": entry.name, "data": self.node(data, f"{path}(dump)")}
        return {
            "$": "dataclass",
            "name": entry.name,
            "fields": {f: self.node(getattr(v, f), f"{path}.{f}") for f in entry.fields},
        }


def _member(zf: zipfile.ZipFile, name: str, data: bytes) -> None:
    info = zipfile.ZipInfo(name, date_time=_ZIP_TIME)
    info.compress_type = zipfile.ZIP_STORED
    info.external_attr = 0o644 << 16
    zf.writestr(info, data)


def dumps(value: Any, header: Mapping[str, Any] | None = None) -> bytes:
    """Encode plain data (see the module docstring) into the bytes of one file.

    Args:
        value: the value to store.
        header: plain data describing the value (string keys), read back beside it.

    Returns:
        The file's bytes; the same value and header always give the same bytes.

    Raises:
        StoreError: if something is not plain data (the message gives its path, e.g.
            ``value.flights['direct'].arrays['t']``), or the value contains itself.
    """
    head = dict(header or {})
    for k in head:
        if type(k) is not str:
            raise StoreError(f"header: key {k!r} is not a string")
    enc = _Encoder()
    try:
        manifest = {
            "format": FORMAT,
            "version": VERSION,
            "header": enc.node(head, "header"),
            "value": enc.node(value, "value"),
        }
    except RecursionError:
        raise StoreError("value: nested too deeply, or it contains itself") from None
    names = [f"arrays/{i:06d}.npy" for i in range(len(enc.arrays))]
    manifest["arrays"] = names
    text = json.dumps(manifest, allow_nan=False, ensure_ascii=False, separators=(",", ":"))
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as zf:
        _member(zf, MANIFEST, text.encode("utf-8"))
        for name, a in zip(names, enc.arrays, strict=True):
            npy = io.BytesIO()
            np.lib.format.write_array(npy, a, allow_pickle=False)
            _member(zf, name, npy.getvalue())
    return buf.getvalue()


# ---------------------------------------------------------------------------------------------
# Decoding


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def _json_constant(name: str) -> Any:
    raise ValueError(f"{name} is not JSON")


def _json_object(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise ValueError(f"duplicate key {k!r}")
        out[k] = v
    return out


def _dtype(text: Any, where: str) -> np.dtype:
    if type(text) is not str or not _DTYPE_RE.fullmatch(text):
        raise StoreError(f"{where}: dtype {text!r} is not a plain-data dtype")
    return np.dtype(text)


class _Decoder:
    def __init__(self, source: str, arrays: list[np.ndarray]) -> None:
        self.source = source
        self.arrays = arrays
        self.used: set[int] = set()

    def fail(self, path: str, what: str) -> StoreError:
        return StoreError(f"{self.source}: {path}: {what}")

    def keys(self, n: dict[str, Any], expected: set[str], path: str) -> None:
        if set(n) != expected:
            raise self.fail(
                path, f"{n['$']!r} node has keys {sorted(n)}, expected {sorted(expected)}"
            )

    def value(self, n: Any, path: str) -> Any:
        t = type(n)
        if n is None or t is bool or t is int or t is float or t is str:
            return n
        if t is list:
            return [self.value(x, f"{path}[{i}]") for i, x in enumerate(n)]
        if t is not dict or type(n.get("$")) is not str:
            raise self.fail(path, f"not a value node: {_short(n)}")
        tag = n["$"]
        if tag == "float":
            self.keys(n, {"$", "bits"}, path)
            bits = n["bits"]
            if type(bits) is not str or not re.fullmatch(r"[0-9a-f]{16}", bits):
                raise self.fail(path, f"float bits {bits!r} are not 16 hex digits")
            return struct.unpack(">d", bytes.fromhex(bits))[0]
        if tag == "tuple":
            self.keys(n, {"$", "items"}, path)
            return tuple(self.value(x, f"{path}[{i}]") for i, x in enumerate(self.items(n, path)))
        if tag == "dict":
            return self.mapping(n, path)
        if tag == "ndarray":
            return self.array(n, path)
        if tag == "scalar":
            return self.scalar(n, path)
        if tag == "dataclass":
            return self.dataclass(n, path)
        if tag == "model":
            return self.model(n, path)
        raise self.fail(path, f"unknown node type {tag!r}")

    def items(self, n: dict[str, Any], path: str) -> list[Any]:
        items = n["items"]
        if type(items) is not list:
            raise self.fail(path, f"'items' is not a list: {_short(items)}")
        return items

    def mapping(self, n: dict[str, Any], path: str) -> dict[Any, Any]:
        self.keys(n, {"$", "items"}, path)
        out: dict[Any, Any] = {}
        for i, pair in enumerate(self.items(n, path)):
            if type(pair) is not list or len(pair) != 2:
                raise self.fail(path, f"item {i} is not a [key, value] pair")
            k = self.value(pair[0], f"{path} (key {i})")
            try:
                hash(k)
            except TypeError:
                raise self.fail(path, f"key {i} is unhashable ({type(k).__name__})") from None
            if k in out:
                raise self.fail(path, f"duplicate key {k!r}")
            out[k] = self.value(pair[1], f"{path}[{k!r}]")
        return out

    def array(self, n: dict[str, Any], path: str) -> np.ndarray:
        self.keys(n, {"$", "index", "dtype", "shape"}, path)
        i = n["index"]
        if type(i) is not int or not 0 <= i < len(self.arrays):
            raise self.fail(path, f"array index {i!r} is not one of the {len(self.arrays)} arrays")
        if i in self.used:
            raise self.fail(path, f"array {i} is used twice")
        self.used.add(i)
        a = self.arrays[i]
        dtype = _dtype(n["dtype"], f"{self.source}: {path}")
        shape = n["shape"]
        if a.dtype != dtype or a.dtype.str != dtype.str or list(a.shape) != shape:
            raise self.fail(
                path,
                f"array {i} is {a.dtype.str} {list(a.shape)} but the manifest says "
                f"{dtype.str} {shape!r}",
            )
        return a

    def scalar(self, n: dict[str, Any], path: str) -> np.generic:
        dtype = _dtype(n.get("dtype"), f"{self.source}: {path}")
        if dtype.kind == "U":
            self.keys(n, {"$", "dtype", "value"}, path)
            if type(n["value"]) is not str:
                raise self.fail(path, f"unicode scalar value {_short(n['value'])} is not a string")
            return np.str_(n["value"])
        self.keys(n, {"$", "dtype", "bytes"}, path)
        raw = n["bytes"]
        if type(raw) is not str or not re.fullmatch(r"(?:[0-9a-f]{2})*", raw):
            raise self.fail(path, f"scalar bytes {_short(raw)} are not hex")
        data = bytes.fromhex(raw)
        if len(data) != dtype.itemsize:
            raise self.fail(path, f"{len(data)} bytes for a {dtype.str} scalar")
        return np.frombuffer(data, dtype=dtype)[0]

    def registered(self, n: dict[str, Any], path: str, model: bool) -> _Entry:
        name = n.get("name")
        entry = _BY_NAME.get(name) if type(name) is str else None
        if entry is None or entry.is_model != model:
            kind = "pydantic model" if model else "dataclass"
            raise self.fail(path, f"unknown type name {name!r} (not a registered {kind})")
        return entry

    def dataclass(self, n: dict[str, Any], path: str) -> Any:
        self.keys(n, {"$", "name", "fields"}, path)
        entry = self.registered(n, path, model=False)
        fields = n["fields"]
        if type(fields) is not dict:
            raise self.fail(path, f"'fields' of {entry.name} is not an object")
        if set(fields) != set(entry.fields):
            missing = [f for f in entry.fields if f not in fields]
            extra = [f for f in fields if f not in entry.fields]
            raise self.fail(
                path, f"{entry.name} has the wrong fields (missing {missing}, unexpected {extra})"
            )
        kwargs = {f: self.value(fields[f], f"{path}.{f}") for f in entry.fields}
        try:
            return entry.cls(**kwargs)
        except Exception as exc:
            raise self.fail(path, f"cannot rebuild {entry.name}: {_one_line(exc)}") from None

    def model(self, n: dict[str, Any], path: str) -> BaseModel:
        self.keys(n, {"$", "name", "data"}, path)
        entry = self.registered(n, path, model=True)
        data = self.value(n["data"], f"{path}(dump)")
        try:
            return entry.cls.model_validate(data)  # type: ignore[attr-defined]
        except ValidationError as exc:
            err = exc.errors(include_url=False)[0]
            loc = ".".join(str(p) for p in err["loc"]) or "(top level)"
            raise self.fail(
                path,
                f"cannot rebuild {entry.name}: {loc}: {err['msg']} ({exc.error_count()} error(s))",
            ) from None


def _short(v: Any) -> str:
    text = repr(v)
    return text if len(text) <= 60 else text[:57] + "..."


def _read_npy(raw: bytes, where: str) -> np.ndarray:
    fh = io.BytesIO(raw)
    try:
        version = np.lib.format.read_magic(fh)
        read_header = _NPY_VERSIONS.get(version)
        if read_header is None:
            raise StoreError(f"{where}: .npy version {version} is not supported")
        shape, _fortran, dtype = read_header(fh)
    except StoreError:
        raise
    except Exception as exc:
        raise StoreError(f"{where}: not a .npy array: {_one_line(exc)}") from None
    if not _dtype_ok(dtype):
        raise StoreError(
            f"{where}: dtype {dtype} is not plain data (bool, int, uint, float, complex or unicode)"
        )
    count = math.prod(shape)
    if len(raw) - fh.tell() != count * dtype.itemsize:
        raise StoreError(
            f"{where}: {len(raw) - fh.tell()} data bytes for a {dtype.str} array of shape "
            f"{shape} ({count * dtype.itemsize} expected)"
        )
    fh.seek(0)
    try:
        return np.lib.format.read_array(fh, allow_pickle=False)
    except Exception as exc:
        raise StoreError(f"{where}: cannot read the array: {_one_line(exc)}") from None


def loads(data: bytes, source: str = "<bytes>") -> Stored:
    """Decode the bytes of a file written by :func:`dumps`.

    Args:
        data: the file's bytes.
        source: how messages name the file (its path).

    Returns:
        The header and the value.

    Raises:
        StoreError: naming ``source`` and what is wrong, on any malformed, damaged, truncated or
            foreign input. Nothing the file names is imported or called.
    """
    return load_file(io.BytesIO(data), source)


def load_file(fh: BinaryIO, source: str = "<file>") -> Stored:
    """Decode a file written by :func:`dumps` from an open, seekable binary file, member by
    member: the file is never held whole in memory (its arrays are, one member's bytes more).

    Args:
        fh: the file, open for reading in binary mode.
        source: how messages name the file (its path).

    Returns:
        The header and the value.

    Raises:
        StoreError: as :func:`loads`; also if the file cannot be read.
    """
    try:
        zf = zipfile.ZipFile(fh)
    except Exception as exc:
        raise StoreError(
            f"{source}: not a {FORMAT} file (not a zip archive: {_one_line(exc)})"
        ) from None
    with zf:
        infos = zf.infolist()
        names = [i.filename for i in infos]
        if len(set(names)) != len(names):
            raise StoreError(f"{source}: a member appears twice in the archive")
        for info in infos:
            if info.compress_type != zipfile.ZIP_STORED or info.flag_bits & 0x1:
                raise StoreError(f"{source}: member {info.filename!r} is compressed or encrypted")
        if MANIFEST not in names:
            raise StoreError(f"{source}: not a {FORMAT} file (no {MANIFEST})")
        try:
            text = zf.read(MANIFEST).decode("utf-8")
            manifest = json.loads(
                text, parse_constant=_json_constant, object_pairs_hook=_json_object
            )
        except RecursionError:
            raise StoreError(f"{source}: {MANIFEST} is nested too deeply") from None
        except Exception as exc:
            raise StoreError(f"{source}: {MANIFEST} is damaged: {_one_line(exc)}") from None
        keys = {"format", "version", "header", "value", "arrays"}
        if type(manifest) is not dict or set(manifest) != keys:
            got = sorted(manifest) if type(manifest) is dict else type(manifest).__name__
            raise StoreError(f"{source}: {MANIFEST} has keys {got}, expected {sorted(keys)}")
        if manifest["format"] != FORMAT:
            raise StoreError(f"{source}: format {manifest['format']!r} is not {FORMAT!r}")
        if manifest["version"] != VERSION or type(manifest["version"]) is not int:
            raise StoreError(
                f"{source}: {FORMAT} version {manifest['version']!r}; this version of bauv-sim "
                f"reads version {VERSION}"
            )
        arrays = manifest["arrays"]
        expected = (
            [f"arrays/{i:06d}.npy" for i in range(len(arrays))] if type(arrays) is list else None
        )
        if arrays != expected:
            raise StoreError(f"{source}: {MANIFEST} 'arrays' is not the list of array members")
        if set(names) != {MANIFEST, *arrays}:
            missing = sorted({MANIFEST, *arrays} - set(names))
            extra = sorted(set(names) - {MANIFEST, *arrays})
            raise StoreError(f"{source}: members missing {missing}, unexpected {extra}")
        loaded = []
        for name in arrays:
            try:
                raw = zf.read(name)
            except Exception as exc:
                raise StoreError(
                    f"{source}: member {name!r} is damaged: {_one_line(exc)}"
                ) from None
            loaded.append(_read_npy(raw, f"{source}: {name}"))
    dec = _Decoder(source, loaded)
    try:
        header = dec.value(manifest["header"], "header")
        value = dec.value(manifest["value"], "value")
    except RecursionError:
        raise StoreError(f"{source}: the value is nested too deeply") from None
    if type(header) is not dict or any(type(k) is not str for k in header):
        raise StoreError(f"{source}: the header is not a dict with string keys")
    if len(dec.used) != len(loaded):
        raise StoreError(f"{source}: {len(loaded) - len(dec.used)} array member(s) are not used")
    return Stored(header, value)


def load(path: str | Path) -> Stored:
    """Read and decode a file written with :func:`dumps`.

    Raises:
        StoreError: if it cannot be read or decoded (naming the path).
    """
    p = Path(path)
    try:
        fh = p.open("rb")
    except OSError as exc:
        raise StoreError(f"{p}: cannot read: {_one_line(exc)}") from None
    with fh:
        return load_file(fh, str(p))
