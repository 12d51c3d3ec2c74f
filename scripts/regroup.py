"""Issue 34's regrouping of runtime/ into wings, driven by scripts/regroup-table.tsv.

`python scripts/regroup.py --move` moved every module of the table with `git mv` and rewrote
every import and dotted name in the repository; it was run once, in its own commit. What stays
useful is the rewrite alone, for code outside REI that imports the old paths (a controller
importing ``rei.runtime.robot.protocol``, a script importing ``rei.runtime.commands.run``):

    python scripts/regroup.py --rewrite PATH...     # rewrite those files (or folders) in place

It rewrites ``from OLD import name`` statements (``from rei.runtime.animator import animator``
included: a module imported from its package), names from the two packages that were dissolved
(``rei.runtime.collector``, ``rei.runtime.world``: each name to the module defining it now),
and every other dotted mention of an old module (strings, docstrings, comments, Markdown).
"""

from __future__ import annotations

import argparse
import ast
import re
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
TABLE = HERE / "regroup-table.tsv"
PREFIX = "rei.runtime"

DISSOLVED = {
    # The two packages whose __init__ re-exported names and did not move as a package: each
    # name to the old module that defined it.
    "collector": {
        "DataCollector": "collector.collector",
        "MonitorConfig": "collector.config", "load_monitor_config": "collector.config",
        "SampleList": "collector.sink", "SampleSink": "collector.sink",
        "TraceError": "collector.trace", "TraceWriter": "collector.trace",
        "read_trace": "collector.trace", "write": "collector.trace",
    },
    "world": {
        "BodySpec": "world.manifest", "Trajectory": "world.manifest",
        "WorldManifest": "world.manifest", "load_manifest": "world.manifest",
    },
}
TEXT_SUFFIXES = {".py", ".md", ".j2", ".toml", ".txt", ".sh", ".cfg", ".ini", ".json", ".tsv", ""}


def dotted(path: str) -> str:
    parts = path.removesuffix(".py").split("/")
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def load_table() -> list[tuple[str, str]]:
    rows = []
    for line in TABLE.read_text(encoding="utf-8").splitlines():
        if line.strip() and not line.startswith("#"):
            old, new = line.split("\t")
            rows.append((old, new))
    return rows


def module_map(rows: list[tuple[str, str]]) -> dict[str, str]:
    mapping = {}
    for old, new in rows:
        o, n = dotted(old), dotted(new)
        mapping[f"{PREFIX}.{o}" if o else PREFIX] = f"{PREFIX}.{n}" if n else PREFIX
    return mapping


class Rewriter:
    def __init__(self, mapping: dict[str, str], paths: dict[str, str]) -> None:
        self.mapping = mapping
        olds = sorted((m for m in mapping if m != PREFIX), key=len, reverse=True)
        self.dotted = re.compile(r"(?<![\w.])(" + "|".join(map(re.escape, olds)) + r")(?!\w)")
        files = sorted((o for o in paths if o != paths[o]), key=len, reverse=True)
        self.paths = paths
        self.slashed = re.compile(r"(?<![\w/])runtime/(" + "|".join(map(re.escape, files))
                                  + r")(?![\w/])")
        for new in mapping.values():  # no new name may be read again as an old one
            hit = self.dotted.search(new)
            assert hit is None or mapping[hit.group(1)] == hit.group(1), new

    def target(self, module: str) -> str:
        return self.mapping.get(module, module)

    def split_import(self, node: ast.ImportFrom) -> list[tuple[str, str, str | None]] | None:
        """(module, name, asname) per alias, or None when nothing of it moved."""
        module = node.module or ""
        if node.level or not module.startswith(PREFIX):
            return None
        short = module[len(PREFIX) + 1:]
        out = []
        changed = False
        for alias in node.names:
            full = f"{module}.{alias.name}"
            if full in self.mapping:  # a module imported from its package
                new = self.mapping[full]
                parent, _, leaf = new.rpartition(".")
                asname = alias.asname or (alias.name if leaf != alias.name else None)
                out.append((parent, leaf, asname))
                changed = changed or new != full
            elif short in DISSOLVED and alias.name in DISSOLVED[short]:
                out.append((self.target(f"{PREFIX}.{DISSOLVED[short][alias.name]}"),
                            alias.name, alias.asname))
                changed = True
            else:
                out.append((self.target(module), alias.name, alias.asname))
                changed = changed or self.target(module) != module
        return out if changed else None

    def python(self, text: str) -> str:
        try:
            tree = ast.parse(text)
        except SyntaxError:
            return self.plain(text)
        lines = text.splitlines(keepends=True)
        edits = []
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                parts = self.split_import(node)
                if parts is None:
                    continue
                first, last = node.lineno - 1, node.end_lineno - 1
                indent = re.match(r"\s*", lines[first]).group(0)
                tail = lines[last][node.end_col_offset:].rstrip("\n")
                by_module: dict[str, list[str]] = {}
                for module, name, asname in parts:
                    by_module.setdefault(module, []).append(
                        f"{name} as {asname}" if asname else name)
                statements = []
                for module, names in by_module.items():
                    one = f"{indent}from {module} import {', '.join(names)}{tail}"
                    if len(one) > 100:
                        inner = "".join(f"{indent}    {n},\n" for n in names)
                        one = f"{indent}from {module} import ({tail}\n{inner}{indent})"
                    statements.append(one + "\n")
                edits.append((first, last, statements))
        for first, last, statements in sorted(edits, reverse=True):
            lines[first:last + 1] = statements
        return self.plain("".join(lines))

    def plain(self, text: str) -> str:
        text = self.dotted.sub(lambda m: self.mapping[m.group(1)], text)
        return self.slashed.sub(lambda m: "runtime/" + self.paths[m.group(1)], text)

    def file(self, path: Path) -> bool:
        try:
            text = path.read_text(encoding="utf-8")
        except (UnicodeDecodeError, OSError):
            return False
        new = self.python(text) if path.suffix == ".py" else self.plain(text)
        if new != text:
            path.write_text(new, encoding="utf-8")
            return True
        return False


def files_under(paths: list[Path]) -> list[Path]:
    out = []
    skip = {".git", ".venv", "node_modules", "__pycache__", ".hypothesis", ".pytest_cache"}
    for path in paths:
        if path.is_file():
            out.append(path)
            continue
        for p in path.rglob("*"):
            if p.is_file() and not skip & set(p.relative_to(path).parts) \
                    and p.suffix in TEXT_SUFFIXES:
                out.append(p)
    return out


def move(rows: list[tuple[str, str]]) -> None:
    runtime = ROOT / "runtime"
    for old, new in rows:
        if old == new:
            continue
        (runtime / new).parent.mkdir(parents=True, exist_ok=True)
        subprocess.run(["git", "mv", str(runtime / old), str(runtime / new)], check=True,
                       cwd=ROOT)
    for package in DISSOLVED:
        init = runtime / package / "__init__.py"
        if init.exists():
            subprocess.run(["git", "rm", "-q", str(init)], check=True, cwd=ROOT)
    for folder in sorted(runtime.rglob("*"), reverse=True):  # new packages get an __init__
        if folder.is_dir() and folder.name != "__pycache__" and any(folder.glob("*.py")) \
                and not (folder / "__init__.py").exists():
            (folder / "__init__.py").write_text('"""TODO: door sign."""\n', encoding="utf-8")
    for folder in sorted(runtime.rglob("*"), reverse=True):  # emptied ones go
        if folder.is_dir() and not any(p for p in folder.rglob("*")
                                       if p.is_file() and "__pycache__" not in p.parts):
            subprocess.run(["rm", "-rf", str(folder)], check=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--move", action="store_true",
                        help="git mv the table's modules, then rewrite the whole repository")
    parser.add_argument("--rewrite", nargs="+", type=Path, metavar="PATH",
                        help="rewrite old import paths in these files or folders")
    args = parser.parse_args()
    rows = load_table()
    rewriter = Rewriter(module_map(rows), dict(rows))
    if args.move:
        move(rows)
        targets = [ROOT]
    elif args.rewrite:
        targets = args.rewrite
    else:
        parser.error("give --move or --rewrite PATH...")
    changed = [p for p in files_under(targets) if p.resolve() != TABLE and p.resolve() != Path(
        __file__).resolve() and rewriter.file(p)]
    print(f"{len(changed)} files rewritten", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
