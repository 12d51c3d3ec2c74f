"""Bug-finding benchmark: does REI fail buggy navigation software and pass correct software?

Runs the campaign `rei demo` runs (a suite of ``--count`` generated ``--preset`` rooms, seed S,
every mission ``--repeat`` times with seeds derived from S, the default .vepl) once per
campaign seed with each navigator: the correct `reference` (the baseline, measured in the same
invocation) and every defective navigator of bench/defects (one realistic defect each). A run
fails as `rei campaign` counts it: it did not complete its mission (a failed task, a time-out,
a crash) or a requirement's verdict is not "pass". A navigator is *flagged* on a seed when any
run of that campaign fails; it is *caught* on a seed when it fails a run (same mission, repeat
and seed) that the reference passed: failures both share are the suite's (a mission the
correct navigator cannot complete either), not detections.

Reported per navigator: seeds caught (and flagged), failed runs, and what caught them: each
requirement whose verdict was "fail" (counted over the failed runs the reference passed; names
are read from the runs' summary.json, none is assumed here), "inconclusive" verdicts apart, and
the runs whose only failure is the task outcome ("task:failed (timeout)", "task:crashed", ...).
A second table names, per defect and seed, the requirements that caught it (the target: a
named requirement on every seed). Then: detection rate (defects caught on every seed / defects;
and caught seed-campaigns /
defect seed-campaigns), the reference's false-alarm rate (its campaigns with any failed run),
which defects were caught only by task outcomes, and each navigator's campaign wall time (noisy
on a shared machine) and simulated seconds (deterministic: longer missions, time-outs) relative
to the reference's on the same seed.

Writes bench/out/bugs.json (every run's verdicts); ``--markdown`` prints the table for
bench/RESULTS.md. ``--quick`` is a smoke test: the first seed, 2 rooms, one run per mission.
``--examples`` adds the four bundled examples to every campaign: the small preset has no
humans and no goal headings or speed limits, so some defects cannot show in the demo suite.

``--families`` measures the suite instead of scoring a fixed set of defects: each knock-out
family of bench/knockouts (one defect at graded severities, a wrapper around any navigator)
runs at each severity on each seed, against the same campaigns, with the navigator the
knock-outs wrap as the baseline (``reference``, or ``--base SPEC``). Reported per family: its
*detection threshold*, the mildest severity caught on every seed (a point of a sensitivity
curve: milder defects than that slip through the suite), with the seeds caught at each
severity and the requirements that caught it; and knock-outs whose every run was the same as
the baseline's (a defect the suite never lets show, or, for ``recovery``, a base that does
not report its recoveries). All severities run unless ``--stop-after-miss``: then each family
runs from severe to mild and stops after the first severity missed on every seed (the output
says which were not run). Writes bench/out/families.json.

Usage: python bench/bugs.py [--seeds S ...] [--workers N] [--only NAME ...] [--quick]
       [--count N] [--repeat K] [--preset small|medium|large] [--examples] [--resume]
       [--markdown] [--out DIR]
       python bench/bugs.py --families [FAMILY ...] [--base SPEC] [--stop-after-miss] ...
"""

from __future__ import annotations

import argparse
import io
import json
import os
import shutil
import sys
import time
from collections import Counter
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
# The defects are `bench.defects.MODULE:Class`: importable here and in every run's process
# (a run imports its controller from its own working folder and PYTHONPATH).
sys.path.insert(0, str(REPO))
os.environ["PYTHONPATH"] = os.pathsep.join(
    p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p)

from bench.defects import DEFECTS  # noqa: E402
from bench.knockouts import (  # noqa: E402
    BASE_VARIABLE,
    FAMILIES,
    KNOCKOUTS,
    Family,
    Knockout,
    base_spec,
)
from bench.knockouts import make as make_knockout  # noqa: E402
from rei.runtime.campaigns import LocalEngine, RunRecord, plan_campaign, run_campaign  # noqa: E402
from rei.runtime.commands.demo import DEMO_ROOMS  # noqa: E402
from rei.runtime.robot import load_controller  # noqa: E402

REFERENCE = "reference"
TASK = "task:"
"""Prefix of a catcher that is a run's outcome (failed task, time-out, crash), not a verdict."""
INCONCLUSIVE = "inconclusive:"


@dataclass(frozen=True)
class Navigator:
    name: str
    kind: str
    spec: str
    expected: str
    """The docstring's "Expected catcher" (the defect's own claim, never used for scoring)."""


@dataclass(frozen=True)
class RunOutcome:
    run_id: str
    seed: int
    passed: bool
    outcome: str
    status: str
    reason: str
    simulated: float
    """Simulation seconds of the run (0 without a summary)."""
    task_failures: tuple[str, ...]
    """Why tasks failed, by kind ("timeout", "aborted", "outside tolerance", ...)."""
    failed: tuple[str, ...]
    """Requirements whose verdict was "fail"."""
    inconclusive: tuple[str, ...]
    reasons: dict[str, str] = field(default_factory=dict)
    """Each failed requirement's reason."""

    @property
    def catchers(self) -> list[str]:
        """What made this run fail: its failed (and inconclusive) requirements, and its outcome
        when it did not complete its mission."""
        if self.passed:
            return []
        found = list(self.failed) + [INCONCLUSIVE + r for r in self.inconclusive]
        if self.status != "ran" or self.outcome != "completed":
            kinds = "/".join(self.task_failures)
            found.append(TASK + (self.outcome if self.status == "ran" else self.status)
                         + (f" ({kinds})" if kinds else ""))
        return found


@dataclass(frozen=True)
class CampaignOutcome:
    navigator: str
    seed: int
    wall: float
    runs: tuple[RunOutcome, ...]

    @property
    def flagged(self) -> bool:
        return any(not r.passed for r in self.runs)

    @property
    def simulated(self) -> float:
        return sum(r.simulated for r in self.runs)


def expected_catcher(doc: str) -> str:
    """The "Expected catcher:" paragraph of a defect's docstring, on one line."""
    return " ".join(doc.split("Expected catcher:", 1)[-1].split("\n\n")[0].split())


def navigators(only: list[str] | None) -> list[Navigator]:
    found = [Navigator(REFERENCE, "correct", REFERENCE, "nothing (the correct navigator)")]
    for d in DEFECTS:
        doc = type(load_controller(d.spec)).__doc__ or ""
        found.append(Navigator(d.name, d.kind, d.spec, expected_catcher(doc)))
    if only:
        unknown = sorted(set(only) - {n.name for n in found})
        if unknown:
            raise SystemExit(f"--only: unknown navigator(s) {', '.join(unknown)}; expected "
                             f"among {', '.join(n.name for n in found)}")
        # The reference is the baseline of the time ratios and the false-alarm rate: always run.
        found = [n for n in found if n.name == REFERENCE or n.name in only]
    return found


def failure_kind(reason: str) -> str:
    """A task's failure reason without its figures: "timeout after 30 s" -> "timeout"."""
    kind = reason.split(":")[0].strip()
    return "timeout" if kind.startswith("timeout") else kind


def outcome_of(record: RunRecord) -> RunOutcome:
    s = record.summary
    verdicts = s.verdicts if s is not None else ()
    tasks = s.measurements.get("tasks", []) if s is not None else []
    kinds = sorted({failure_kind(str(t.get("reason", ""))) for t in tasks
                    if isinstance(t, dict) and not t.get("succeeded", True)})
    return RunOutcome(
        run_id=record.spec.run_id, seed=record.spec.seed, passed=record.passed,
        outcome=record.outcome, status=record.status, reason=record.reason,
        simulated=s.duration if s is not None else 0.0,
        task_failures=tuple(kinds),
        failed=tuple(v.requirement for v in verdicts if v.status == "fail"),
        inconclusive=tuple(v.requirement for v in verdicts if v.status == "inconclusive"),
        reasons={v.requirement: v.reason for v in verdicts if v.status == "fail"})


def run_one(nav: Navigator, inputs: list[Path], seed: int, repeat: int, workers: int,
            root: Path, resume: bool) -> CampaignOutcome:
    plan = plan_campaign(inputs, repeat=repeat, seed=seed,
                         controller=None if nav.spec == REFERENCE else nav.spec)
    if not resume:  # a fresh campaign: never mix in runs of older code
        shutil.rmtree(root, ignore_errors=True)
    start = time.perf_counter()
    result = run_campaign(plan, root, LocalEngine(workers), {"command": ["bench/bugs.py"]},
                          stream=io.StringIO())
    wall = time.perf_counter() - start
    return CampaignOutcome(nav.name, seed, wall, tuple(outcome_of(r) for r in result.records))


def suite(out: Path, count: int, preset: str, seed: int, examples: bool,
          stressor: str | None = None) -> list[Path]:
    """The demo's suite; with ``stressor``, ``count`` stress rooms of that one stressor
    instead (their movers' sides alternate over the suite, as in every suite)."""
    from rei.runtime.commands.demo import EXAMPLES, generate_suite  # noqa: PLC0415

    if stressor is None:
        inputs = generate_suite(out / f"suite-{preset}-{count}-seed{seed}", count, preset, seed)
    else:
        from rei.lang.cli import main as rei_gen  # noqa: PLC0415

        folder = out / f"suite-stress-{stressor}-{count}-seed{seed}"
        if not (folder / "index.csv").is_file():
            status = rei_gen(["rooms", "-o", str(folder), "--preset", "stress", "--stressor",
                              stressor, "--count", str(count), "--seed", str(seed)])
            if status != 0:
                raise SystemExit(status)
        inputs = [folder / "index.csv"]
    return [*inputs, EXAMPLES] if examples and EXAMPLES not in inputs else inputs


def catchers(campaigns: list[CampaignOutcome]) -> Counter[str]:
    return Counter(c for camp in campaigns for r in camp.runs for c in r.catchers)


def caught_runs(camp: CampaignOutcome, baseline: CampaignOutcome | None) -> list[RunOutcome]:
    """The runs of ``camp`` that fail where its baseline campaign (same seed; None: not run)
    passed the same mission, repeat and seed: the detections (a failure both share is the
    suite's)."""
    if baseline is None:
        return []
    passed = {r.run_id for r in baseline.runs if r.passed}
    return [r for r in camp.runs if not r.passed and r.run_id in passed]


def summarise(navs: list[Navigator], results: dict[str, list[CampaignOutcome]],
              seeds: list[int], baseline: str = REFERENCE) -> dict[str, Any]:
    """Per navigator and overall figures. Runs are paired with the reference's run of the same
    mission, repeat and seed: a defect is *caught* on a seed when it fails a run the reference
    passed (a failure both share, such as a mission the reference cannot complete either, is
    the suite's, not a detection). ``baseline`` names the correct navigator (the first of
    ``navs``)."""
    ref_camps = results[baseline]
    ref_wall = {c.seed: c.wall for c in ref_camps}
    ref_sim = {c.seed: c.simulated for c in ref_camps}
    ref_of = {c.seed: c for c in ref_camps}
    rows: list[dict[str, Any]] = []
    for nav in navs:
        camps = results[nav.name]
        new = [caught_runs(c, ref_of.get(c.seed)) for c in camps]
        caught = Counter(k for runs in new for r in runs for k in r.catchers)
        named = sorted(k for k in caught if not k.startswith((TASK, INCONCLUSIVE)))
        ratios = [c.wall / ref_wall[c.seed] for c in camps if ref_wall.get(c.seed)]
        sim = [c.simulated / ref_sim[c.seed] for c in camps if ref_sim.get(c.seed)]
        rows.append({
            "navigator": nav.name, "kind": nav.kind, "spec": nav.spec,
            "expected_catcher": nav.expected,
            "seeds": len(camps),
            "seeds_flagged": sum(c.flagged for c in camps),
            "seeds_caught": sum(bool(runs) for runs in new),
            "runs": sum(len(c.runs) for c in camps),
            "runs_failed": sum(not r.passed for c in camps for r in c.runs),
            "runs_failed_reference_passed": sum(len(runs) for runs in new),
            "caught_by": dict(caught.most_common()),
            "caught_by_all_failed_runs": dict(catchers(camps).most_common()),
            "caught_by_requirement": bool(named),
            "per_seed": {str(c.seed): dict(Counter(k for r in runs for k in r.catchers)
                                           .most_common())
                         for c, runs in zip(camps, new, strict=True)},
            "time_vs_reference": sum(ratios) / len(ratios) if ratios else None,
            "simulated_vs_reference": sum(sim) / len(sim) if sim else None,
        })
    defects = [r for r in rows if r["navigator"] != baseline]
    ref = rows[0]

    def rate(key: str, every: bool) -> float | None:
        if not defects:
            return None
        if every:
            return sum(r[key] == r["seeds"] for r in defects) / len(defects)
        return sum(r[key] for r in defects) / sum(r["seeds"] for r in defects)

    return {
        "seeds": seeds,
        "rows": rows,
        "detection_rate_every_seed": rate("seeds_caught", True),
        "detection_rate_per_seed_campaign": rate("seeds_caught", False),
        "flagged_rate_every_seed": rate("seeds_flagged", True),
        "flagged_rate_per_seed_campaign": rate("seeds_flagged", False),
        "false_alarm_rate": ref["seeds_flagged"] / ref["seeds"] if ref["seeds"] else None,
        "reference_failed_runs": ref["runs_failed"],
        "defects_caught_every_seed": [r["navigator"] for r in defects
                                      if r["seeds_caught"] == r["seeds"]],
        "defects_never_caught": [r["navigator"] for r in defects if r["seeds_caught"] == 0],
        "caught_only_by_task_outcome": [r["navigator"] for r in defects
                                        if r["seeds_caught"] and not r["caught_by_requirement"]],
        "caught_by_a_requirement": [r["navigator"] for r in defects
                                    if r["caught_by_requirement"]],
        "caught_by_a_requirement_every_seed": [
            r["navigator"] for r in defects if r["per_seed"] and all(
                any(not k.startswith((TASK, INCONCLUSIVE)) for k in found)
                for found in r["per_seed"].values())],
    }


def named_catchers(found: dict[str, int]) -> str:
    """The requirements that failed in the runs the reference passed, most runs first; the
    task outcome or inconclusive verdicts only when no requirement failed."""
    named = [f"{k} ({n})" for k, n in found.items() if not k.startswith((TASK, INCONCLUSIVE))]
    if named:
        return ", ".join(named)
    other = [f"{k} ({n})" for k, n in found.items()]
    return ("only " + ", ".join(other)) if other else "not caught"


def seed_table(summary: dict[str, Any]) -> str:
    """Per defect and seed: which requirement caught it (runs the reference passed)."""
    seeds = [str(s) for s in summary["seeds"]]
    lines = ["| navigator | " + " | ".join(f"seed {s}" for s in seeds) + " |",
             "|---|" + "---|" * len(seeds)]
    for r in summary["rows"]:
        if r["navigator"] == REFERENCE:
            continue
        cells = [named_catchers(r["per_seed"].get(s, {})) for s in seeds]
        lines.append(f"| {r['navigator']} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table(summary: dict[str, Any], markdown: bool) -> str:
    lines = ["| navigator | kind | seeds caught (flagged) | failed runs the reference passed "
             "(all failed) | caught by (runs the reference passed) | expected catcher "
             "| campaign time vs reference | simulated s vs reference |",
             "|---|---|---:|---:|---|---|---:|---:|"]
    for r in summary["rows"]:
        caught = ", ".join(f"{k} × {n}" for k, n in r["caught_by"].items()) or "—"
        ratio, sim = r["time_vs_reference"], r["simulated_vs_reference"]
        expected = r["expected_catcher"] if markdown else r["expected_catcher"][:50] + "…"
        lines.append(
            f"| {r['navigator']} | {r['kind']} | {r['seeds_caught']}/{r['seeds']} "
            f"({r['seeds_flagged']}) | {r['runs_failed_reference_passed']}/{r['runs']} "
            f"({r['runs_failed']}) | {caught} | {expected} | "
            f"{'—' if ratio is None else f'{ratio:.2f}'} | "
            f"{'—' if sim is None else f'{sim:.2f}'} |")

    def pct(key: str) -> str:
        value = summary[key]
        return "—" if value is None else f"{100 * value:.0f} %"

    n_defects = len(summary["rows"]) - 1
    lines += [
        "",
        f"* Detection rate (defects caught on every seed, i.e. failing a run the reference "
        f"passed): {len(summary['defects_caught_every_seed'])}/{n_defects} = "
        f"{pct('detection_rate_every_seed')}; per seed-campaign: "
        f"{pct('detection_rate_per_seed_campaign')}. Flagged at all (any failed run, shared "
        f"failures included): {pct('flagged_rate_every_seed')}; per seed-campaign: "
        f"{pct('flagged_rate_per_seed_campaign')}.",
        f"* False-alarm rate (reference campaigns with any failed run): "
        f"{pct('false_alarm_rate')} ({summary['reference_failed_runs']} failed run(s)).",
        f"* Never caught: {', '.join(summary['defects_never_caught']) or 'none'}.",
        f"* Caught only by task outcomes (no requirement failed): "
        f"{', '.join(summary['caught_only_by_task_outcome']) or 'none'}.",
        f"* Caught by a named requirement: "
        f"{', '.join(summary['caught_by_a_requirement']) or 'none'}.",
        f"* Caught by a named requirement on every seed: "
        f"{len(summary['caught_by_a_requirement_every_seed'])}/{n_defects} "
        f"({', '.join(summary['caught_by_a_requirement_every_seed']) or 'none'}).",
        "",
        "Per defect and seed, the requirements that failed in runs the reference passed "
        "(number of runs):",
        "",
        seed_table(summary),
    ]
    return "\n".join(lines)


# -- knock-out families (--families) -------------------------------------------------------

def knockout_navigator(family: Family, knockout: Knockout) -> Navigator:
    doc = type(make_knockout(knockout.name)).__doc__ or ""
    return Navigator(knockout.name, family.name, knockout.spec, expected_catcher(doc))


def chosen_families(names: list[str]) -> list[Family]:
    known = {f.name: f for f in FAMILIES}
    unknown = sorted(set(names) - set(known))
    if unknown:
        raise SystemExit(f"--families: unknown famil{'y' if len(unknown) == 1 else 'ies'} "
                         f"{', '.join(unknown)}; expected among {', '.join(known)}")
    return [f for f in FAMILIES if not names or f.name in names]


def caught_on(camp: CampaignOutcome, baseline: CampaignOutcome) -> bool:
    """Whether ``camp`` fails a run its baseline campaign (same seed) passed."""
    return bool(caught_runs(camp, baseline))


def same_as_baseline(camps: list[CampaignOutcome], base: list[CampaignOutcome]) -> bool:
    """Every run ended as the baseline's run of the same mission, repeat and seed: the same
    outcome, the same failed requirements and the same simulated seconds to the last bit (a
    defect that never showed, or a knock-out equal to its base on this suite)."""
    by_seed = {c.seed: {r.run_id: r for r in c.runs} for c in base}
    for camp in camps:
        theirs = by_seed.get(camp.seed, {})
        for run in camp.runs:
            other = theirs.get(run.run_id)
            if other is None or (run.passed, run.outcome, run.failed, run.simulated) != (
                    other.passed, other.outcome, other.failed, other.simulated):
                return False
    return True


def family_rows(families: list[Family], summary: dict[str, Any],
                results: dict[str, list[CampaignOutcome]], baseline: str) -> list[dict[str, Any]]:
    """Per family: each severity's seeds caught and catchers (severities not run: None), and
    the detection threshold, the mildest severity caught on every seed."""
    rows = {r["navigator"]: r for r in summary["rows"]}
    found: list[dict[str, Any]] = []
    for family in families:
        severities: list[dict[str, Any]] = []
        for severity in family.severities:
            name = f"{family.name}_{severity}"
            row = rows.get(name)
            entry: dict[str, Any] = {"knockout": name, "severity": severity,
                                     "shown": f"{severity * family.shown:g}",
                                     "label": family.label(severity), "run": row is not None}
            if row is not None:
                entry.update({
                    "seeds": row["seeds"], "seeds_caught": row["seeds_caught"],
                    "seeds_flagged": row["seeds_flagged"],
                    "caught_seeds": [int(s) for s, found in row["per_seed"].items() if found],
                    "caught_by": row["caught_by"],
                    "same_as_baseline": same_as_baseline(results[name], results[baseline]),
                    "expected_catcher": row["expected_catcher"],
                    "simulated_vs_baseline": row["simulated_vs_reference"]})
            severities.append(entry)
        every = [e for e in severities if e["run"] and e["seeds"]
                 and e["seeds_caught"] == e["seeds"]]
        threshold = every[0] if every else None  # severities run mild to severe
        worse = severities[severities.index(threshold) + 1:] if threshold else []
        found.append({
            "family": family.name, "severity_is": family.unit.format("N"),
            "threshold": None if threshold is None else threshold["severity"],
            "threshold_label": None if threshold is None else threshold["label"],
            "missed_beyond_threshold": [e["severity"] for e in worse
                                        if e["run"] and e["seeds_caught"] < e["seeds"]],
            "severities": severities})
    return found


def family_table(rows: list[dict[str, Any]], summary: dict[str, Any], baseline: str,
                 stop_after_miss: bool, markdown: bool) -> str:
    def curve(row: dict[str, Any]) -> str:
        return ", ".join(f"{e['shown']}: {e['seeds_caught']}/{e['seeds']}" if e["run"]
                         else f"{e['shown']}: not run" for e in row["severities"])

    def threshold(row: dict[str, Any]) -> str:
        if row["threshold"] is None:
            return "none (no severity caught on every seed)"
        text = str(row["threshold_label"])
        if row["threshold"] == row["severities"][0]["severity"]:
            text += " (the mildest tried: the suite's limit is milder still)"
        if row["missed_beyond_threshold"]:
            text += (" (yet missed on some seed at the more severe "
                     + ", ".join(map(str, row["missed_beyond_threshold"])) + ")")
        return text

    def seeds(e: dict[str, Any]) -> str:
        return ", ".join(map(str, e["caught_seeds"])) or "none"

    ref = summary["rows"][0]
    heads = (["family", "severity N", "detection threshold (mildest caught on every seed)",
              "seeds caught per N, mild to severe"],
             ["knock-out", "severity", "seeds caught (flagged)", "caught on seeds",
              "caught by (runs the baseline passed)", "same runs as the baseline"])
    first = [[r["family"], r["severity_is"], threshold(r), curve(r)] for r in rows]
    second = [[e["knockout"], e["label"], f"{e['seeds_caught']}/{e['seeds']} "
               f"({e['seeds_flagged']})", seeds(e), named_catchers(e["caught_by"]),
               "yes" if e["same_as_baseline"] else "no"]
              for r in rows for e in r["severities"] if e["run"]]
    notes = [
        f"* Baseline: {baseline} (the navigator every knock-out wraps); its campaigns with any "
        f"failed run: {ref['seeds_flagged']}/{ref['seeds']} ({ref['runs_failed']} failed "
        f"run(s)). Caught: a knock-out fails a run (same mission, repeat and seed) the "
        f"baseline passed.",
        "* Severities: " + ("each family ran from severe to mild and stopped after the first "
                            "severity missed on every seed (--stop-after-miss); 'not run' "
                            "severities are milder than that one." if stop_after_miss else
                            "every severity of every family ran."),
        "* 'same runs as the baseline': every run ended exactly as the baseline's (outcome, "
        "failed requirements, simulated seconds): the defect never showed on this suite, or "
        "the knock-out equals its base here (overspeed without mission speed limits; "
        "recovery on a base that does not report its recoveries or never recovers).",
    ]
    if markdown:
        def md(head: list[str], body: list[list[str]]) -> list[str]:
            return (["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
                    + ["| " + " | ".join(cells) + " |" for cells in body])
        return "\n".join([*md(heads[0], first), "", *notes, "",
                          "Per knock-out (runs the baseline passed):", "",
                          *md(heads[1], second)])

    def plain(head: list[str], body: list[list[str]]) -> list[str]:
        widths = [max(len(c) for c in column) for column in zip(head, *body, strict=True)]
        return ["  ".join(c.ljust(w) for c, w in zip(cells, widths, strict=True)).rstrip()
                for cells in (head, *body)]
    return "\n".join([*plain(heads[0], first), "", *notes, "", *plain(heads[1], second)])


def run_families(args: argparse.Namespace, seeds: list[int], count: int, repeat: int) -> int:
    """The --families mode: every knock-out family at each severity on each seed."""
    families = chosen_families(args.families)
    base = args.base or base_spec()
    # Every run's process makes its knock-out around this base (it inherits the environment).
    os.environ[BASE_VARIABLE] = base
    baseline = Navigator(REFERENCE if base == REFERENCE else "base", "baseline", base,
                         f"nothing (the base navigator, {base})")
    out: Path = args.out
    started = time.perf_counter()
    inputs = {seed: suite(out / "suites", count, args.preset, seed, args.examples,
                          args.stressor) for seed in seeds}
    results: dict[str, list[CampaignOutcome]] = {}

    def campaigns(nav: Navigator) -> list[CampaignOutcome]:
        found = []
        for seed in seeds:
            camp = run_one(nav, inputs[seed], seed, repeat, args.workers,
                           out / "families" / f"seed{seed}" / nav.name, args.resume)
            failed = sum(not r.passed for r in camp.runs)
            print(f"seed {seed} {nav.name}: {failed}/{len(camp.runs)} runs failed "
                  f"({camp.wall:.0f} s)", file=sys.stderr)
            found.append(camp)
        results[nav.name] = found
        return found

    campaigns(baseline)
    ran: list[Navigator] = []
    for family in families:
        # severe first: the order --stop-after-miss needs
        for knockout in reversed(_knockouts(family)):
            nav = knockout_navigator(family, knockout)
            ran.append(nav)
            camps = campaigns(nav)
            if args.stop_after_miss and not any(
                    caught_on(c, b) for c, b in zip(camps, results[baseline.name], strict=True)):
                break
    order = {k.name: i for i, k in enumerate(k for f in families for k in _knockouts(f))}
    navs = [baseline, *sorted(ran, key=lambda n: order[n.name])]
    summary = summarise(navs, results, seeds, baseline.name)
    rows = family_rows(families, summary, results, baseline.name)
    settings = {"seeds": seeds, "count": count, "repeat": repeat, "preset": args.preset,
                "examples": args.examples, "stressor": args.stressor, "base": base,
                "families": [f.name for f in families], "stop_after_miss": args.stop_after_miss,
                "workers": args.workers, "quick": args.quick, "resumed": args.resume,
                "wall_seconds": time.perf_counter() - started,
                "campaign_wall_seconds": {n: [c.wall for c in camps]
                                          for n, camps in results.items()}}
    report = {"settings": settings, "families": rows, "summary": summary,
              "campaigns": [asdict(c) for camps in results.values() for c in camps]}
    out.mkdir(parents=True, exist_ok=True)
    (out / "families.json").write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    rooms = f"{args.stressor} stress" if args.stressor else args.preset
    walls = [c.wall for camps in results.values() for c in camps]
    print(f"{len(seeds)} seed(s) x {count} {rooms} room(s) x {repeat} run(s)"
          f"{' + examples' if args.examples else ''}; {len(walls)} campaigns, "
          f"{sum(walls) / len(walls):.0f} s each on average "
          f"({time.perf_counter() - started:.0f} s in all); {out / 'families.json'}\n")
    print(family_table(rows, summary, baseline.name, args.stop_after_miss, args.markdown))
    return 0


def _knockouts(family: Family) -> list[Knockout]:
    return [k for k in KNOCKOUTS if k.family == family.name]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3], metavar="S",
                        help="campaign seeds (suite and run seeds; default 1 2 3)")
    parser.add_argument("--workers", type=int, default=2, help="runs at once (default 2)")
    parser.add_argument("--only", nargs="+", default=None, metavar="NAME",
                        help="only these defects (the reference always runs)")
    parser.add_argument("--quick", action="store_true",
                        help="smoke test: first seed, 2 rooms, one run per mission")
    parser.add_argument("--count", type=int, default=DEMO_ROOMS,
                        help=f"rooms per suite (default {DEMO_ROOMS}, as rei demo's)")
    parser.add_argument("--repeat", type=int, default=2, help="runs per mission (demo: 2)")
    parser.add_argument("--preset", choices=("small", "medium", "large"), default="small",
                        help="room class of the suite (demo: small)")
    parser.add_argument("--stressor", default=None, metavar="KIND",
                        help="instead of the demo's suite, --count stress rooms of this one "
                             "stressor (e.g. doorway)")
    parser.add_argument("--examples", action="store_true",
                        help="add the bundled examples (humans, a goal heading) to every "
                             "campaign")
    parser.add_argument("--resume", action="store_true",
                        help="keep the campaigns of an earlier invocation with the same "
                             "settings and run only what they miss (campaign time ratios are "
                             "then meaningless)")
    parser.add_argument("--markdown", action="store_true",
                        help="print the table for bench/RESULTS.md (full expected catchers)")
    parser.add_argument("--out", type=Path, default=REPO / "bench" / "out",
                        help="folder for suites, campaigns and bugs.json (default bench/out)")
    parser.add_argument("--families", nargs="*", default=None, metavar="FAMILY",
                        help="instead of bench/defects, the knock-out families of "
                             "bench/knockouts (all, or these) at each severity: per family "
                             "the detection threshold; writes families.json")
    parser.add_argument("--base", default=None, metavar="SPEC",
                        help="with --families: the navigator the knock-outs wrap, also the "
                             f"baseline, as --controller takes it (default ${BASE_VARIABLE} "
                             "or reference)")
    parser.add_argument("--stop-after-miss", action="store_true",
                        help="with --families: run each family from severe to mild and stop "
                             "after the first severity missed on every seed")
    args = parser.parse_args()
    seeds, count, repeat = args.seeds, args.count, args.repeat
    if args.quick:
        seeds, count, repeat = seeds[:1], 2, 1
    if args.families is not None:
        if args.only:
            parser.error("--only names defects of bench/defects; with --families name families")
        return run_families(args, seeds, count, repeat)
    if args.base or args.stop_after_miss:
        parser.error("--base and --stop-after-miss go with --families")
    navs = navigators(args.only)
    out: Path = args.out
    results: dict[str, list[CampaignOutcome]] = {n.name: [] for n in navs}
    started = time.perf_counter()
    for seed in seeds:
        inputs = suite(out / "suites", count, args.preset, seed, args.examples, args.stressor)
        for nav in navs:
            camp = run_one(nav, inputs, seed, repeat, args.workers,
                           out / "bugs" / f"seed{seed}" / nav.name, args.resume)
            results[nav.name].append(camp)
            failed = sum(not r.passed for r in camp.runs)
            print(f"seed {seed} {nav.name}: {failed}/{len(camp.runs)} runs failed "
                  f"({camp.wall:.0f} s)", file=sys.stderr)
    summary = summarise(navs, results, seeds)
    settings = {"seeds": seeds, "count": count, "repeat": repeat, "preset": args.preset,
                "examples": args.examples, "stressor": args.stressor,
                "workers": args.workers, "quick": args.quick,
                "resumed": args.resume,
                "wall_seconds": time.perf_counter() - started}
    report = {"settings": settings, "summary": summary,
              "campaigns": [asdict(c) for camps in results.values() for c in camps]}
    out.mkdir(parents=True, exist_ok=True)
    (out / "bugs.json").write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    rooms = f"{args.stressor} stress" if args.stressor else args.preset
    print(f"{len(seeds)} seed(s) x {count} {rooms} room(s) x {repeat} run(s)"
          f"{' + examples' if args.examples else ''}; {out / 'bugs.json'}\n")
    print(table(summary, args.markdown))
    return 0


if __name__ == "__main__":
    sys.exit(main())
