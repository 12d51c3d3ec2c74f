"""The run loop as components on one simulated clock (issue 16).

``scheduler`` owns simulated time and steps each component's stages at their declared rates
in a fixed order; ``board`` holds the messages (``rei.runtime.messages``) the components
exchange, which is all they share. One module per component, each a frozen definition whose
``start`` returns the running part: world (pybullet, contacts), laser, odometry, faults (the
fault stage), mission (the executor), robot (the robot under test and its motors), collector
(samples to the sinks), humans (the animator: humans and dynamic objects).
``rei.runtime.simulation.assembly.run_mission``
assembles them; docs/run-loop.md describes the order within a tick.
"""

from rei.runtime.simulation.loop.board import Board
from rei.runtime.simulation.loop.controls import Robot, RobotRun
from rei.runtime.simulation.loop.dead_reckoning import DeadReckoning, DeadReckoningRun
from rei.runtime.simulation.loop.fault_injection import Faults, FaultsRun, SignalSource
from rei.runtime.simulation.loop.humans import Humans, HumansRun
from rei.runtime.simulation.loop.physics import World, WorldRun
from rei.runtime.simulation.loop.sampling import Collector, CollectorRun
from rei.runtime.simulation.loop.scans import Laser, LaserRun
from rei.runtime.simulation.loop.scheduler import Clock, Scheduler, Stage, every
from rei.runtime.simulation.loop.tasks import Mission, MissionRun

__all__ = ["Board", "Clock", "Collector", "CollectorRun", "DeadReckoning", "DeadReckoningRun",
           "Faults", "FaultsRun", "Humans", "HumansRun", "Laser", "LaserRun", "Mission",
           "MissionRun", "Robot", "RobotRun", "Scheduler", "SignalSource", "Stage", "World",
           "WorldRun", "every"]
