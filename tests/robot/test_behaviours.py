"""The behaviour vocabulary and a run's behaviour log (rei.runtime.robot.behaviours)."""

from __future__ import annotations

from rei.runtime.robot.behaviours import (
    BEHAVIOURS,
    OBSERVED,
    EpisodeLog,
    doing_message,
    observed,
    reported,
)


def test_a_doing_message_reads_back_as_the_behaviours_it_names() -> None:
    names = ("recovery.backup", "slow_for_person")
    assert reported(doing_message(names)) == names
    assert doing_message(()) == ""
    assert reported("") == ()


def test_other_messages_report_nothing_and_unknown_names_are_kept() -> None:
    assert reported("no path to the goal on the static map") == ()
    assert reported("doing: docking,  , slow_for_person") == ("docking", "slow_for_person")


def test_commands_show_rotating_in_place_and_backing_up() -> None:
    assert observed(0.0, 0.5) == ("rotate_in_place",)
    assert observed(0.005, -0.2) == ("rotate_in_place",)
    assert observed(-0.1, 0.0) == ("back_up",)
    assert observed(0.2, 0.5) == ()
    assert observed(0.0, 0.05) == ()
    assert set(OBSERVED) <= set(BEHAVIOURS)


def test_the_log_counts_episodes_seconds_and_the_first_time() -> None:
    log = EpisodeLog()
    ticks = [(0.0, ()), (0.1, ("rotate_in_place",)), (0.2, ("rotate_in_place",)),
             (0.3, ("rotate_in_place", "goal_heading")), (0.4, ()),
             (0.5, ("rotate_in_place",)), (0.6, ())]
    for time, names in ticks:
        log.tick(time, names)
    assert log.to_json() == {
        "goal_heading": {"episodes": 1, "seconds": 0.1, "first": 0.3},
        "rotate_in_place": {"episodes": 2, "seconds": 0.4, "first": 0.1},
    }
    assert EpisodeLog().to_json() == {}
