"""Planning: derived seeds, run ids, inputs from files, folders and suite indexes."""

from __future__ import annotations

from pathlib import Path

import pytest

from rei.runtime.campaigns import CampaignError, derive_seed, plan_campaign
from rei.runtime.campaigns.plan import CampaignPlan

from .records import EXAMPLES


def test_seeds_are_derived_per_mission_and_repeat_and_reproducible() -> None:
    first = plan_campaign([EXAMPLES], repeat=3, seed=11)
    again = plan_campaign([EXAMPLES], repeat=3, seed=11)
    assert first == again
    seeds = [r.seed for r in first.runs]
    assert len(set(seeds)) == len(seeds)
    assert [r.seed for r in plan_campaign([EXAMPLES], repeat=3, seed=12).runs] != seeds
    assert derive_seed(11, "navigation/navigation.mission", 2) == next(
        r.seed for r in first.runs if r.run_id == "navigation.r02")


def test_a_seed_does_not_depend_on_the_other_missions() -> None:
    alone = plan_campaign([EXAMPLES / "navigation"], repeat=2, seed=5)
    together = plan_campaign([EXAMPLES], repeat=2, seed=5)
    assert [r.seed for r in alone.runs] == [r.seed for r in together.runs
                                            if r.run_id.startswith("navigation")]


def test_files_folders_and_duplicates() -> None:
    plan = plan_campaign([EXAMPLES, EXAMPLES / "simple_wall" / "simple_wall.mission"], repeat=2)
    ids = [r.run_id for r in plan.runs]
    assert len(ids) == len(set(ids)) == 2 * len(list(EXAMPLES.rglob("*.mission")))
    assert ids[:2] == ["high_error.r00", "high_error.r01"]  # examples/faults/high_error
    assert all(Path(r.mission_file).is_absolute() for r in plan.runs)


def test_plan_json_roundtrip() -> None:
    plan = plan_campaign([EXAMPLES], repeat=2, seed=3, controller="navigator", duration=2.5)
    assert CampaignPlan.from_json(plan.to_json()) == plan


def test_run_arguments_pass_the_options_through(tmp_path: Path) -> None:
    vepl = tmp_path / "watch.vepl"
    vepl.write_text("// empty\n")
    spec = plan_campaign([EXAMPLES / "navigation"], seed=1, controller="scripted",
                         vepl=vepl, duration=2.0).runs[0]
    argv = spec.run_argv("OUT")
    assert argv[:4] == ["run", spec.mission_file, "-o", "OUT"]
    assert argv[4:] == ["--seed", str(spec.seed), "--controller", "scripted",
                        "--vepl", str(vepl.resolve()), "--duration", "2"]


def test_suite_index_carries_parameters_and_descriptors(tmp_path: Path) -> None:
    suite = tmp_path / "suite"
    (suite / "a").mkdir(parents=True)
    for name in ("one", "two"):
        (suite / "a" / f"{name}.mission").write_text(
            (EXAMPLES / "simple_wall" / "simple_wall.mission").read_text())
    (suite / "index.csv").write_text(
        "room,mission,preset,objects,density\n"
        "a/one.room,a/one.mission,small,3,0.25\n"
        "a/two.room,a/two.mission,small,5,0.5\n")
    plan = plan_campaign([suite / "index.csv"], repeat=1)
    assert [r.run_id for r in plan.runs] == ["one.r00", "two.r00"]
    assert plan.runs[1].parameters == {"preset": "small", "objects": 5, "density": 0.5}
    assert plan.runs[0].group == "small"


@pytest.mark.parametrize(("content", "expected"), [
    ("room,name\nx.room,y\n", "'mission' column"),
    ("room,mission\nx.room,missing.mission\n", "does not exist"),
    ("room,mission\nx.room,\n", "is empty"),
])
def test_bad_index_is_refused_with_the_line(tmp_path: Path, content: str, expected: str) -> None:
    index = tmp_path / "index.csv"
    index.write_text(content)
    with pytest.raises(CampaignError, match=expected) as info:
        plan_campaign([index])
    assert str(index) in str(info.value)


def test_bad_inputs_are_named(tmp_path: Path) -> None:
    with pytest.raises(CampaignError, match="nowhere.mission: mission file does not exist"):
        plan_campaign([tmp_path / "nowhere.mission"])
    with pytest.raises(CampaignError, match="found none"):
        plan_campaign([tmp_path])
    with pytest.raises(CampaignError, match="--repeat"):
        plan_campaign([EXAMPLES], repeat=0)
    with pytest.raises(CampaignError, match="--duration"):
        plan_campaign([EXAMPLES], duration=float("nan"))
    with pytest.raises(CampaignError, match="--vepl"):
        plan_campaign([EXAMPLES], vepl=tmp_path / "x.vepl")


def test_no_variation_reaches_the_run_and_is_part_of_the_plan() -> None:
    plain = plan_campaign([EXAMPLES / "simple_wall"])
    exact = plan_campaign([EXAMPLES / "simple_wall"], variation=False)
    assert "--no-variation" in exact.runs[0].run_argv("out")
    assert "--no-variation" not in plain.runs[0].run_argv("out")
    assert "variation" not in plain.runs[0].to_json()  # plans as earlier versions wrote them
    assert CampaignPlan.from_json(exact.to_json()) == exact != plain
