"""What a user imports is a promise (httpx's tests/test_exported_members.py): each public
package's ``__all__`` is listed here, every name in it resolves, none is private, and each
is defined inside REI (not a re-export of a third party's name). Changing a list here is
changing REI's public API: say so in the change."""

from __future__ import annotations

import importlib
import inspect

import pytest

PUBLIC = {
    # the languages: check and load files
    "rei.lang": ["Diagnostic", "Workspace", "__version__", "load_mission", "load_room"],
    # running a mission from Python
    "rei.runtime.runs": ["run_into"],
    # the controller contract, its checker, and making a controller by name
    "rei.runtime.robot": [
        "BUILT_IN", "Controller", "ControllerContext", "GoalFeedback", "GoalTracker",
        "HostedController", "MapObstacle", "NavGoal", "Observation", "VelocityCommand",
        "check_controller", "load_controller", "make_controller"],
    # the bus client
    "rei.runtime.bus": [
        "ACTIONS", "AccessRules", "BusError", "BusSession", "CONFIG_NAMES", "DEFAULT_ACCESS",
        "MAX_PAYLOAD", "Message", "PREFIX", "ROLES", "RoleAccess", "Subscription",
        "WIRE_VERSION", "connect"],
    # campaigns, search and shrink
    "rei.runtime.campaigns": [
        "CampaignEngine", "CampaignError", "CampaignPlan", "CampaignResult", "CampaignStore",
        "DaskEngine", "LocalEngine", "MissionVerdict", "PairedMission", "RunRecord",
        "RunResult", "RunSpec", "SuccessRate", "campaign_passed", "check_engine",
        "classify_pairs", "derive_seed", "execute_run", "mission_verdicts", "plan_campaign",
        "record_row", "run_campaign", "static_twin", "success_rates", "wilson_interval",
        "write_static_twins", "write_tables"],
    "rei.runtime.campaigns.search": [
        "STRATEGIES", "SearchConfig", "SearchError", "SearchResult", "SearchStrategy", "Told",
        "check_strategy", "make_strategy", "objective", "run_search"],
    "rei.runtime.campaigns.shrink": [
        "RunSettings", "ScenarioCase", "ShrinkReport", "load_case", "shrink_into",
        "size_reduction", "sizes"],
    # the trace reader (and writer) and recordings
    "rei.runtime.trace": [
        "TraceDecoder", "TraceEncoder", "TraceError", "TraceWriter", "open_regular",
        "read_trace", "read_trace_end", "write"],
    "rei.runtime.observation.recordings": [
        "McapRecorder", "RECORDING", "RecordedSamples", "RecordingError", "TRACE_TOPIC",
        "is_recording", "read_recording", "read_stream"],
    # drawing a run's page
    "rei.runtime.presentation.run_page": ["write_run_page"],
    # building a campaign's report
    "rei.runtime.presentation.campaign_report": [
        "ReportOutcome", "Table", "build_report", "execution_summary", "junit_xml",
        "rerun_command", "signal_counts"],
}


@pytest.mark.parametrize("package", sorted(PUBLIC))
def test_public_names_are_the_promised_ones(package: str) -> None:
    module = importlib.import_module(package)
    assert sorted(module.__all__) == sorted(PUBLIC[package])
    for name in module.__all__:
        value = getattr(module, name)  # resolves (lazily exported names too)
        assert not name.startswith("_") or name == "__version__", name
        if inspect.isclass(value) or inspect.isfunction(value):
            assert value.__module__.startswith("rei."), (name, value.__module__)
