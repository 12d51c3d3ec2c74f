"""Scratch folders that name the process they belong to, so a later process can sweep them.

A process removes its scratch folder however its children end, but nothing runs when the
process itself is killed with SIGKILL (or the machine loses power): its folder would stay in
the system's temporary folder for ever. ``make_scratch`` therefore names each folder after
its owner — ``PREFIX<pid>-<start>-<namespace>-<random>``, ``start`` being the owner's start
time in clock ticks since boot (Linux ``/proc/PID/stat``: exact, and unaffected by changes of
the system clock) and ``namespace`` its pid namespace — and ``sweep_stale`` removes the
folders whose owner is gone: no process with that pid, a zombie, or a process with that pid
that started at another time (the pid was reused). Only folders of the sweeper's own pid
namespace are judged: a container sharing the temporary folder numbers its processes apart,
and its owners cannot be seen from here.

The owner is written into the folder's *name*, not a file inside it: the name exists as soon
as the folder does (no moment when a live folder looks ownerless) and the programs that work
in the folder (a robot under test among them) cannot rewrite it.

This module must never remove a folder whose owner may be alive, one another user owns, or
anything that is not a directory made by ``make_scratch`` (a symbolic link, a file, a name it
cannot read). Where the start time cannot be read (not Linux) folders are made as before and
never swept.
"""

from __future__ import annotations

import os
import re
import shutil
import stat
import tempfile
from pathlib import Path

_OWNED = re.compile(r"(?P<pid>[0-9]+)-(?P<start>[0-9]+)-(?P<space>[0-9]+)-[a-z0-9_]+")
"""What follows the prefix in a folder ``make_scratch`` made (mkdtemp's random part last)."""


def start_ticks(pid: int) -> int | None:
    """When process ``pid`` started (clock ticks since boot), None when there is no such
    process that is alive (none, a zombie) or its start time cannot be read (not Linux)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as file:
            text = file.read()
    except OSError:
        return None
    # The command name (field 2) is in parentheses and may hold spaces or parentheses.
    fields = text.rsplit(")", 1)[-1].split()
    if len(fields) < 20 or fields[0] in ("Z", "X") or not fields[19].isdigit():
        return None
    return int(fields[19])  # field 22 of proc(5), starttime


def pid_namespace() -> int | None:
    """The identity of this process's pid namespace (Linux), None where it cannot be read."""
    try:
        link = os.readlink("/proc/self/ns/pid")  # "pid:[4026531836]"
    except OSError:
        return None
    digits = link.rpartition("[")[2].rstrip("]")
    return int(digits) if digits.isdigit() else None


def make_scratch(prefix: str) -> str:
    """A new folder in the system's temporary folder whose name says this process owns it
    (``sweep_stale(prefix)`` removes it once this process is gone)."""
    start, space = start_ticks(os.getpid()), pid_namespace()
    owned = start is not None and space is not None
    return tempfile.mkdtemp(prefix=prefix + (f"{os.getpid()}-{start}-{space}-" if owned else ""))


def sweep_stale(prefix: str, folder: str | None = None) -> list[Path]:
    """Remove the folders ``make_scratch(prefix)`` made in ``folder`` (default: the system's
    temporary folder) that belong to this user and to a process that is gone; the removed."""
    where = Path(folder if folder is not None else tempfile.gettempdir())
    user, space = os.geteuid(), pid_namespace()
    if space is None:
        return []  # owners cannot be told apart here
    removed = []
    try:
        entries = sorted(os.scandir(where), key=lambda entry: entry.name)
    except OSError:
        return []  # nothing to sweep where nothing can be listed
    for entry in entries:
        owned = _OWNED.fullmatch(entry.name[len(prefix):]) if entry.name.startswith(prefix) \
            else None
        if owned is None or int(owned["space"]) != space:
            continue  # not ours, made where the owner could not be written, or another
            # namespace's (whose pids mean other processes)
        try:
            info = entry.stat(follow_symlinks=False)
        except OSError:
            continue  # gone meanwhile
        if not stat.S_ISDIR(info.st_mode) or info.st_uid != user:
            continue
        if start_ticks(int(owned["pid"])) == int(owned["start"]):
            continue  # its owner is running
        shutil.rmtree(entry.path, ignore_errors=True)  # a sweep running beside may be first
        removed.append(Path(entry.path))
    return removed
