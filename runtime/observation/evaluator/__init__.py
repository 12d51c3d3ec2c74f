"""The evaluator (thesis 5.2, 6.1.5): utility per signal, the event log (events.csv),
requirement verdicts and the run's measurements, merged into the RunSummary.

It consumes occurrences from the event automata; it must never import the simulator."""

from rei.runtime.observation.evaluator.signal_log import SignalLog
from rei.runtime.observation.evaluator.summary import MonitorResult, merge_summary, write_summary
from rei.runtime.observation.evaluator.verdicts import RequirementChecker

__all__ = ["MonitorResult", "RequirementChecker", "SignalLog", "merge_summary", "write_summary"]
