"""What a suite covers: levels per factor, pairs of levels, cells of the parameter space,
and the ranges of the difficulty descriptors (so a user can see what is missing before
running hours of simulation). Pure text, no files."""

from __future__ import annotations

from collections import Counter

from rei.generators.rooms.descriptors import DESCRIPTOR_NAMES, format_number
from rei.generators.rooms.design import uncovered_pairs
from rei.generators.rooms.suite import Suite

BINS = 5


def _quantile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    pos = q * (len(ordered) - 1)
    lo = int(pos)
    hi = min(lo + 1, len(ordered) - 1)
    return ordered[lo] + (ordered[hi] - ordered[lo]) * (pos - lo)


def coverage_report(suite: Suite) -> str:
    space = suite.request.space
    factors = space.factors
    sizes = [len(f.levels) for f in factors]
    used_rows = [suite.design.rows[p.design_row - 1] for p in suite.pairs]
    lines = [f"Suite of {len(suite.pairs)} room(s), strategy {suite.request.strategy}, "
             f"design {suite.design.design}, seed {suite.request.seed}"]
    lines.append(f"Parameter space: {len(factors)} factors, {space.grid_size} cells in the full "
                 f"grid; the suite uses {len(set(used_rows))} distinct cell(s)")
    if suite.design.design != "random":
        missing_rows = len(suite.design.rows) - len({p.design_row for p in suite.pairs})
        lines.append(f"Design rows: {len(suite.design.rows)}, generated "
                     f"{len(suite.design.rows) - missing_rows}"
                     + (f" ({missing_rows} not generated: raise --count)" if missing_rows
                        else ""))
    lines.append("")
    lines.append("Levels (rooms per level):")
    for k, factor in enumerate(factors):
        counts = Counter(row[k] for row in used_rows)
        cells = ", ".join(f"{level}: {counts.get(i, 0)}" for i, level in enumerate(factor.levels))
        lines.append(f"  {factor.name:<9} {cells}")
    missing = uncovered_pairs(sizes, used_rows)
    total = sum(sizes[i] * sizes[j] for i in range(len(sizes)) for j in range(i + 1, len(sizes)))
    lines.append("")
    lines.append(f"Pairs of levels covered: {total - len(missing)} of {total}")
    for i, a, j, b in missing[:10]:
        lines.append(f"  missing: {factors[i].name}={factors[i].levels[a]} with "
                     f"{factors[j].name}={factors[j].levels[b]}")
    if len(missing) > 10:
        lines.append(f"  ... and {len(missing) - 10} more")
    lines.append("")
    lines.append(f"Difficulty ranges (min / quartiles / max; rooms in {BINS} equal bins):")
    for name in DESCRIPTOR_NAMES:
        values = [float(getattr(p.plan.descriptors, name)) for p in suite.pairs]
        if not values:
            continue
        lo, hi = min(values), max(values)
        width = (hi - lo) / BINS
        bins = [0] * BINS
        for v in values:
            bins[min(BINS - 1, int((v - lo) / width)) if width > 0 else 0] += 1
        quart = " / ".join(format_number(_quantile(values, q)) for q in (0.25, 0.5, 0.75))
        lines.append(f"  {name:<27} {format_number(lo)} / {quart} / {format_number(hi)}   "
                     f"bins {' '.join(str(b) for b in bins)}")
    return "\n".join(lines) + "\n"
