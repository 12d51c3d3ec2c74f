"""The simulated world: the generated pybullet target loaded headless (``bullet``) and the
robot's seeded start pose (``start_jitter``); the manifest it loads is a contract,
``rei.runtime.artifacts.world``."""
