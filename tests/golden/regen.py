"""Golden files: every available target on every example it accepts, byte for byte.

Layout: ``tests/golden/<example>/<input file>/<target>/<generated files>``, e.g.
``tests/golden/navigation/navigation.mission/gazebo/world.sdf``. Regenerate after an
intended change with ``bash scripts/regen-golden`` (runs ``python -m tests.golden.regen``) and
review the diff. Targets are found through ``available_targets()``, so a target added later
is covered as soon as its owner runs the script. This module must never regenerate goldens
during a test run: tests only compare.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from rei.generators.pipeline import plan
from rei.generators.targets import available_targets
from tests.conftest import EXAMPLES, example_files

GOLDEN = Path(__file__).resolve().parent
REGEN_COMMAND = "bash scripts/regen-golden"


def inputs() -> list[Path]:
    return sorted(example_files(".room") + example_files(".mission") + example_files(".vepl"))


def cases() -> list[tuple[Path, str]]:
    """(example file, target name) for every target that accepts the example's suffix."""
    targets = available_targets()
    return [(path, name) for path in inputs() for name, target in sorted(targets.items())
            if path.suffix in target.accepts]


def case_dir(path: Path, target: str) -> Path:
    example = path.parent.relative_to(EXAMPLES)
    return GOLDEN / example / path.name / target


def generated(path: Path, target: str) -> dict[str, bytes]:
    return dict(plan(path, target).tree.files)


def stored(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def main() -> int:
    examples = {p.parent.relative_to(EXAMPLES) for p in inputs()}
    for example in sorted(examples):
        shutil.rmtree(GOLDEN / example, ignore_errors=True)
    count = 0
    for path, target in cases():
        folder = case_dir(path, target)
        for rel, data in sorted(generated(path, target).items()):
            out = folder / rel
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_bytes(data)
            count += 1
    print(f"wrote {count} golden file(s) for {len(cases())} (example, target) case(s) "
          f"under {GOLDEN.relative_to(GOLDEN.parent.parent)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
