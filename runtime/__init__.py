"""What runs a test: the pybullet world, the robot under test, the animator, the mission
executor, the data collector, the host of the generated event automata, and the evaluator.

The monitor and evaluator never import pybullet: they meet the simulator only through the
sample stream defined in ``rei.runtime.messages``.
"""
