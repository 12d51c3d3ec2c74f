"""The vectorised laser against pybullet's own ray test, on the generated examples."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rei.generators.concrete.build import load_concrete_mission
from rei.runtime.artifacts.world import load_manifest
from rei.runtime.raycast import merge_wall_tiles, scene_shapes
from rei.runtime.simulation.assembly import generate_world
from rei.runtime.simulation.sensors.laser import Laser2D
from rei.runtime.simulation.world.bullet import BulletWorld
from tests.conftest import EXAMPLES


@pytest.mark.parametrize("example", ["navigation", "small_dense", "medium_sparse"])
def test_numpy_laser_matches_pybullet_rays(example: str, tmp_path: Path) -> None:
    generate_world(EXAMPLES / example / f"{example}.mission", tmp_path)
    m = load_manifest(tmp_path)
    plane = m.laser.mount_z
    laser = Laser2D(m.laser, scene_shapes(m, m.objects))
    rng = np.random.default_rng(3)
    with BulletWorld(m, 100.0) as sim:
        x0, y0, x1, y1 = m.bounds
        for _ in range(5):
            pose = (float(rng.uniform(x0 + 1.2, x1 - 1.2)), float(rng.uniform(y0 + 1.2, y1 - 1.2)),
                    float(rng.uniform(-np.pi, np.pi)))
            sim.place(sim.robot_id, pose)
            ours = laser.scan(pose)
            o = laser.origin(pose)
            ref = sim.ray_scan((float(o[0]), float(o[1]), plane), laser.angles + pose[2],
                               m.laser.max_range)
            ref = np.clip(ref, m.laser.min_range, m.laser.max_range)
            inside = ours <= m.laser.min_range  # pose inside an obstacle: pybullet sees nothing
            close = np.abs(ours - ref) < 2e-3
            assert np.mean(close | inside) > 0.97, (pose, np.nonzero(~close)[0][:10])


def test_walls_merge_into_runs(tmp_path: Path) -> None:
    mission = EXAMPLES / "navigation" / "navigation.mission"
    generate_world(mission, tmp_path)
    m = load_manifest(tmp_path)
    merged = merge_wall_tiles(m.walls, m.tile_size)
    assert len(merged) < len(m.walls)
    # Same covered area.
    assert float((merged[:, 3] * merged[:, 4] * 4).sum()) == pytest.approx(len(m.walls))
    assert load_concrete_mission(mission).world.name == m.world
