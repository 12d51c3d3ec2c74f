"""Generated files are collected in memory and written all at once, or not at all.

A generator adds files to an ``OutputTree``; ``write_tree`` writes them into a fresh
temporary folder beside the destination and moves each into place only when every file
was written, so a failure never leaves a half-written output folder behind. Paths are
checked to stay inside the output folder.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

from rei.generators.errors import GenerationError


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


def write_tree(tree: OutputTree, out_dir: str | Path) -> list[Path]:
    """Write every file of the tree under ``out_dir``; all or nothing. Returns the paths."""
    out = Path(out_dir)
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
        for rel in sorted(tree.files):
            final = out / rel
            final.parent.mkdir(parents=True, exist_ok=True)
            os.replace(staging / rel, final)
            written.append(final)
    except OSError as exc:
        raise GenerationError(f"cannot write '{out}': {exc.strerror} ({exc.filename})") from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return written
