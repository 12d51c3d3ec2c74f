"""JUnit XML of a campaign for CI: a test suite per mission, a test case per requirement per run.

A failed requirement is a <failure> with its reason; a run that crashed, hung or ended in error
is an <error> test case named "run"; an inconclusive verdict is <skipped>. This module must
never read files.
"""

from __future__ import annotations

from collections.abc import Sequence

from lxml import etree

from rei.runtime.campaign.stats import by_mission
from rei.runtime.campaign.store import RunRecord


def _case(suite: etree._Element, record: RunRecord, name: str, time: float
          ) -> etree._Element:
    return etree.SubElement(suite, "testcase", name=name, classname=record.spec.run_id,
                            time=f"{time:.3f}")


def junit_xml(records: Sequence[RunRecord], rerun: dict[str, str], name: str = "rei campaign"
              ) -> bytes:
    """The JUnit document; ``rerun`` maps run ids to the command that repeats the run."""
    root = etree.Element("testsuites", name=name)
    suites: dict[str, list[RunRecord]] = {}
    for record in records:
        suites.setdefault(by_mission(record), []).append(record)
    totals = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
    for mission, runs in suites.items():
        suite = etree.SubElement(root, "testsuite", name=mission)
        counts = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
        for record in runs:
            label = f"repeat {record.spec.repeat}, seed {record.spec.seed}"
            summary = record.summary
            broken = record.status != "ran" or summary is None or summary.outcome == "error"
            if broken:
                case = _case(suite, record, f"run [{label}]", record.wall_time)
                etree.SubElement(case, "error", message=f"{record.status}: {record.reason}"[:500],
                                 type=record.status).text = \
                    f"{record.reason}\nre-run: {rerun.get(record.spec.run_id, '')}"
                counts["tests"] += 1
                counts["errors"] += 1
            for verdict in summary.verdicts if summary is not None else ():
                case = _case(suite, record, f"{verdict.requirement} [{label}]", 0.0)
                counts["tests"] += 1
                if verdict.status == "fail":
                    counts["failures"] += 1
                    etree.SubElement(case, "failure", message=verdict.reason[:500],
                                     type="requirement").text = \
                        f"{verdict.reason}\nre-run: {rerun.get(record.spec.run_id, '')}"
                elif verdict.status == "inconclusive":
                    counts["skipped"] += 1
                    etree.SubElement(case, "skipped", message=f"inconclusive: {verdict.reason}")
            if not broken and summary is not None and not summary.verdicts:
                # No requirements were checked: the run itself is the test case.
                _case(suite, record, f"run [{label}]", record.wall_time)
                counts["tests"] += 1
        for key, value in counts.items():
            suite.set(key, str(value))
            totals[key] += value
    for key, value in totals.items():
        root.set(key, str(value))
    data: bytes = etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)
    return data
