"""The monitor: the runtime model, exact footprint geometry, query evaluation and the host
that runs the event automata generated from a .vepl file (thesis 5.1.3-5.1.6).

``MonitorSink`` is a sample sink (start / feed / finish) that writes events.csv and gives
the monitor's part of the run summary. It must never import the simulator: live runs and
replayed traces go through exactly the same code.
"""

from rei.runtime.monitor.host import AutomataHost, MonitorSink, generate_automata

__all__ = ["AutomataHost", "MonitorSink", "generate_automata"]
