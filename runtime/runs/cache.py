"""Generated worlds and automata, cached by a hash of their inputs, so that a campaign pays
for textX parsing, checking and template rendering once per mission and specification, not
once per run (docs/campaign.md, "Start-up").

An entry holds what generation produced (the files written into a run's ``world/`` or
``automata/`` folder, and the checked model the run goes on with) and the inputs it read
(every file ``rei.lang.source.read_bounded`` was asked for, with the sha256 of its bytes).
It is found by a key: the kind, REI's version and code (the files of the ``rei`` package, by
name, size and modification time), the first input's path (as given and absolute), the
sha256 of its bytes, and the values generation was given beside the file (a .vepl's
`--param`). It is served only when, read again now, every input has the same
bytes and every stored file the hash the entry lists; a changed mission, room, catalogue or
specification, or a changed REI, is a miss and the entry is made again. Entries are written
into a private temporary folder and renamed into place in one step, so a reader finds a whole
entry or none, and of two writers of the same key the first rename wins (both made the same
entry).

A cache is a directory of the user's (``rei campaign`` uses ``DIR/cache/``; ``rei run`` uses
``$REI_CACHE_DIR`` when set): its entries hold pickled models, to be trusted as the user's own
files are. This module must never serve an entry whose inputs changed, never let a problem of
the cache itself (unreadable, corrupt, full disk) fail or change a run — it generates as if
there were no cache — and never write outside its directory.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import pickle
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from rei.lang.source import Reads, read_bounded, recorded_reads

if TYPE_CHECKING:
    from rei.generators.concrete import ConcreteMission

CACHE_VARIABLE = "REI_CACHE_DIR"
"""The environment variable naming the cache directory of `rei run` (unset: no cache);
``off`` turns the cache off for `rei campaign` and `rei demo` too."""
CACHE_OFF = "off"

FORMAT = "rei-artifact-cache/1"
CODE_PACKAGES = ("rei.lang", "rei.grammars", "rei.generators", "rei.runtime", "rei.catalogue")
"""The packages whose code or data can change what generation produces."""

T = TypeVar("T")


@functools.cache
def code_fingerprint() -> str:
    """REI's version and every file of its packages by name, size and modification time (a
    stat each, no reading): an edited generator or template misses every entry. Computed once
    per process, which imports the code once too."""
    import importlib  # noqa: PLC0415
    from importlib import metadata  # noqa: PLC0415

    digest = hashlib.sha256()
    try:
        digest.update(metadata.version("rei-testbed").encode())
    except metadata.PackageNotFoundError:
        digest.update(b"unknown version")
    for name in CODE_PACKAGES:
        for folder in sorted(importlib.import_module(name).__path__):
            for root, dirs, files in os.walk(folder):
                dirs[:] = sorted(d for d in dirs if d != "__pycache__")
                for file in sorted(files):
                    if file.endswith((".pyc", ".pyo")):
                        continue
                    path = os.path.join(root, file)
                    try:
                        info = os.stat(path)
                    except OSError:
                        continue
                    relative = os.path.relpath(path, folder)
                    digest.update(f"{name}/{relative}\0{info.st_size}\0{info.st_mtime_ns}\n"
                                  .encode("utf-8", "surrogateescape"))
    return digest.hexdigest()


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _same_inputs(reads: list[Any]) -> bool:
    """Whether every recorded input reads now as it read then."""
    for entry in reads:
        if not (isinstance(entry, list) and len(entry) == 2 and isinstance(entry[0], str)):
            return False
        path, digest = entry
        data = read_bounded(path)
        now = _sha256(data) if isinstance(data, bytes) else None
        if now != digest:
            return False
    return True


@dataclass(frozen=True)
class ArtifactCache:
    """The cache in the directory ``root`` (created when the first entry is written)."""

    root: Path

    @classmethod
    def from_environment(cls) -> ArtifactCache | None:
        """The cache ``$REI_CACHE_DIR`` names; None when it is unset, empty or ``off``."""
        folder = os.environ.get(CACHE_VARIABLE, "")
        return cls(Path(folder)) if folder and folder != CACHE_OFF else None

    # -- the two kinds a run generates ---------------------------------------------------

    def world(self, mission_path: Path, out_dir: Path) -> ConcreteMission:
        """``rei.runtime.simulation.assembly.generate_world``, from the cache when its inputs are
        unchanged:
        the `pybullet` and `monitor` targets in ``out_dir`` (replacing what was there) and
        the checked mission."""
        from rei.generators.output import OutputTree, write_tree  # noqa: PLC0415

        def make() -> tuple[dict[str, bytes], ConcreteMission]:
            from rei.generators.concrete.build import load_concrete_mission  # noqa: PLC0415
            from rei.generators.targets import GenerationRequest, get_target  # noqa: PLC0415

            mission = load_concrete_mission(mission_path)
            request = GenerationRequest(mission_path, mission.world, mission)
            tree = OutputTree()
            for name in ("pybullet", "monitor"):
                tree.merge(get_target(name).generate(request))
            return tree.files, mission

        files, mission = self.cached("world", mission_path, make)
        write_tree(OutputTree(dict(files)), out_dir, replace=True)
        return mission

    def automata(self, vepl: Path | None, out_dir: Path,
                 parameters: tuple[tuple[str, float], ...] = ()) -> Path:
        """``rei.runtime.observation.monitor.generate_automata`` (the default specification when
        ``vepl`` is None, with ``parameters`` from `--param`), from the cache when its
        inputs are unchanged: the parameters are part of the key, so automata generated
        with other values are never served."""
        from rei.generators.output import OutputTree, write_tree  # noqa: PLC0415
        from rei.lang.vepl.document import DEFAULT_VEPL  # noqa: PLC0415

        source = vepl if vepl is not None else DEFAULT_VEPL

        def make() -> tuple[dict[str, bytes], None]:
            from rei.generators.pipeline import plan  # noqa: PLC0415

            return plan(source, "rx", parameters=parameters).tree.files, None

        files, _ = self.cached("automata", source, make,
                               [[name, repr(value)] for name, value in parameters])
        write_tree(OutputTree(dict(files)), out_dir, replace=True)
        return Path(out_dir) / "automata.py"

    # -- the mechanism ---------------------------------------------------------------------

    def key(self, kind: str, source: Path, extra: list[Any] | None = None) -> str | None:
        """The key of ``kind`` made from ``source`` (and ``extra``, what else generation was
        told: a .vepl's `--param` values); None when the file cannot be read (then
        generation reports why, as without a cache)."""
        data = read_bounded(source)
        if not isinstance(data, bytes):
            return None
        # The path as given too: a model may keep it as spelled (a room's path, in messages).
        text = json.dumps([FORMAT, kind, code_fingerprint(), str(source),
                           os.path.abspath(source), _sha256(data), *([extra] if extra else [])])
        return _sha256(text.encode("utf-8"))

    def cached(self, kind: str, source: Path,
               make: Callable[[], tuple[dict[str, bytes], T]],
               extra: list[Any] | None = None) -> tuple[dict[str, bytes], T]:
        """The files and value ``make`` returns, from a valid entry when there is one; else
        made now (its errors are the caller's, as without a cache) and stored."""
        key = self.key(kind, source, extra)
        if key is not None:
            found = self.lookup(key)
            if found is not None:
                return found
        with recorded_reads() as reads:
            files, value = make()
        if key is not None:
            self.store(key, reads, files, value)
        return files, value

    def entry(self, key: str) -> Path:
        return self.root / key[:2] / key

    def lookup(self, key: str) -> tuple[dict[str, bytes], Any] | None:
        """The entry's files and value when it is whole and its inputs unchanged, else None."""
        folder = self.entry(key)
        try:
            index = json.loads((folder / "entry.json").read_text(encoding="utf-8"))
            if not isinstance(index, dict) or index.get("format") != FORMAT \
                    or not isinstance(index.get("files"), dict) \
                    or not isinstance(index.get("reads"), list):
                return None
            if not _same_inputs(index["reads"]):
                return None
            blob = (folder / "value.pickle").read_bytes()
            if _sha256(blob) != index.get("value"):
                return None
            files: dict[str, bytes] = {}
            for number, (name, digest) in enumerate(sorted(index["files"].items())):
                data = (folder / "files" / str(number)).read_bytes()
                if _sha256(data) != digest:
                    return None
                files[name] = data
            return files, pickle.loads(blob)  # noqa: S301  (the user's own cache, see above)
        except (OSError, ValueError, TypeError, pickle.UnpicklingError, EOFError,
                AttributeError, ImportError):
            return None

    def store(self, key: str, reads: Reads, files: dict[str, bytes], value: object) -> None:
        """Write the entry (replacing a stale one); a cache that cannot be written is left
        as it is: the run has what it needs."""
        folder = self.entry(key)
        try:
            folder.parent.mkdir(parents=True, exist_ok=True)
            work = Path(tempfile.mkdtemp(prefix=f".{key[:16]}-", dir=folder.parent))
        except OSError:
            return
        try:
            blob = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
            (work / "value.pickle").write_bytes(blob)
            (work / "files").mkdir()
            listed = {}
            for number, (name, data) in enumerate(sorted(files.items())):
                (work / "files" / str(number)).write_bytes(data)
                listed[name] = _sha256(data)
            index = {"format": FORMAT, "reads": [list(r) for r in reads], "files": listed,
                     "value": _sha256(blob)}
            # entry.json last: even a folder renamed by hand half-way is never whole
            (work / "entry.json").write_text(json.dumps(index, indent=1), encoding="utf-8")
            self._install(work, folder)
        except (OSError, pickle.PicklingError, TypeError, AttributeError):
            pass
        finally:
            shutil.rmtree(work, ignore_errors=True)

    @staticmethod
    def _install(work: Path, folder: Path) -> None:
        """Rename the finished entry into place; a stale entry there is moved aside first."""
        try:
            os.rename(work, folder)
            return
        except OSError:
            pass  # an entry is there: stale (we missed it) or just written by another run
        aside = Path(tempfile.mkdtemp(prefix=f".{folder.name[:16]}-old-", dir=folder.parent))
        try:
            os.rename(folder, aside / "entry")
        except OSError:
            shutil.rmtree(aside, ignore_errors=True)
            return
        try:
            os.rename(work, folder)
        except OSError:
            pass  # another writer's entry won the place: as good as ours
        shutil.rmtree(aside, ignore_errors=True)
