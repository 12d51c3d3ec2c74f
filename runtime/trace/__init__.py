"""The run's sample trace on disk: exact, deterministic JSON lines, and reading it back.

Line 1 is the stream header, then one line per sample, then an ``end`` line with the
outcome. Floats are written by ``repr`` (Python's shortest round-tripping form), so reading
a trace gives back bit-identical numbers. Per-object poses and twists are written as the
rows that changed since the previous sample (static objects appear once), which keeps a
trace of a room of walls small without losing exactness. The writer streams to
``NAME.partial`` and renames it into place at ``finish``: a trace file that exists is
complete; a killed run leaves only the partial file.

A recording is input like any other: the reader checks every field of every line (JSON
types, with a bool never a number; finite numbers in their ranges; sequence numbers 0, 1, 2,
... without gaps; times that never go back; known event kinds, outcomes and causes; object
indices within the header's table; a sample carrying exactly the data the header names as
collected; exactly one end line, last) and refuses the first
violation with a ``TraceError`` naming ``path:line: field: expected ..., found ...``. The
reader stays lazy: a damaged line 5000 is found when line 5000 is read. The writer applies
the same rules to what it is about to write, so whatever it writes reads back and it never
writes what the reader would refuse. Traces of sample schema 3 (before the header named
the collected data) are still read: they carry every kind of data.

The package, one idea a module: ``format`` (the shared names and ``TraceError``), ``rules``
(a field's checks and the header's rules), ``sample_rules`` (the rules between the lines: the
samples, the end line), ``encode`` (records into lines: ``TraceEncoder``, ``TraceWriter``,
``write``) and ``read`` (``TraceDecoder``, ``read_trace``, ``read_trace_end``). ``encode``
and ``read`` import the rules and the format, never the other way round.

The trace format is what a run, a replay, the bus and a monitor share, so it imports only
the contracts (``rei.runtime.messages``, ``rei.runtime.results``, ``rei.runtime.errors``),
``rei.catalogue``, ``rei.lang``, ``rei.generators.output``, the standard library and numpy.
It must never import the simulation, pybullet or anything above the contracts.
"""

from rei.runtime.trace.encode import TraceEncoder, TraceWriter, write
from rei.runtime.trace.format import TraceError
from rei.runtime.trace.read import TraceDecoder, open_regular, read_trace, read_trace_end

__all__ = ["TraceDecoder", "TraceEncoder", "TraceError", "TraceWriter", "open_regular",
           "read_trace", "read_trace_end", "write"]
