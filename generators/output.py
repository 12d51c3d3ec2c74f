"""Writing into output folders: generated trees all at once, and every other output file of REI
without ever following a link that is already in the folder.

A generator adds files to an ``OutputTree``; ``write_tree`` writes them into a fresh
temporary folder beside the destination and moves each into place only when every file
was written, so a failure never leaves a half-written output folder behind. Paths are
checked to stay inside the output folder.

An output folder is often reused (the same ``-o`` again), and what is already in it is not
trusted: a symbolic link named ``run.log`` or ``world`` pointing elsewhere, a hard link to
someone's file, a FIFO. The folder given (``-o DIR`` itself) is the user's choice and is used
as given; below it, every writer here replaces what is at an output's name — the link
itself, never its target — with a new file or folder. ``open_output`` and ``write_atomic`` are
the one way REI's commands (`rei run`, `rei replay`, `rei-gen`, `rei campaign`) create output
files; ``write_tree(..., replace=True)`` empties a generated folder (``world/``,
``automata/``) of an earlier run's files so nothing stale can be loaded. This module must
never write outside the folder it is given, nor follow a link below it.
"""

from __future__ import annotations

import errno
import os
import shutil
import stat
import tempfile
import uuid
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import IO, Literal, overload

from rei.generators.errors import GenerationError

_NEW_FILE = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC
_FOLDER = os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC
_ATTEMPTS = 5
"""Tries to create a file whose name something else keeps re-creating, before giving up."""


@dataclass
class OutputTree:
    files: dict[str, bytes] = field(default_factory=dict)

    def add_text(self, relpath: str, text: str) -> None:
        self.add_bytes(relpath, text.encode("utf-8"))

    def add_bytes(self, relpath: str, data: bytes) -> None:
        path = PurePosixPath(relpath)
        if path.is_absolute() or ".." in path.parts or not path.parts or relpath != str(path):
            raise GenerationError(f"refusing to write '{relpath}': expected a relative path "
                                  f"inside the output folder")
        if relpath in self.files:
            raise GenerationError(f"two generated files would both be '{relpath}'")
        self.files[relpath] = data

    def merge(self, other: OutputTree, prefix: str = "") -> None:
        for rel, data in other.files.items():
            self.add_bytes(f"{prefix}/{rel}" if prefix else rel, data)


# -- single output files ------------------------------------------------------------------


def _remove_entry(name: str | Path, dir_fd: int | None = None) -> None:
    """Remove a file, link or FIFO at ``name``; a real folder there is refused."""
    try:
        os.unlink(name, dir_fd=dir_fd)
    except FileNotFoundError:
        pass
    except IsADirectoryError:
        raise IsADirectoryError(errno.EISDIR, "expected a file name, found a folder",
                                str(name)) from None
    except PermissionError:
        # Linux says EPERM (not EISDIR) for unlink() of a folder
        if stat.S_ISDIR(os.stat(name, dir_fd=dir_fd, follow_symlinks=False).st_mode):
            raise IsADirectoryError(errno.EISDIR, "expected a file name, found a folder",
                                    str(name)) from None
        raise


def _new_file(name: str | Path, dir_fd: int | None = None) -> int:
    """A descriptor of a new, empty regular file at ``name``: whatever was there is removed
    first, so a link (symbolic or hard) is never written through."""
    for _ in range(_ATTEMPTS):
        _remove_entry(name, dir_fd)
        try:
            return os.open(name, _NEW_FILE, 0o666, dir_fd=dir_fd)
        except FileExistsError:
            continue  # re-created meanwhile: remove it again
    raise FileExistsError(errno.EEXIST, "something keeps re-creating this name", str(name))


@overload
def open_output(path: str | Path, *, binary: Literal[True], newline: str | None = ...
                ) -> IO[bytes]: ...
@overload
def open_output(path: str | Path, *, binary: Literal[False] = ..., newline: str | None = ...
                ) -> IO[str]: ...
def open_output(path: str | Path, *, binary: bool = False, newline: str | None = "\n"
                ) -> IO[bytes] | IO[str]:
    """Open a new, empty regular file at ``path`` for writing (UTF-8 text unless ``binary``).

    What was at that name — an older output, a symbolic link, a hard link to another file, a
    FIFO — is removed first, never followed or written through; a folder there is refused
    (OSError). ``path``'s folder must exist and is used as given.
    """
    fd = _new_file(path)
    if binary:
        return os.fdopen(fd, "wb")
    return os.fdopen(fd, "w", encoding="utf-8", newline=newline)


def append_output(path: str | Path) -> IO[str]:
    """Open the regular file at ``path`` to append UTF-8 text (created if missing). Only a
    regular file with a single name is appended to; a link (symbolic or hard), FIFO or
    anything else at that name is replaced by a new, empty file, never written through."""
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_NOFOLLOW | os.O_NONBLOCK)
    except FileNotFoundError:
        fd = _new_file(path)
    except OSError as exc:
        if exc.errno not in (errno.ELOOP, errno.ENXIO):  # a symbolic link; a FIFO
            raise
        fd = _new_file(path)
    else:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or info.st_nlink != 1:
            os.close(fd)
            fd = _new_file(path)
        else:
            os.set_blocking(fd, True)
    return os.fdopen(fd, "a", encoding="utf-8", newline="\n")


def write_atomic(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` so that readers see the old file or the whole new one; a
    link at ``path`` is replaced by the file, never followed."""
    target = Path(path)
    tmp = target.with_name(f".{target.name}.{uuid.uuid4().hex}.tmp")
    try:
        with open_output(tmp, binary=True) as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, target)  # rename() replaces a link at the target, it does not follow it
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


# -- generated trees ---------------------------------------------------------------------


def _open_folder(name: str, dir_fd: int) -> int:
    """A descriptor of the real folder ``name`` inside ``dir_fd``, made if missing; a link or
    a file of that name is removed first (never followed)."""
    for _ in range(_ATTEMPTS):
        try:
            mode = os.stat(name, dir_fd=dir_fd, follow_symlinks=False).st_mode
        except FileNotFoundError:
            mode = None
        if mode is not None and not stat.S_ISDIR(mode):
            os.unlink(name, dir_fd=dir_fd)
            mode = None
        if mode is None:
            try:
                os.mkdir(name, dir_fd=dir_fd)
            except FileExistsError:
                continue
        try:
            return os.open(name, _FOLDER, dir_fd=dir_fd)
        except (NotADirectoryError, OSError) as exc:
            if isinstance(exc, NotADirectoryError) or exc.errno == errno.ELOOP:
                continue  # replaced by a link or file meanwhile: look again
            raise
    raise FileExistsError(errno.EEXIST, "something keeps replacing this folder", name)


def _place(source: Path, root_fd: int, rel: str) -> None:
    """Move ``source`` to ``rel`` below the folder ``root_fd`` without following any link."""
    *folders, name = PurePosixPath(rel).parts
    fd = os.dup(root_fd)
    try:
        for folder in folders:
            inner = _open_folder(folder, fd)
            os.close(fd)
            fd = inner
        # rename() replaces a link or file at the name (never follows it); a folder there
        # is refused with EISDIR.
        os.replace(source, name, dst_dir_fd=fd)
    finally:
        os.close(fd)


def remove_tree(path: Path) -> None:
    """Remove ``path`` — a folder with everything in it, or a file or link — never following
    a link (shutil.rmtree deletes links inside, not what they point to)."""
    if path.is_symlink() or not path.is_dir():
        path.unlink(missing_ok=True)
    else:
        shutil.rmtree(path)


def write_tree(tree: OutputTree, out_dir: str | Path, *, replace: bool = False) -> list[Path]:
    """Write every file of the tree under ``out_dir``; all or nothing. Returns the paths.

    Links already below ``out_dir`` are replaced, never written through. With ``replace``,
    ``out_dir`` belongs to this tree alone (``world/``, ``automata/``): it ends up holding
    exactly the tree's files, and a link at its own name is replaced by the folder; without,
    other files in it are kept.
    """
    out = Path(out_dir)
    if replace:
        return _replace_tree(tree, out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=".rei-gen-", dir=out))
    except OSError as exc:
        raise GenerationError(
            f"cannot write to the output folder '{out}': {exc.strerror}") from None
    written: list[Path] = []
    try:
        for rel, data in sorted(tree.files.items()):
            target = staging / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        root_fd = os.open(out, _FOLDER & ~os.O_NOFOLLOW)  # DIR itself is the user's choice
        try:
            for rel in sorted(tree.files):
                _place(staging / rel, root_fd, rel)
                written.append(out / rel)
        finally:
            os.close(root_fd)
    except OSError as exc:
        raise GenerationError(f"cannot write '{out}': {exc.strerror} ({exc.filename})") from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return written


def _replace_tree(tree: OutputTree, out: Path) -> list[Path]:
    # Built complete beside the old folder, then swapped in: a failure keeps the old one.
    staging = out.with_name(f".{out.name}.{uuid.uuid4().hex}.new")
    old = out.with_name(f".{out.name}.{uuid.uuid4().hex}.old")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        staging.mkdir()
    except OSError as exc:
        raise GenerationError(
            f"cannot write to the output folder '{out.parent}': {exc.strerror}") from None
    try:
        for rel, data in sorted(tree.files.items()):
            target = staging / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        try:
            os.rename(out, old)  # moves a link as a link
        except FileNotFoundError:
            pass
        try:
            os.rename(staging, out)
        except OSError:
            if old.exists() or old.is_symlink():
                os.rename(old, out)
            raise
    except OSError as exc:
        remove_tree(staging)
        raise GenerationError(f"cannot write '{out}': {exc.strerror} ({exc.filename})") from None
    try:
        remove_tree(old)
    except OSError as exc:
        raise GenerationError(f"wrote '{out}' but cannot remove the earlier one, now at "
                              f"'{old}': {exc.strerror}") from None
    return [out / rel for rel in sorted(tree.files)]
