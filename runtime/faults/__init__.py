"""The fault stage: what stands between the simulated sensors and the robot under test.

``FaultStage`` is the contract the run loop calls (``rei.runtime.faults.stage``); ``NO_FAULTS``
passes everything through unchanged. Faults act on what the robot receives (its scans, its
odometry, the commands its motors get), never on the ground truth the monitor judges by.
"""

from rei.runtime.faults.stage import NO_FAULTS, FaultStage, NoFaults

__all__ = ["NO_FAULTS", "FaultStage", "NoFaults"]
