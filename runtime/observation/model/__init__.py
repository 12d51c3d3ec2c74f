"""The runtime model the queries read (thesis 5.1.5.1), updated from the sample stream:
``runtime_model`` with its exact footprint ``geometry``, the ``floors``, the ``pushes`` it
was given, the laser's ``laser_clearance``, the ``hazard`` ahead, the task ``efficiency``
against the ``free_space`` shortest paths, the ``sample_checks`` and the ``interpolation``
between samples. It may import the automata's records and the contracts; it must never import
the evaluator, the monitor's host or the simulator.
"""
