"""Reports on a campaign folder: the thesis's tables, plots, a self-contained HTML page and
JUnit XML for CI.

``build_report(DIR)`` reads the results store written by ``rei.runtime.campaigns`` and writes
results.csv / results.parquet, junit.xml and report.html. Nothing here runs a mission.
"""

from rei.runtime.presentation.campaign_report.build import (
    ReportOutcome,
    build_report,
    rerun_command,
)
from rei.runtime.presentation.campaign_report.tables import Table, execution_summary, signal_counts
from rei.runtime.presentation.junit import junit_xml

__all__ = ["ReportOutcome", "Table", "build_report", "execution_summary", "junit_xml",
           "rerun_command", "signal_counts"]
