"""Observation: judging a run's sample stream, wherever it comes from (a live run, a trace, the
bus, a ROS 2 bag). ``automata`` (the records and patterns generated automata are written
against), ``model`` (the runtime model the queries read: geometry, laser clearance, hazard,
efficiency), ``evaluator`` (utilities, the event log, verdicts, margins, the summary),
``monitor`` (the host of the generated automata, user functions, the data a specification
needs), ``judgement`` (the one stream judgement), ``recordings`` (MCAP recordings, foreign
ROS 2 bags, evidence checks), ``run_folder`` (one run's event log and paths, read leniently).

Inside, imports run monitor -> evaluator -> model -> automata. It may import the robot
contract, the mission executor and the contracts; it must never reach pybullet or the
simulation loop, even indirectly: the judge meets the simulator only through the stream.
"""
