"""The monitor's fast paths give what the plain computation gives: queries kept from the
previous step only while their inputs are the same, margins crossed in Python floats as
numpy crosses them, the robot's floor kept only well inside its tile."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rei.catalogue import Box
from rei.lang.vepl import model as vm
from rei.runtime.messages import SCHEMA_VERSION, MissionEvent, ObservedObject, StreamHeader
from rei.runtime.observation.automata.records import Matches, RequirementSpec, load_generated
from rei.runtime.observation.evaluator.verdicts import RequirementChecker
from rei.runtime.observation.model.interpolation import crossings
from rei.runtime.observation.model.runtime_model import RuntimeModel
from rei.runtime.observation.model.sample_checks import SampleProblems
from tests.observation.helpers import default_automata

ROBOT = ObservedObject("robot", "static", "turtlebot3_waffle", Box(0.281, 0.306), 0.2)


def _header(floors: tuple[tuple[str, float, float], ...] = ()) -> StreamHeader:
    return StreamHeader(SCHEMA_VERSION, "t", "t", 0, 10.0, ROBOT,
                        (ObservedObject("h", "human", "human", Box(0.5, 0.5), 1.0),),
                        1.0, floors, (0.0, 0.0))


def test_steady_queries_follow_mission_events_and_facts(tmp_path: Path) -> None:
    module = load_generated(default_automata(tmp_path))
    model = RuntimeModel(_header())
    w = model.baseline()
    q0 = module.evaluate_queries(w, {})
    assert isinstance(q0, Matches) and q0.inputs is w
    assert bool(q0["humansPresent"]) and not q0["missionRunning"]
    # nothing steady changed: the very same matches are kept
    q1 = module.evaluate_queries(replace(w, laser_min=0.1), q0)
    assert q1["taskActive"] is q0["taskActive"] and q1["goalMissed"] is q0["goalMissed"]
    # a mission event changes the task arrays and the mission state: evaluated again
    w2 = model.apply(MissionEvent("begin", 0.0), w)
    w2 = model.apply(MissionEvent("task_start", 0.0, "g", 0), w2)
    q2 = module.evaluate_queries(w2, q1)
    assert bool(q2["missionRunning"]) and q2["taskActive"].tolist() == [True]
    w3 = model.apply(MissionEvent("task_fail", 1.0, "g", 0, cause="timeout"), w2)
    q3 = module.evaluate_queries(w3, q2)
    assert q3["taskFailed"].tolist() == [True] and q3["taskActive"].tolist() == [False]
    assert q2["taskActive"].tolist() == [True]  # the earlier inputs were not changed under it
    # other facts (inputs from elsewhere): evaluated again, not kept
    q4 = module.evaluate_queries(replace(w3, humans=0.0), q3)
    assert not q4["humansPresent"]


margin = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64),
                   st.sampled_from([0.0, -0.0, 1e-300, -1e-300, 1e308, -1e308]))


@settings(max_examples=300, deadline=None)
@given(pairs=st.lists(st.tuples(margin, margin), min_size=1, max_size=6))
def test_scalar_crossings_match_the_vectorised_ones(pairs: list[tuple[float, float]]) -> None:
    before = [np.asarray(a) for a, _ in pairs]
    after = [np.asarray(b) for _, b in pairs]
    # the same numbers as one-element arrays take the numpy path
    as_arrays = crossings([m.reshape(1) for m in before], [m.reshape(1) for m in after])
    assert crossings(before, after) == as_arrays


def test_robot_floor_is_kept_only_well_inside_its_tile() -> None:
    floors = tuple((f"f{i}", float(i), 0.0) for i in range(3))
    model = RuntimeModel(_header(floors))
    assert model._robot_floor(1.2, 0.1).tolist() == [False, True, False]
    assert model._robot_floor(1.45, 0.0).tolist() == [False, True, False]
    # on the shared edge the first floor in header order wins, as without the shortcut
    assert model._robot_floor(1.5, 0.0).tolist() == [False, True, False]
    assert model._robot_floor(0.5, 0.0).tolist() == [True, False, False]
    assert model._robot_floor(2.2, 0.0).tolist() == [False, False, True]
    assert model._robot_floor(9.0, 0.0).tolist() == [False, False, False]
    assert model._robot_floor(2.0, 0.0).tolist() == [False, False, True]
    mask = model._robot_floor(2.1, 0.0)
    assert not mask.flags.writeable  # shared between samples: nobody may change it
    assert np.flatnonzero(mask).tolist() == [2]


def test_a_trigger_waiting_for_events_needs_no_steps() -> None:
    """Steps answer only query targets: a checker told of every step and one told of none
    give the same verdicts for triggers waiting on events (expiry at the window's end)."""
    reqs = (RequirementSpec("R", "r", (vm.Whenever("T", ("A",), 1.0),)),
            RequirementSpec("S", "s", (vm.Whenever("T", ("A",), None),)),
            RequirementSpec("Q", "q", (vm.Whenever("T", ("held",), 1.0),)))
    stepped = RequirementChecker(reqs, {"held"})
    quiet = RequirementChecker(reqs, {"held"})
    for checker in (stepped, quiet):
        checker.on_event("T", 1.0)
    assert quiet.waiting()  # Q waits for its query
    for t in (1.5, 2.5, 3.0):
        stepped.on_step(t, {"held": False})
    for checker in (stepped, quiet):
        checker.on_event("A", 3.0)
        checker.on_event("T", 4.0)
        checker.on_step(4.2, {"held": True})
    assert not quiet.waiting()
    ends = [c.verdicts(6.0, SampleProblems(), True) for c in (stepped, quiet)]
    assert ends[0] == ends[1]
    assert [v.status for v in ends[0]] == ["fail", "fail", "fail"]
