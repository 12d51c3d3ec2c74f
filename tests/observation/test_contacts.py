"""A physical contact is always a collision to the monitor, and the new sample fields are
checked like the old ones: a NaN command is non-finite, a contact index out of range is
malformed (the sample is counted, never modelled)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from rei.runtime.observation.model.runtime_model import RuntimeModel
from rei.runtime.observation.model.sample_checks import check_sample
from tests.observation.helpers import default_automata, geom, monitor
from tests.observation.streams import drive, human, straight, wall


@pytest.fixture(scope="module")
def automata(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return default_automata(tmp_path_factory.mktemp("automata"))


def test_a_contacted_object_is_at_distance_zero_at_most() -> None:
    # The robot's front face stops 0.0595 m short of the wall (beyond ε_collision), the
    # human is 1 m away; pybullet says the wall was touched between the samples.
    h, samples = drive([wall("w", 0.7, 0.0), human("p", 0.0, 2.0)], [(0.0, 0.0, 0.0)] * 2)
    touched = replace(samples[1], contacts=(0,))
    model = RuntimeModel(h)
    free = model.observe(samples[0]).distance
    assert free[0] == pytest.approx(0.7 - 0.5 - 0.1405)
    inputs = model.observe(touched).distance
    assert inputs[0] == 0.0 and inputs[1] == pytest.approx(free[1])
    # A deeper overlap than zero stays as deep as the footprints say.
    h, samples = drive([wall("w", 0.5, 0.0)], [(0.0, 0.0, 0.0)])
    assert RuntimeModel(h).observe(replace(samples[0], contacts=(0,))).distance[0] == \
        pytest.approx(-0.1405)


def test_a_contacted_human_counts_in_the_closest_approach() -> None:
    h, samples = drive([human("p", 1.0, 0.0)], [(0.0, 0.0, 0.0)])
    model = RuntimeModel(h)
    model.observe(replace(samples[0], contacts=(0,)))
    assert model.min_distance_to_human == 0.0


def test_a_contact_between_samples_is_a_collision_signal(tmp_path: Path, automata: Path) -> None:
    # The robot drives towards a wall and back, never closer than 0.06 m by its footprint.
    poses = straight(0.0, 0.3, 10) + straight(0.3, 0.0, 10)
    h, samples = drive([wall("w", 1.0, 0.0)], poses)
    rows, _ = monitor(h, samples, tmp_path / "sampled", automata=automata)
    assert not any("COLLISION" in signal for _, signal in geom(rows))
    samples[10] = replace(samples[10], contacts=(0,))
    rows, _ = monitor(h, samples, tmp_path / "touched", automata=automata)
    assert (pytest.approx(1.0), "SIG_GEOM_CLOSE_TRANSIT_COLLISION") in geom(rows)


@pytest.mark.parametrize(("change", "problem"), [
    ({"contacts": (1,)}, "malformed"),
    ({"contacts": (-1,)}, "malformed"),
    ({"contacts": (0, 0)}, None),  # a repeated index is still the same contact
    ({"belief_cmd": (float("nan"), 0.0)}, "non_finite"),
    ({"belief_cmd": (0.0, float("inf"))}, "non_finite"),
    ({"belief_cmd": (5.0, -9.0)}, None),  # beyond the drive limits is what the robot asked for
])
def test_check_sample_judges_contacts_and_the_command(change: dict[str, object],
                                                      problem: str | None) -> None:
    h, [s] = drive([wall("w", 2.0, 0.0)], [(0.0, 0.0, 0.0)])
    if "contacts" in change:
        s = replace(s, contacts=change["contacts"])
    else:
        s = replace(s, belief=replace(s.belief, cmd=change["belief_cmd"]))
    assert check_sample(s, h) == problem
