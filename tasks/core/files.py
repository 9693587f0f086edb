"""Files written atomically beside their final name, with the permissions of ordinary files.

A file is written to a temporary name in its folder and renamed over its final name, so that it
either exists whole or not at all. The temporary file is created with mode ``0o666`` filtered by
the process umask, as :func:`open` creates files (:func:`tempfile.mkstemp` would make it
``0o600``, and the rename would keep that: run folders unreadable by a collaborator while the
figures beside them are not).
"""

from __future__ import annotations

import contextlib
import os
import secrets
from pathlib import Path

_FILE_MODE = 0o666
"""Requested mode of a new file; the kernel removes the umask's bits, as for :func:`open`."""


def create_beside(path: Path) -> tuple[int, Path]:
    """Create a new, empty temporary file in ``path``'s folder (created if missing).

    Args:
        path: the final name the temporary file will be renamed to.

    Returns:
        ``(file descriptor open for writing, temporary path)``.

    Raises:
        OSError: if the folder cannot be created or written.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)
    while True:
        tmp = path.parent / f".{path.name}.{secrets.token_hex(6)}.tmp"
        try:
            return os.open(tmp, flags, _FILE_MODE), tmp
        except FileExistsError:
            continue


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` so that the file either exists whole or not at all.

    Raises:
        OSError: if the file cannot be written (nothing is left at the temporary name).
    """
    fd, tmp = create_beside(path)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def os_error_text(exc: OSError) -> str:
    """An :class:`OSError` in a few words: its reason and the file it names."""
    reason = exc.strerror or type(exc).__name__
    return f"{reason}: {exc.filename!r}" if exc.filename else reason
