"""`rei shrink`: delta debugging of a failing case down to the smallest one that still fails.

``case`` reads a .mission and its .room as text and edits them at the positions REI's linker
reports; ``ddmin`` is the generic algorithm; ``oracle`` runs a candidate on K seeds through the
campaign's local engine; ``shrinker`` holds the stages and shrink.json; ``session`` ties them to
an output folder. Nothing here imports pybullet: runs happen in `rei run` processes.
"""

from rei.runtime.campaigns.shrink.case import ScenarioCase, load_case, sizes
from rei.runtime.campaigns.shrink.oracle import RunSettings
from rei.runtime.campaigns.shrink.shrinker import ShrinkReport
from rei.runtime.campaigns.shrink.workflow import shrink_into, size_reduction

__all__ = ["RunSettings", "ScenarioCase", "ShrinkReport", "load_case", "shrink_into",
           "size_reduction", "sizes"]
