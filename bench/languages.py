"""Benchmark: how fast `rei-gen check` reads rooms, against a bare textX parse of the same text.

Run:  .venv/bin/python bench/languages.py [--floors 1000 10000]

For each size, a room written with explicit floors and the same room as a grid block are
checked in full (parse, link, layout, catalogue, reachability); the baseline is textX parsing
the same text with a plain metamodel of the same grammar and no REI processing, measured in the
same run. Reports seconds, lines/s, floors/s and the ratio check/parse.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from textx import metamodel_from_file

from rei.lang.parsing import grammar_path
from rei.lang.workspace import Workspace


def room_text(floors: int, form: str) -> str:
    width = max(1, int(floors ** 0.5))
    height = max(1, floors // width)
    if form == "grid":
        rows = ["#" * (width + 2)] + ["#" + "." * width + "#"] * height + ["#" * (width + 2)]
        body = "\n".join(f'        "{row}"' for row in rows)
        return (f"room bench {{\n    grid g {{\n{body}\n    }}\n"
                f"    robot r : turtlebot3_waffle on g_1_1\n}}\n")
    lines = ["room bench {"]
    for i in range(height):
        for j in range(width):
            links = []
            if j + 1 < width:
                links.append(f"right f{i}_{j + 1}")
            if i + 1 < height:
                links.append(f"bottom f{i + 1}_{j}")
            lines.append(f"    floor f{i}_{j} {{ {' '.join(links)} }}")
    lines.append("    robot r : turtlebot3_waffle on f0_0")
    lines.append("}")
    return "\n".join(lines) + "\n"


def best_of(repeats: int, func) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--floors", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    bare = metamodel_from_file(grammar_path("room"), auto_init_attributes=False, autokwd=True)
    print(f"{'floors':>7} {'form':>8} {'lines':>7} {'parse s':>8} {'check s':>8} "
          f"{'lines/s':>9} {'floors/s':>9} {'check/parse':>11}")
    with tempfile.TemporaryDirectory() as tmp:
        for floors in args.floors:
            for form in ("explicit", "grid"):
                text = room_text(floors, form)
                path = Path(tmp) / f"{form}_{floors}.room"
                path.write_text(text)
                parse_s = best_of(args.repeats, lambda text=text: bare.model_from_str(text))
                diagnostics = Workspace().check(path)
                assert not diagnostics, diagnostics[:3]
                check_s = best_of(args.repeats, lambda path=path: Workspace().check(path))
                lines = text.count("\n")
                print(f"{floors:>7} {form:>8} {lines:>7} {parse_s:>8.3f} {check_s:>8.3f} "
                      f"{lines / check_s:>9.0f} {floors / check_s:>9.0f} "
                      f"{check_s / parse_s:>11.2f}")


if __name__ == "__main__":
    main()
