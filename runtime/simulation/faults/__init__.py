"""The fault stage: what stands between the simulated sensors and the robot under test.

``FaultStage`` is the contract the run loop calls (``rei.runtime.simulation.faults.stage``);
``NO_FAULTS``
passes everything through unchanged. Faults act on what the robot receives (its scans, its
odometry, the commands its motors get), never on the ground truth the monitor judges by.
``fault_stage(definitions, seed)`` builds a run's stage from a mission's fault section
(``ConcreteMission.faults``) and ``--fault`` options (``parse_fault_option``); the faults and
their semantics are in docs/faults.md.
"""

from rei.lang.mission.faults import (
    ALWAYS,
    FAULT_KINDS,
    Activation,
    FaultDefinition,
    parse_fault_option,
)
from rei.runtime.simulation.faults.composition import (
    FAULT_STREAM,
    FaultPlan,
    FaultStatistics,
    fault_stage,
)
from rei.runtime.simulation.faults.stage import NO_FAULTS, FaultStage, NoFaults, active_at

__all__ = ["ALWAYS", "FAULT_KINDS", "FAULT_STREAM", "NO_FAULTS", "Activation", "FaultDefinition",
           "FaultPlan", "FaultStage", "FaultStatistics", "NoFaults", "active_at", "fault_stage",
           "parse_fault_option"]
