"""The object catalogue: what an abstract type means in simulation (thesis 4.1.3, Figure 11).

Each type has a footprint (box, cylinder or polygon, or the room's tile for floors and
walls), a height, a mass, an inertia, a colour and an optional mesh; robot types add their
drive limits and laser. The default catalogue ships as ``default.toml`` beside this file;
a room may name its own TOML file, whose types are added to the default or replace it by name.
"""

from rei.catalogue.loader import default_catalogue, load_catalogue
from rei.catalogue.model import (
    Box,
    Catalogue,
    CatalogueError,
    Cylinder,
    DriveSpec,
    Footprint,
    LaserSpec,
    ObjectType,
    Polygon,
    Tile,
)

__all__ = [
    "Box",
    "Catalogue",
    "CatalogueError",
    "Cylinder",
    "DriveSpec",
    "Footprint",
    "LaserSpec",
    "ObjectType",
    "Polygon",
    "Tile",
    "default_catalogue",
    "load_catalogue",
]
