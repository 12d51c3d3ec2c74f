"""JUnit XML of a campaign for CI: a test suite per mission, a test case per requirement per run.

The test cases follow the one pass rule (rei.runtime.results.judge): a failed requirement is
a <failure> with its reason, deciding time and the objects involved; an inconclusive one is a
<failure> too (the run does not pass, so CI must not show it green); a requirement that did not
apply is <skipped>; a run that crashed, hung or ended in error is an <error> test case named
"run". Each run's wall time is shared out over its test cases, so the suite's time is the real
time spent; the seed, the re-run command and the specification's parameters set with
`--param` to other values than the file's (``param.NAME``) are properties of every case.
This module must never read files.
"""

from __future__ import annotations

from collections.abc import Sequence

from lxml import etree

from rei.runtime.campaigns.run_records import RunRecord
from rei.runtime.campaigns.stats import by_mission
from rei.runtime.results import Verdict


def _case(suite: etree._Element, record: RunRecord, name: str, time: float, rerun: str
          ) -> etree._Element:
    case = etree.SubElement(suite, "testcase", name=name, classname=record.spec.run_id,
                            time=f"{time:.3f}")
    props = etree.SubElement(case, "properties")
    for key, value in (("seed", str(record.spec.seed)), ("repeat", str(record.spec.repeat)),
                       ("mission_file", record.spec.mission_file), ("rerun", rerun)):
        etree.SubElement(props, "property", name=key, value=value)
    # what the verdicts were judged against beyond the .vepl (`--param`, values other than
    # the file's)
    parameters = record.summary.parameters if record.summary is not None else {}
    for key, number in sorted(parameters.items()):
        etree.SubElement(props, "property", name=f"param.{key}", value=f"{number:g}")
    return case


def _verdict_text(v: Verdict) -> str:
    at = f" at t={v.decided_at:g} s" if v.decided_at is not None else ""
    objects = f" (involving {', '.join(v.objects)})" if v.objects else ""
    return f"{v.requirement} {v.status}{at}{objects}: {v.reason}"


def junit_xml(records: Sequence[RunRecord], rerun: dict[str, str], name: str = "rei campaign"
              ) -> bytes:
    """The JUnit document; ``rerun`` maps run ids to the command that repeats the run."""
    root = etree.Element("testsuites", name=name)
    suites: dict[str, list[RunRecord]] = {}
    for record in records:
        suites.setdefault(by_mission(record), []).append(record)
    totals = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
    total_time = 0.0
    for mission, runs in suites.items():
        suite = etree.SubElement(root, "testsuite", name=mission)
        counts = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
        suite_time = 0.0
        for record in runs:
            label = f"repeat {record.spec.repeat}, seed {record.spec.seed}"
            command = rerun.get(record.spec.run_id, "")
            summary = record.summary
            verdicts = summary.verdicts if summary is not None else ()
            broken = record.verdict in ("error", "interrupted")
            cases = len(verdicts) + (1 if broken or not verdicts else 0)
            share = record.wall_time / cases
            suite_time += record.wall_time
            if broken:
                case = _case(suite, record, f"run [{label}]", share, command)
                why = summary.reason if summary is not None else record.message
                kind = summary.outcome if summary is not None else record.status
                etree.SubElement(case, "error", message=f"{kind}: {why}"[:500],
                                 type=kind).text = f"{kind}: {why}\nre-run: {command}"
                counts["tests"] += 1
                counts["errors"] += 1
            for verdict in verdicts:
                case = _case(suite, record, f"{verdict.requirement} [{label}]", share, command)
                if verdict.margin is not None:
                    props = case.find("properties")
                    assert props is not None  # _case always adds it
                    etree.SubElement(props, "property", name="margin",
                                     value=f"{verdict.margin:.6g} {verdict.margin_unit}")
                counts["tests"] += 1
                text = _verdict_text(verdict)
                if verdict.status in ("fail", "inconclusive"):
                    counts["failures"] += 1
                    etree.SubElement(case, "failure", message=text[:500],
                                     type=verdict.status).text = f"{text}\nre-run: {command}"
                elif verdict.status == "not_applicable":
                    counts["skipped"] += 1
                    etree.SubElement(case, "skipped", message=text[:500])
            if not broken and not verdicts:
                # No requirements were checked: the run itself is the test case.
                _case(suite, record, f"run [{label}]", share, command)
                counts["tests"] += 1
        for key, value in counts.items():
            suite.set(key, str(value))
            totals[key] += value
        suite.set("time", f"{suite_time:.3f}")
        total_time += suite_time
    for key, value in totals.items():
        root.set(key, str(value))
    root.set("time", f"{total_time:.3f}")
    data: bytes = etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)
    return data
