"""`rei search` end to end with real runs (`rei run` in pybullet, the campaign engines).

The navigator under test is bench/defects' ``exceeds-drive-limit``: it believes its drive is
2.5 times faster than it is, so it obeys a mission's speed limit only while that limit is
below the drive's own (0.26 m/s) and fails SPEED_LIMIT above it (+0.01 m/s tolerance). The
search space is one small room whose mission limit ranges over 0.05..0.3 m/s: 12 % of it
fails, and SPEED_LIMIT's margin (0.01 / (limit + 0.01) while passing) falls towards it. With
4 simulations, TPE finds the failure on every seed tried and random sampling misses it on
most (at least half: the issue's criterion); the correct navigator never fails (0 false
alarms, exit 0). The same search gives the same bytes with 2 local workers, with 1 (the
interrupted one) and on a real Dask cluster, and a search interrupted with Ctrl-C (exit 130)
and run again ends exactly as the uninterrupted one.
"""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rei.lang.cli_support import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK
from rei.runtime.campaigns import CampaignStore

REPO = Path(__file__).resolve().parents[2]
DEFECT = "bench.defects.control:ExceedsDriveLimit"
SEEDS = (0, 1, 2)
SAFETY_LIMIT = 900.0
"""Seconds after which a stuck test fails instead of hanging CI (not a performance limit)."""
SPACE = ["--shape", "rect", "--size", "5x3", "--objects", "0", "--mix", "furniture",
         "--humans", "0", "--goals", "2", "--spacing", "2", "--cycles", "1",
         "--behaviour", "yielding", "--heading", "no", "--layout", "1",
         "--max-speed", "0.05:0.3", "--requirement", "SPEED_LIMIT", "--budget", "4",
         "--batch", "2", "--no-report"]


def _env() -> dict[str, str]:
    # The defects are `bench.defects.MODULE:Class`: importable from the repository root.
    path = os.pathsep.join(p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p)
    return {**os.environ, "PYTHONPATH": path}


def search_argv(out: Path, seed: int, *extra: str, strategy: str = "tpe",
                controller: str = DEFECT) -> list[str]:
    return [sys.executable, "-m", "rei.runtime.commands", "search", "-o", str(out), *SPACE,
            "--seed", str(seed), "--strategy", strategy, "--controller", controller, *extra]


def search(out: Path, seed: int, *extra: str, strategy: str = "tpe",
           controller: str = DEFECT) -> subprocess.CompletedProcess[str]:
    return subprocess.run(search_argv(out, seed, *extra, strategy=strategy,
                                      controller=controller),
                          capture_output=True, text=True, timeout=SAFETY_LIMIT, env=_env(),
                          cwd=REPO)


def table(out: Path) -> list[dict[str, str]]:
    with open(out / "search.csv", newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def found(out: Path) -> bool:
    return any(row["verdict"] == "fail" for row in table(out))


def outputs(out: Path) -> dict[str, bytes]:
    """What must not depend on workers, engine or interruptions: the candidates' files, the
    search table and every run's summary."""
    files = sorted([*out.glob("candidates/*"), out / "search.csv",
                    *out.glob("runs/*/summary.json")])
    return {str(p.relative_to(out)): p.read_bytes() for p in files}


def _search_into(out: Path, strategy: str, seed: int) -> Path:
    result = search(out, seed, "--workers", "2", strategy=strategy)
    assert result.returncode in (EXIT_OK, EXIT_FAILED), result.stderr
    assert (result.returncode == EXIT_FAILED) == found(out), result.stderr
    return out


@pytest.fixture(scope="module")
def tpe_seed_0(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The uninterrupted TPE search of seed 0 on 2 local workers (4 runs)."""
    return _search_into(tmp_path_factory.mktemp("tpe-0") / "out", "tpe", 0)


@pytest.fixture(scope="module")
def searches(tmp_path_factory: pytest.TempPathFactory, tpe_seed_0: Path
             ) -> dict[tuple[str, int], Path]:
    """TPE and random on every seed, 2 local workers: 24 runs in all."""
    root = tmp_path_factory.mktemp("searches")
    return {(strategy, seed): tpe_seed_0 if (strategy, seed) == ("tpe", 0)
            else _search_into(root / f"{strategy}-{seed}", strategy, seed)
            for strategy in ("tpe", "random") for seed in SEEDS}


@pytest.mark.slow
def test_tpe_finds_the_defect_that_random_sampling_misses_on_the_same_budget(
        searches: dict[tuple[str, int], Path]) -> None:
    tpe = [found(searches[("tpe", s)]) for s in SEEDS]
    rnd = [found(searches[("random", s)]) for s in SEEDS]
    assert all(tpe), tpe
    assert sum(not f for f in rnd) * 2 >= len(SEEDS), rnd  # random misses at least half
    for seed in SEEDS:
        rows = table(searches[("tpe", seed)])
        assert len(rows) == 4 and all(r["run_id"] for r in rows)  # 4 simulations, no more
        failing = [r for r in rows if r["verdict"] == "fail"]
        # The failure is the defect's: SPEED_LIMIT, at a limit above the drive's own.
        assert all("SPEED_LIMIT" in r["failed_requirements"] for r in failing)
        assert all(float(r["max_speed"]) > 0.27 and float(r["objective"]) < 0 for r in failing)
        passing = [r for r in rows if r["verdict"] == "pass"]
        assert all(float(r["objective"]) >= 0 for r in passing)


@pytest.mark.slow
def test_every_candidate_is_a_checked_pair_and_the_folder_is_a_campaign(
        tpe_seed_0: Path) -> None:
    out = tpe_seed_0
    missions = sorted((out / "candidates").glob("*.mission"))
    assert len(missions) == 4
    check = subprocess.run([sys.executable, "-m", "rei.lang.cli", "check", *map(str, missions)],
                           capture_output=True, text=True, timeout=SAFETY_LIMIT)
    assert check.returncode == 0, check.stdout + check.stderr
    plan, _, records = CampaignStore.read(out)
    assert len(plan.runs) == len(records) == 4
    # `rei report` reads the search folder as a campaign and judges it by the same rule.
    report = subprocess.run([sys.executable, "-m", "rei.runtime.commands", "report", str(out),
                             "--no-html"], capture_output=True, text=True,
                            timeout=SAFETY_LIMIT)
    assert report.returncode == EXIT_FAILED, report.stderr
    results = (out / "results.csv").read_text()
    assert "margin:SPEED_LIMIT" in results and "param:max_speed" in results


@pytest.mark.slow
def test_the_correct_navigator_yields_no_failure_and_exits_0(tmp_path: Path) -> None:
    result = search(tmp_path / "reference", 0, "--workers", "2", "--budget", "2",
                    controller="reference")
    assert result.returncode == EXIT_OK, result.stderr
    rows = table(tmp_path / "reference")
    assert [r["verdict"] for r in rows] == ["pass", "pass"]


@pytest.fixture(scope="module")
def dask_scheduler() -> Iterator[str]:
    pytest.importorskip("distributed", reason="pip install 'dask[distributed]'")
    from rei.runtime.campaigns.dask_cluster import loopback_cluster  # noqa: PLC0415

    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("PYTHONPATH", _env()["PYTHONPATH"])  # the workers import the defect
        with loopback_cluster(workers=1, threads=1, nanny=False) as address:
            yield address


@pytest.mark.slow
def test_same_seed_same_bytes_with_two_workers_and_dask(
        tmp_path: Path, tpe_seed_0: Path, dask_scheduler: str) -> None:
    reference = outputs(tpe_seed_0)  # 2 local workers
    dask = tmp_path / "dask"
    result = search(dask, 0, "--engine", "dask", "--scheduler", dask_scheduler)
    assert result.returncode == EXIT_FAILED, result.stderr
    assert outputs(dask) == reference
    assert len([k for k in reference if k.endswith("summary.json")]) == 4


def _recorded(out: Path) -> int:
    return sum(1 for _ in out.glob("runs/*/record.json"))


@pytest.mark.slow
def test_interrupted_and_resumed_search_ends_as_an_uninterrupted_one(
        tmp_path: Path, tpe_seed_0: Path) -> None:
    """Ctrl-C during the second batch (one worker: its second run is in flight), so the
    resumed session replays a finished batch and finishes a partial one."""
    out = tmp_path / "resumed"
    argv = search_argv(out, 0, "--workers", "1")
    process = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                               text=True, env=_env(), cwd=REPO)
    deadline = time.monotonic() + SAFETY_LIMIT
    while _recorded(out) < 3 and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    process.send_signal(signal.SIGINT)  # Ctrl-C
    _, err = process.communicate(timeout=SAFETY_LIMIT)
    assert process.returncode == EXIT_INTERRUPTED, err
    assert "run the same command again" in err.lower()
    assert _recorded(out) == 3
    resumed = subprocess.run(argv, capture_output=True, text=True, timeout=SAFETY_LIMIT,
                             env=_env(), cwd=REPO)
    assert resumed.returncode == EXIT_FAILED, resumed.stderr
    assert "3 simulation(s) already recorded" in resumed.stderr
    assert outputs(out) == outputs(tpe_seed_0)
