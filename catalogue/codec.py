"""Footprints as JSON: the one encoding every file REI writes uses for them (world.json and
monitor.json, written by the generators; a run's trace), beside the footprint types.

``footprint_json`` writes any footprint; ``simulated`` is the shape pybullet builds of it (a
tile as a box of the room's tile size, a polygon as its bounding box), which is what the
generated world files hold. Reading them back, with every field checked as input, is the
trace's rules' job (``rei.runtime.trace.rules.footprint_of``), for the trace and the generated
files alike. This module must never import the runtime.
"""

from __future__ import annotations

from typing import Any

from rei.catalogue.model import Box, Cylinder, Footprint, Polygon, Tile


def footprint_json(fp: Footprint) -> dict[str, Any]:
    """``{"shape": "box", "size": [x, y]}``, ``{"shape": "cylinder", "radius": r}``,
    ``{"shape": "polygon", "points": [[x, y], ...]}`` or ``{"shape": "tile"}``."""
    if isinstance(fp, Box):
        return {"shape": "box", "size": [fp.size_x, fp.size_y]}
    if isinstance(fp, Cylinder):
        return {"shape": "cylinder", "radius": fp.radius}
    if isinstance(fp, Polygon):
        return {"shape": "polygon", "points": [list(p) for p in fp.points]}
    return {"shape": "tile"}


def simulated(fp: Footprint, tile: float) -> Box | Cylinder:
    """The shape the simulator builds of ``fp`` in a room of ``tile``-sized cells."""
    if isinstance(fp, Tile):
        return Box(tile, tile)
    if isinstance(fp, Cylinder | Box):
        return fp
    hx, hy = fp.half_extents()
    return Box(2 * hx, 2 * hy)
