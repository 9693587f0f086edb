"""Files written atomically beside their final name, never through a link out of a run folder.

A file is written to a temporary name in its folder and renamed over its final name, so that it
either exists whole or not at all (a full disk leaves the previous file, or none, never a
truncated one). The temporary file is created with mode ``0o666`` filtered by the process umask,
as :func:`open` creates files (:func:`tempfile.mkstemp` would make it ``0o600``, and the rename
would keep that: run folders unreadable by a collaborator while the figures beside them are not).

Every file of a run folder (blocks, ``run.json``, ``scenario.toml``, tables, CSV, metrics, figures,
recordings, Parquet data, gains) is written here. While the runner holds a run folder open with
:func:`confined`, a write under it never leaves it:

* the folders between the run folder and the file are opened one by one, each relative to the one
  before (``openat`` with ``O_NOFOLLOW``), and created there when missing; a folder that is a
  symbolic link is refused (:class:`LinkInRunFolder`), as is a path with a ``..`` component;
* the temporary file is created in the folder so opened (``O_EXCL | O_NOFOLLOW``) and renamed
  over the final name within it: a symbolic link at the final name is replaced by the file (a
  rename replaces the link, not what it points to), never written through.

The run folder itself may be a symbolic link (it is the folder the user named). ``--resume``
refuses a run folder that holds any symbolic link before it writes anything
(:func:`find_link`); the rules above hold for a link that appears later.
"""

from __future__ import annotations

import collections
import contextlib
import errno
import os
import secrets
import stat
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

_FILE_MODE = 0o666
"""Requested mode of a new file; the kernel removes the umask's bits, as for :func:`open`."""

_DIR_MODE = 0o777
"""Requested mode of a new folder (less the umask, as :meth:`Path.mkdir`)."""

_CLOEXEC = getattr(os, "O_CLOEXEC", 0)
_DIR_FLAGS = os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | _CLOEXEC
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_AT_CALLS = (
    {os.open, os.mkdir, os.unlink, os.rename, os.stat} <= os.supports_dir_fd  # replace: as rename
    and _NOFOLLOW != 0
    and hasattr(os, "O_DIRECTORY")
)
"""Whether the platform has the ``*at`` calls (Linux, macOS); elsewhere each folder of a path
under a run folder is checked with :func:`os.lstat` before the write, by name."""

_ROOTS: collections.Counter[Path] = collections.Counter()
_ROOTS_LOCK = threading.Lock()


class LinkInRunFolder(OSError):
    """A write (or read) under a run folder met a symbolic link where a folder belongs, or a path
    leaving the run folder; nothing was written."""


@contextlib.contextmanager
def confined(root: str | Path) -> Iterator[None]:
    """Confine this process's writes under ``root`` to ``root`` (see the module docstring),
    in every thread, while the context is open.

    Args:
        root: the run folder (it need not exist yet).
    """
    # as the writers will name it (``..`` kept, as in ``out_dir / "x"``) and normalised
    keys = {_absolute(root), Path(os.path.abspath(root))}
    with _ROOTS_LOCK:
        _ROOTS.update(keys)
    try:
        yield
    finally:
        with _ROOTS_LOCK:
            _ROOTS.subtract(keys)
            for key in keys:
                if _ROOTS[key] <= 0:
                    del _ROOTS[key]


def _absolute(path: str | Path) -> Path:
    """``path`` made absolute without resolving anything (``..`` kept, ``.`` dropped)."""
    return Path(os.getcwd(), path) if not os.path.isabs(path) else Path(path)


def _root_of(path: Path) -> tuple[Path, tuple[str, ...]] | None:
    """The open run folder ``path`` lies under (the deepest), with the parts below it.

    Raises:
        LinkInRunFolder: if a part below the run folder is ``..``.
    """
    with _ROOTS_LOCK:
        roots = list(_ROOTS)
    best = None
    for root in roots:
        n = len(root.parts)
        if path.parts[:n] == root.parts and (best is None or n > len(best.parts)):
            best = root
    if best is None:
        return None
    rest = path.parts[len(best.parts) :]
    if ".." in rest:
        raise LinkInRunFolder(
            errno.EXDEV, "a path with '..' leaves the run folder; nothing is written", str(path)
        )
    return best, rest


def _link_error(path: Path) -> LinkInRunFolder:
    return LinkInRunFolder(
        errno.ELOOP,
        "a symbolic link inside the run folder (nothing is written through one; remove it)",
        str(path),
    )


def _enter(dir_fd: int, name: str, shown: Path, create: bool) -> int:
    """Open folder ``name`` of the folder ``dir_fd`` without following a link (created first
    when missing and ``create``); ``dir_fd`` is closed."""
    try:
        try:
            return os.open(name, _DIR_FLAGS | _NOFOLLOW, dir_fd=dir_fd)
        except FileNotFoundError:
            if not create:
                raise
            with contextlib.suppress(FileExistsError):
                os.mkdir(name, _DIR_MODE, dir_fd=dir_fd)
            return os.open(name, _DIR_FLAGS | _NOFOLLOW, dir_fd=dir_fd)
        except OSError as exc:
            if exc.errno in (errno.ELOOP, errno.ENOTDIR, errno.EMLINK):
                st = os.stat(name, dir_fd=dir_fd, follow_symlinks=False)
                if stat.S_ISLNK(st.st_mode):
                    raise _link_error(shown) from None
            raise
    finally:
        os.close(dir_fd)


def _check_by_name(root: Path, parts: tuple[str, ...]) -> None:
    """Where there are no ``*at`` calls: refuse a link among the folders of ``parts``."""
    here = root
    for part in parts:
        here = here / part
        with contextlib.suppress(FileNotFoundError):
            if stat.S_ISLNK(os.lstat(here).st_mode):
                raise _link_error(here)


def _open_folder(path: Path, create: bool = True) -> tuple[int | None, Path, str]:
    """The folder of ``path``, opened for the ``*at`` calls, and the final name.

    Returns:
        ``(folder fd or None where the platform has no *at calls, folder path, final name)``;
        the caller closes the fd.

    Raises:
        LinkInRunFolder: under a run folder, for a folder that is a link or a ``..``.
        OSError: if a folder cannot be created or opened.
    """
    full = _absolute(path)
    name = full.name
    if not name or name in (".", ".."):
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
    under = _root_of(full)
    folder = full.parent
    if under is None:
        if create:
            folder.mkdir(parents=True, exist_ok=True)
        if not _AT_CALLS:
            return None, folder, name
        return os.open(folder, _DIR_FLAGS), folder, name
    root, rest = under
    if not _AT_CALLS:
        if create:
            root.mkdir(parents=True, exist_ok=True)
        _check_by_name(root, rest[:-1])
        if create:
            folder.mkdir(parents=True, exist_ok=True)
        _check_by_name(root, rest[:-1])
        return None, folder, name
    if create:
        root.mkdir(parents=True, exist_ok=True)
    fd = os.open(root, _DIR_FLAGS)
    shown = root
    for part in rest[:-1]:
        shown = shown / part
        fd = _enter(fd, part, shown, create)
    return fd, folder, name


class AtomicFile:
    """A file being written under a temporary name beside ``path``; :meth:`commit` renames it
    over ``path``, :meth:`discard` removes it. Use :func:`atomic_writer` rather than this."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._dir_fd, self._folder, self._name = _open_folder(self.path)
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | _CLOEXEC
        try:
            while True:
                self._tmp = f".{self._name}.{secrets.token_hex(6)}.tmp"
                try:
                    fd = os.open(self._at(self._tmp), flags, _FILE_MODE, dir_fd=self._dir_fd)
                    break
                except FileExistsError:
                    continue
        except BaseException:
            self._close_dir()
            raise
        self.file: BinaryIO = os.fdopen(fd, "wb")

    def _at(self, name: str) -> str:
        return name if self._dir_fd is not None else str(self._folder / name)

    def _close_dir(self) -> None:
        if self._dir_fd is not None:
            os.close(self._dir_fd)
            self._dir_fd = None

    def commit(self) -> None:
        """Close the temporary file and rename it over the final name (replacing a link there,
        not writing through it)."""
        try:
            self.file.close()
            os.replace(
                self._at(self._tmp),
                self._at(self._name),
                src_dir_fd=self._dir_fd,
                dst_dir_fd=self._dir_fd,
            )
        except BaseException:
            self.discard()
            raise
        self._close_dir()

    def discard(self) -> None:
        """Close and remove the temporary file (nothing is left at the final name)."""
        with contextlib.suppress(OSError):
            self.file.close()
        if self._dir_fd is not None or not _AT_CALLS:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(self._at(self._tmp), dir_fd=self._dir_fd)
        self._close_dir()


@contextlib.contextmanager
def atomic_writer(path: str | Path) -> Iterator[BinaryIO]:
    """A binary file to write ``path``'s content into: renamed over ``path`` when the block
    ends, removed if it raises (then ``path`` is as it was).

    Raises:
        LinkInRunFolder: under a run folder (:func:`confined`), if a folder of the path is a
            symbolic link or the path leaves the run folder.
        OSError: if the file cannot be written (nothing is left at the temporary name).
    """
    f = AtomicFile(path)
    try:
        yield f.file
    except BaseException:
        f.discard()
        raise
    f.commit()


def atomic_write_bytes(path: str | Path, data: bytes | bytearray | memoryview) -> None:
    """Write ``data`` (any bytes-like object) to ``path`` so that the file either exists whole
    or not at all.

    Raises:
        LinkInRunFolder: see :func:`atomic_writer`.
        OSError: if the file cannot be written (nothing is left at the temporary name).
    """
    with atomic_writer(path) as fh:
        fh.write(data)


def remove(path: str | Path) -> None:
    """Remove a file if it is there, without following a link among its folders (a link at the
    name itself is removed, not what it points to).

    Raises:
        LinkInRunFolder: see :func:`atomic_writer`.
        OSError: if it cannot be removed.
    """
    try:
        dir_fd, folder, name = _open_folder(Path(path), create=False)
    except FileNotFoundError:
        return
    try:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(name if dir_fd is not None else folder / name, dir_fd=dir_fd)
    finally:
        if dir_fd is not None:
            os.close(dir_fd)


def open_for_reading(path: str | Path) -> BinaryIO:
    """Open a file of a run folder for reading, without following a link, neither at its name
    nor among its folders.

    Raises:
        LinkInRunFolder: if it or one of its folders (under a run folder) is a symbolic link.
        OSError: if it cannot be opened, or is not a regular file.
    """
    dir_fd, folder, name = _open_folder(Path(path), create=False)
    try:
        try:
            fd = os.open(
                name if dir_fd is not None else folder / name,
                os.O_RDONLY | _NOFOLLOW | _CLOEXEC,
                dir_fd=dir_fd,
            )
        except OSError as exc:
            if exc.errno == errno.ELOOP:
                raise _link_error(Path(path)) from None
            raise
    finally:
        if dir_fd is not None:
            os.close(dir_fd)
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise OSError(errno.EINVAL, "not a regular file", str(path))
    return os.fdopen(fd, "rb")


def find_link(root: str | Path) -> Path | None:
    """A symbolic link inside folder ``root`` (``root`` itself may be one), or None.

    The folders are listed as the file system gives them (not sorted: a run folder may hold two
    million block files), so of several links any one is named.

    Raises:
        OSError: if a folder cannot be listed.
    """
    stack = [Path(root)]
    while stack:
        folder = stack.pop()
        with os.scandir(folder) as entries:
            for entry in entries:
                if entry.is_symlink():
                    return folder / entry.name
                if entry.is_dir(follow_symlinks=False):
                    stack.append(folder / entry.name)
    return None


def os_error_text(exc: OSError) -> str:
    """An :class:`OSError` in a few words: its reason and the file it names."""
    reason = exc.strerror or type(exc).__name__
    return f"{reason}: {exc.filename!r}" if exc.filename else reason
