"""The one loader of the project's ctypes-loaded C libraries, and the Python mirror of their
argument structs (declared once, in the shared header ``nav/clib.h``).

The libraries are plain C (no Python API), built beside their modules by ``pip install``
(``setup.py``): the harmonic seabed's ray march (``bauv_sim/sensors/harmonic_rays.c``) and the
seabed shift (``nav/seabed/seabed_shift.c``). Each entry point takes a pointer to one struct of
``nav/clib.h``; every buffer travels in it with its number of elements (:class:`InF64` ...
:class:`OutU8`), so the C checks what it reads and writes against the shapes it is given.

**Layout check.** For each struct ``T`` a library takes, the header's X-macro defines
``T_layout`` (``sizeof(T)`` and every field's offset) and ``T_fields`` (the fields' C types and
names). :func:`entry_point` compares both with the :class:`ctypes.Structure` mirror here when it
binds the entry point and raises :class:`nav.errors.NavError` on any difference (a field added,
moved, renamed or retyped on one side only), so the two declarations cannot drift apart silently.

Arguments are packed with :func:`pack`: scalars as they are, buffers as numpy arrays (``None`` for
a NULL buffer), each a C-contiguous array of the view's element type, writeable for an output;
anything else is a programming error (:class:`nav.errors.NavError`), never a silent copy (an
output must be the caller's array). The packed struct holds a reference to every array it points
into, so a temporary array lives as long as the struct.
"""

from __future__ import annotations

import ctypes
import importlib.machinery
from collections.abc import Callable
from pathlib import Path

import numpy as np

from nav.errors import NavError

c_int64, c_double = ctypes.c_int64, ctypes.c_double


class _View(ctypes.Structure):
    """A buffer view of ``nav/clib.h``: data pointer and number of elements."""

    c_name = ""
    dtype: type[np.generic] = np.float64
    writeable = False


def _view(c_name: str, dtype: type[np.generic], writeable: bool) -> type[_View]:
    # the data pointer as an address (the C side's typed pointer has the same size and place);
    # its element type is the view's dtype, which buffer() checks: an address is set three
    # times faster than a typed ctypes pointer, which matters for the per-call overhead
    fields = [("data", ctypes.c_void_p), ("size", c_int64)]
    attrs = {"_fields_": fields, "c_name": c_name, "dtype": dtype, "writeable": writeable}
    return type(c_name, (_View,), attrs)


InF64 = _view("bauv_in_f64", np.float64, False)
InI64 = _view("bauv_in_i64", np.int64, False)
InU8 = _view("bauv_in_u8", np.uint8, False)
OutF64 = _view("bauv_out_f64", np.float64, True)
OutI64 = _view("bauv_out_i64", np.int64, True)
OutU8 = _view("bauv_out_u8", np.uint8, True)


class MarchArgs(ctypes.Structure):
    """``bauv_march_args``: the harmonic seabed's ray march (``harmonic_rays.c``)."""

    c_name = "bauv_march_args"
    _fields_ = [
        *[(n, c_int64) for n in ("n", "paths", "harmonics", "steps")],
        *[(n, c_double) for n in ("a0", "px", "py", "max_range", "tol")],
        ("o", InF64),
        ("e", InF64),
        ("path", InI64),
        *[(n, InF64) for n in ("a", "b", "c", "d", "wx", "wy", "top", "cxx", "cyy")],
        ("range", OutF64),
        ("hit", OutU8),
        ("unresolved", OutU8),
        ("s", OutF64),
    ]


class SeabedFitArgs(ctypes.Structure):
    """``bauv_seabed_fit_args``: Appendix A's slope fit (``seabed_shift.c``)."""

    c_name = "bauv_seabed_fit_args"
    _fields_ = [
        *[(n, c_int64) for n in ("paths", "feet", "kind", "harmonics")],
        *[(n, c_double) for n in ("px", "py", "max_condition")],
        ("points", InF64),
        ("valid", InU8),
        ("grad", OutF64),
        ("fit_ok", OutU8),
        ("to_numpy", OutU8),
    ]


class SeabedShiftArgs(ctypes.Structure):
    """``bauv_seabed_shift_args``: eq. 12-15 with the stated covariance (``seabed_shift.c``)."""

    c_name = "bauv_seabed_shift_args"
    _fields_ = [
        *[(n, c_int64) for n in ("paths", "beams", "residual")],
        *[(n, c_double) for n in ("sigma", "fallback", "rcond", "singular_floor")],
        *[(n, InF64) for n in ("grad", "e", "de", "l0", "l1")],
        ("use", InU8),
        ("fit_ok", InU8),
        ("cmd", InF64),
        *[(n, OutF64) for n in ("shift", "cov")],
        *[(n, OutI64) for n in ("used", "rank")],
        ("ok", OutU8),
        ("rms", OutF64),
    ]


_C_TYPES = {c_int64: "int64_t", c_double: "double"}


def c_fields(struct: type[ctypes.Structure]) -> str:
    """The fields of a mirror as ``T_fields`` of the header states them ("type:name ...")."""
    names = []
    for name, ctype in struct._fields_:
        kind = ctype.c_name if issubclass(ctype, _View) else _C_TYPES[ctype]
        names.append(f"{kind}:{name} ")
    return "".join(names)


def buffer(view: type[_View], a: np.ndarray | None) -> _View:
    """A view of ``a`` (or a NULL buffer of size 0 for ``None``) for a struct field.

    Raises:
        NavError: if ``a`` is not a C-contiguous array of the view's element type, or not
            writeable for an output view.
    """
    if a is None:
        return view(None, 0)
    ok = (
        isinstance(a, np.ndarray)
        and a.dtype == view.dtype
        and a.flags.c_contiguous
        and (a.flags.writeable or not view.writeable)
    )
    if not ok:
        raise NavError(
            f"{view.c_name}: need a C-contiguous{' writeable' if view.writeable else ''} "
            f"{np.dtype(view.dtype).name} array, got {getattr(a, 'dtype', type(a).__name__)}"
        )
    return view(a.ctypes.data, a.size)


def pack(struct: type[ctypes.Structure], **values: object) -> ctypes.Structure:
    """An instance of ``struct`` with every field given: scalars as they are, buffers as numpy
    arrays or ``None`` (:func:`buffer`); the instance keeps the arrays alive (``_keep``).

    Raises:
        NavError: if a field is missing or unknown, or a buffer is not of its view's kind.
    """
    names = [f for f, _ in struct._fields_]
    if set(values) != set(names):
        missing, extra = sorted(set(names) - set(values)), sorted(set(values) - set(names))
        raise NavError(f"{struct.c_name}: missing fields {missing}, unknown fields {extra}")
    fields = {
        name: buffer(ctype, values[name]) if issubclass(ctype, _View) else values[name]
        for name, ctype in struct._fields_
    }
    out = struct(**fields)
    out._keep = list(values.values())  # type: ignore[attr-defined]
    return out


def library_path(directory: Path, stem: str, error: type[Exception] = NavError) -> Path:
    """The built library ``stem`` in ``directory`` (a Python extension's file name).

    Raises:
        error: if it was not built (the message says how to build it).
    """
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        path = directory / (stem + suffix)
        if path.is_file():
            return path
    raise error(
        f"the C library {directory / stem}*.so is not built: reinstall the package "
        "(pip install -e .)"
    )


def load_library(directory: Path, stem: str, error: type[Exception] = NavError) -> ctypes.CDLL:
    """Load the built library ``stem`` of ``directory`` (:func:`library_path`)."""
    return ctypes.CDLL(str(library_path(directory, stem, error)))


def check_layout(lib: ctypes.CDLL, struct: type[ctypes.Structure]) -> None:
    """Compare the C layout of ``struct.c_name`` in ``lib`` with the mirror (module docstring).

    Raises:
        NavError: on any difference of size, offsets, field names or field types.
    """
    name = struct.c_name
    try:
        layout_fn = getattr(lib, f"{name}_layout")
        fields_fn = getattr(lib, f"{name}_fields")
    except AttributeError:
        raise NavError(f"C library {lib._name}: no layout of {name} (rebuild it)") from None
    layout_fn.argtypes = [ctypes.POINTER(c_int64), c_int64]
    layout_fn.restype = c_int64
    fields_fn.argtypes = []
    fields_fn.restype = ctypes.c_char_p
    want = [ctypes.sizeof(struct)] + [getattr(struct, f).offset for f, _ in struct._fields_]
    got = (c_int64 * (len(want) + 1))()
    count = layout_fn(got, len(want) + 1)
    c_layout = list(got[: min(count, len(want) + 1)])
    c_names = fields_fn().decode()
    if count != len(want) or c_layout != want or c_names != c_fields(struct):
        raise NavError(
            f"C library {Path(lib._name).name}: {name} differs from its mirror in nav.clib "
            f"(C: size and offsets {c_layout}, fields {c_names.split()}; Python: {want}, "
            f"{c_fields(struct).split()}); rebuild the library (pip install -e .)"
        )


def entry_point(
    lib: ctypes.CDLL, symbol: str, struct: type[ctypes.Structure]
) -> Callable[[ctypes.Structure], int]:
    """The entry point ``symbol(const T* args) -> int64_t`` of ``lib``, its struct's layout
    checked (:func:`check_layout`); call it with a ``struct`` instance.

    Raises:
        NavError: if the layout differs from the mirror.
    """
    check_layout(lib, struct)
    fn = getattr(lib, symbol)
    fn.argtypes = [ctypes.POINTER(struct)]
    fn.restype = c_int64

    def call(args: ctypes.Structure) -> int:
        if not isinstance(args, struct):
            raise NavError(f"{symbol}: takes a {struct.__name__}, got {type(args).__name__}")
        return int(fn(ctypes.byref(args)))

    call.__name__ = symbol
    return call
