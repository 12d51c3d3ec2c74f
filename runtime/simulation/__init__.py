"""The simulation: the run loop as components on one simulated clock (``loop``), pybullet's
world (``world``), the sensors (``sensors``), the humans (``animator``), the faults between
sensors and robot (``faults``), the mission executor (``mission``), the sampler that turns the
world into the sample stream (``sampler``), and assembling a run from generated artifacts
(``assembly``).

It may import the robot wing (the robot under test is one of its components), the platform and
the contracts; it must never import the observation side, the bus or anything above. It is the
only wing that imports pybullet.
"""
