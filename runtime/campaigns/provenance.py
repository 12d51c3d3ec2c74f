"""Provenance of a campaign session: versions, command line, engine, controller revision.

Recorded once per session in campaign.json so a result can be traced to what produced it.
It must never influence a run (runs depend on the plan only).
"""

from __future__ import annotations

import datetime
import importlib.util
import platform
import subprocess
import sys
from collections.abc import Sequence
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any


def _version(package: str) -> str | None:
    try:
        return version(package)
    except PackageNotFoundError:
        return None


def git_revision(path: Path) -> str | None:
    """The commit (with '+dirty' when modified) of the git work tree holding ``path``."""
    folder = path if path.is_dir() else path.parent
    try:
        head = subprocess.run(["git", "-C", str(folder), "rev-parse", "HEAD"],
                              capture_output=True, text=True, timeout=10, check=True)
        dirty = subprocess.run(["git", "-C", str(folder), "status", "--porcelain", "--", "."],
                               capture_output=True, text=True, timeout=10, check=True)
    except (OSError, subprocess.SubprocessError):
        return None
    return head.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")


def controller_revision(controller: str) -> str | None:
    """The version of a user's controller: its distribution's version, or the git revision of
    its source (``module:Class`` or a path). Built-in controllers have REI's version."""
    if Path(controller).exists():
        return git_revision(Path(controller))
    if ":" not in controller:
        return None
    module = controller.split(":", 1)[0]
    top = module.split(".", 1)[0]
    try:
        spec = importlib.util.find_spec(module)
    except (ImportError, ValueError):
        spec = None
    origin = spec.origin if spec is not None else None
    revision = git_revision(Path(origin)) if origin and Path(origin).exists() else None
    package = _version(top)
    if revision and package:
        return f"{package} ({revision})"
    return revision or package


def collect(argv: Sequence[str], engine: dict[str, object], controller: str | None,
            controller_version: str | None) -> dict[str, Any]:
    from rei.lang import __version__  # noqa: PLC0415

    revision = controller_version
    if revision is None and controller:
        revision = controller_revision(controller)
    return {
        "started": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "rei": __version__,
        "rei_git": git_revision(Path(__file__).resolve().parent),
        "pybullet": _version("pybullet"),
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "command": list(argv),
        "engine": engine,
        "controller": controller,
        "controller_version": revision,
    }
