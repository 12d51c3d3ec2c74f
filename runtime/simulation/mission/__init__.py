"""Mission execution: tasks fed to the robot in order, results judged by ground truth."""

from rei.runtime.simulation.mission.executor import MissionExecutor, TaskResult

__all__ = ["MissionExecutor", "TaskResult"]
