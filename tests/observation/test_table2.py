"""The generated automata agree with a plain-Python implementation of thesis Table 2 on
random distance traces, including jumps across a state and chattering at the thresholds;
and the teleop wall example gives exactly the four transitions at the predicted times."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rei.lang.vepl import load_vepl
from rei.runtime.observation.automata.records import load_generated
from rei.runtime.observation.model.geometry import FootprintSet
from tests.observation.helpers import default_automata, geom, monitor
from tests.observation.streams import ROBOT, drive, header, human, sample, straight, wall

_PARAMETERS = load_vepl().parameters
EPS_CLOSE, EPS_COLLISION = _PARAMETERS["eps_close"], _PARAMETERS["eps_collision"]
FAR_AWAY = 1e3
FAR, CLOSE, COLLISION = "FAR", "CLOSE", "COLLISION"
SIGNAL = {(FAR, CLOSE): "SIG_GEOM_FAR_TRANSIT_CLOSE", (CLOSE, FAR): "SIG_GEOM_CLOSE_TRANSIT_FAR",
          (CLOSE, COLLISION): "SIG_GEOM_CLOSE_TRANSIT_COLLISION",
          (COLLISION, CLOSE): "SIG_GEOM_COLLISION_TRANSIT_CLOSE"}


def state_of(distances: list[float]) -> str:
    """Table 2's guards: COLLISION if some d < ε_collision, CLOSE if some d < ε_close."""
    if any(d < EPS_COLLISION for d in distances):
        return COLLISION
    if any(d < EPS_CLOSE for d in distances):
        return CLOSE
    return FAR


def path(a: str, b: str) -> list[tuple[str, str]]:
    """The transitions from state a to b, through CLOSE when they jump across it."""
    if a == b:
        return []
    if CLOSE in (a, b):
        return [(a, b)]
    return [(a, CLOSE), (CLOSE, b)]


def table2(times: list[float], traces: list[list[float]]) -> list[tuple[float, str]]:
    """Reference: distances change linearly between samples; the state is taken between
    consecutive threshold crossings and at every sample."""
    out: list[tuple[float, str]] = []
    state = FAR
    before = [FAR_AWAY] * len(traces[0])
    for t, now in zip(times, traces, strict=False):
        fractions = set()
        for d0, d1 in zip(before, now, strict=False):
            for thr in (EPS_CLOSE, EPS_COLLISION):
                m0, m1 = d0 - thr, d1 - thr
                if (m0 < 0 or (m0 == 0 and math.copysign(1, m0) < 0)) != (m1 < 0):
                    f = m0 / (m0 - m1)
                    if 0 <= f <= 1:
                        fractions.add(f)
        ordered = sorted(fractions)
        points = [(lo + hi) / 2 for lo, hi in zip(ordered, ordered[1:], strict=False)]
        steps = [[d0 + f * (d1 - d0) for d0, d1 in zip(before, now, strict=True)]
                 for f in points]
        for ds in [*steps, now]:
            new = state_of(ds)
            out.extend((t, SIGNAL[p]) for p in path(state, new))
            state = new
        before = now
    return out


@pytest.fixture(scope="module")
def automata(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return default_automata(tmp_path_factory.mktemp("automata"))


NEAR = st.sampled_from([EPS_COLLISION, EPS_CLOSE, EPS_COLLISION - 1e-9, EPS_CLOSE + 1e-9,
                        0.0, -0.05, (EPS_CLOSE + EPS_COLLISION) / 2, 2.0])
DIST = st.one_of(NEAR, st.floats(-0.1, 1.0, allow_nan=False))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                  HealthCheck.function_scoped_fixture])
@given(trace=st.lists(st.lists(DIST, min_size=3, max_size=3), min_size=1, max_size=25))
def test_automata_agree_with_table_2(trace: list[list[float]], automata: Path,
                                     tmp_path: Path) -> None:
    # Three objects around a robot at the origin, each moved so its footprint is at the
    # drawn distance from the robot's: one ahead, one behind, one to the side.
    placed = [human("ahead", 0, 0), human("behind", 0, 0), human("side", 0, 0)]
    h = header([o for o, _ in placed])
    hx, hy = 0.281 / 2, 0.306 / 2
    samples = []
    for i, (a, b, c) in enumerate(trace):
        poses = np.array([[hx + 0.25 + a, 0, 0], [-hx - 0.25 - b, 0, 0], [0, hy + 0.25 + c, 0]])
        samples.append(sample(i, i * 0.1, (0.0, 0.0, 0.0), poses))
    fs = FootprintSet.build(ROBOT.footprint, [o.footprint for o in h.objects], 1.0)
    # the same broad phase as the automata (exact within their largest distance threshold)
    cutoff = load_generated(automata).DISTANCE_CUTOFF
    measured = [fs.distances(s.robot_pose, s.poses, cutoff).tolist() for s in samples]
    rows, _ = monitor(h, samples, tmp_path / f"run{len(list(tmp_path.iterdir()))}",
                      automata=automata)
    expected = table2([s.time for s in samples], measured)
    assert geom(rows) == expected
    # entries and exits alternate: never two FAR->CLOSE without a CLOSE->FAR between
    depth = 0
    for _, signal in geom(rows):
        depth += {"SIG_GEOM_FAR_TRANSIT_CLOSE": 1, "SIG_GEOM_CLOSE_TRANSIT_FAR": -1}.get(signal, 0)
        assert depth in (0, 1)


def test_teleop_wall_gives_the_four_transitions_at_the_predicted_times(tmp_path: Path,
                                                                       automata: Path) -> None:
    # The robot drives at 0.5 m/s straight at a wall tile (face at x = 1.5) and back.
    rate, speed = 10.0, 0.5
    forward = [(speed * i / rate, 0.0, 0.0) for i in range(30)]          # to x = 1.45
    back = [(1.45 - speed * i / rate, 0.0, 0.0) for i in range(1, 30)]
    h, samples = drive([wall("wall_1", 2.0, 0.0), wall("wall_2", 2.0, 3.0)], forward + back)
    rows, result = monitor(h, samples, tmp_path, automata=automata)
    front = 0.281 / 2

    def first(pred: object) -> float:
        return next(s.time for s in samples if pred(1.5 - front - s.robot_pose[0]))  # type: ignore[operator]

    t_close = first(lambda d: d < EPS_CLOSE)
    t_collision = first(lambda d: d < EPS_COLLISION)
    after = [s for s in samples if s.time > t_collision]
    t_uncollide = next(s.time for s in after if 1.5 - front - s.robot_pose[0] >= EPS_COLLISION)
    t_far = next(s.time for s in after if 1.5 - front - s.robot_pose[0] >= EPS_CLOSE)
    assert geom(rows) == [(t_close, "SIG_GEOM_FAR_TRANSIT_CLOSE"),
                          (t_collision, "SIG_GEOM_CLOSE_TRANSIT_COLLISION"),
                          (t_uncollide, "SIG_GEOM_COLLISION_TRANSIT_CLOSE"),
                          (t_far, "SIG_GEOM_CLOSE_TRANSIT_FAR")]
    assert all(r.objects == ("wall_1",) for r in rows)
    assert result.total_utility == -2 - 10 + 1 + 1


def test_a_jump_across_close_emits_both_transitions(tmp_path: Path, automata: Path) -> None:
    h, samples = drive([wall("w", 2.0, 0.0)], [(0.0, 0, 0), (1.4, 0, 0), (0.0, 0, 0)])
    rows, _ = monitor(h, samples, tmp_path, automata=automata)
    assert geom(rows) == [(0.1, "SIG_GEOM_FAR_TRANSIT_CLOSE"),
                          (0.1, "SIG_GEOM_CLOSE_TRANSIT_COLLISION"),
                          (0.2, "SIG_GEOM_COLLISION_TRANSIT_CLOSE"),
                          (0.2, "SIG_GEOM_CLOSE_TRANSIT_FAR")]


def test_starting_close_enters_close_first(tmp_path: Path, automata: Path) -> None:
    h, samples = drive([wall("w", 2.0, 0.0)], straight(1.2, 0.0, 5))
    rows, _ = monitor(h, samples, tmp_path, automata=automata)
    assert [s for _, s in geom(rows)] == ["SIG_GEOM_FAR_TRANSIT_CLOSE",
                                          "SIG_GEOM_CLOSE_TRANSIT_FAR"]
