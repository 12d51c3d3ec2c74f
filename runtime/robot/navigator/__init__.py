"""The `reference` navigator shipped with REI: a real navigation stack's parts, so a mission
runs out of the box and defects can be seeded into a correct navigator (bench/defects).

``reference`` (the navigator: goals, the global path, the control loop, recovery) on
``localplan`` (the local planner's roll-outs and choice) on ``perception`` (the laser's points
and the slow zone); ``gridplan`` (A* over free cells), ``recovery`` (recovery behaviours),
``mapcast`` (a scan compared with the map), ``clearance`` (the signed distance to an oriented
box, and the clearance field), ``tuning`` (its constants in one frozen record).

It may import the robot contract and the contracts at runtime's root; it must never import
pybullet, the simulation or the monitor: it sees only what its sensors measured.
"""
