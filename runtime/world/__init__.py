"""The simulated world: the generated pybullet target loaded headless, and its manifest."""

from rei.runtime.world.manifest import BodySpec, Trajectory, WorldManifest, load_manifest

__all__ = ["BodySpec", "Trajectory", "WorldManifest", "load_manifest"]
