"""Issue 34's regrouping of runtime/ into wings, driven by scripts/regroup-table.tsv.

The move itself (every module of the table moved with `git mv`, then this rewrite over the whole
repository) was made once, in its own commit ("runtime/: the move of scripts/regroup-table.tsv").
What stays useful is the rewrite, for code outside REI that imports the old paths (a controller
importing ``rei.runtime.robot.protocol``, a script importing ``rei.runtime.commands.run``):

    python scripts/regroup.py PATH...     # rewrite those files (or folders) in place

It rewrites ``from OLD import name`` statements (``from rei.runtime.animator import animator``
included: a module imported from its package), names from the two packages that were dissolved
(``rei.runtime.collector``, ``rei.runtime.world``: each name to the module defining it now),
names the later splits moved out of a module (``SPLIT_OUT``: ``run_into`` to
``rei.runtime.runs.session``, ...), and every other dotted mention of an old module (strings,
docstrings, comments, Markdown).
"""

from __future__ import annotations

import argparse
import ast
import re
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
_R = PREFIX
SPLIT_OUT = {
    # Names the later splits of issue 34 moved out of the module the table gives: (that
    # module, name) -> the module that defines the name now.
    **{(f"{_R}.commands.run", n): f"{_R}.runs.session" for n in (
        "run_into", "execute_request", "check_options", "exit_code", "make_folder",
        "set_aside", "settle_earlier", "read_summary", "PAGE", "TRACE", "SUMMARY", "LOG",
        "EVENTS", "RECORDING", "RUN_OUTPUTS", "EARLIER_OUTPUTS")},
    (f"{_R}.commands.replay", "judge_stream"): f"{_R}.observation.judgement",
    **{(f"{_R}.simulation.sensors.laser", n): f"{_R}.raycast" for n in (
        "ShapeSet", "RayCaster", "merge_wall_tiles", "shapes_of", "scene_shapes", "ray_boxes",
        "ray_circles")},
    **{(f"{_R}.campaigns.folder_reader", n): f"{_R}.observation.run_folder" for n in (
        "Paths", "SignalEvent", "read_events", "read_paths")},
    **{(f"{_R}.campaigns.store", n): f"{_R}.campaigns.run_records" for n in (
        "RunRecord", "verdict_reason", "RECORD_FORMAT", "STORE_VERSION")},
    **{(f"{_R}.campaigns.store", n): f"{_R}.campaigns.results_table" for n in (
        "record_row", "rows_table", "write_tables")},
    **{(f"{_R}.robot.selection", n): f"{_R}.robot.loading" for n in (
        "load_controller", "BUILT_IN")},
    **{(f"{_R}.simulation.animator.engine", n): f"{_R}.simulation.animator.bodies" for n in (
        "Animated", "Reactions", "spline_of", "animated_bodies", "variations_record",
        "wall_boxes")},
    **{(f"{_R}.simulation.animator.social_force", n): f"{_R}.simulation.animator.{m}"
       for m, names in (("agent", ("Agent", "Vec")),
                        ("walls", ("wall_distance", "wall_normals", "room_aside", "way_aside")),
                        ("yielding", ("YieldRule", "gap_in_the_way", "gap_beside",
                                      "speed_share", "yield_factor")))
       for n in names},
    **{(f"{_R}.observation.model.runtime_model", n): f"{_R}.observation.model.{m}"
       for m, names in (("floors", ("FloorMap",)), ("pushes", ("PushTracker",)),
                        ("interpolation", ("interpolate", "crossings")),
                        ("sample_checks", ("PROBLEM_KINDS", "SampleProblems", "check_sample")))
       for n in names},
    **{(f"{_R}.observation.model.efficiency", n): f"{_R}.observation.model.free_space"
       for n in ("FloorGraph", "FreeSpace", "footprint_shapes")},
    **{(f"{_R}.presentation.run_page.rendering", n): f"{_R}.presentation.campaign_report.html"
       for n in ("run_page_link",)},
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
                target = self.target(module)
                target = SPLIT_OUT.get((target, alias.name), target)
                out.append((target, alias.name, alias.asname))
                changed = changed or target != module
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


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("paths", nargs="+", type=Path, metavar="PATH",
                        help="rewrite old import paths in these files or folders, in place")
    args = parser.parse_args()
    rows = load_table()
    rewriter = Rewriter(module_map(rows), dict(rows))
    changed = [p for p in files_under(args.paths) if p.resolve() != TABLE and rewriter.file(p)]
    print(f"{len(changed)} files rewritten", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
