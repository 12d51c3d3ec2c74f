"""From positions to floors (``FloorMap``): the abstract environment's floor tiles, which
floor a position lies on and which floors are neighbours. It must never import pybullet, the
simulation, the evaluator or the monitor's host.
"""

from __future__ import annotations

import numpy as np


class FloorMap:
    """From positions to floors: the floor tile (a square of the tile size around a floor
    centre) each position lies in, -1 for none. Floors of a generated world sit on a grid of
    tile-size steps, so the look-up is an index into that grid."""

    def __init__(self, centres: np.ndarray, tile: float) -> None:
        self.tile = tile
        self.centres = centres
        self.origin = centres.min(axis=0) if len(centres) else np.zeros(2)
        cells = np.rint((centres - self.origin) / tile).astype(np.int64) if len(centres) \
            else np.zeros((0, 2), dtype=np.int64)
        self.on_grid = bool(np.allclose(cells * tile + self.origin, centres, atol=1e-6))
        size = cells.max(axis=0) + 1 if len(cells) else np.zeros(2, dtype=np.int64)
        self.grid = np.full((int(size[0]), int(size[1])), -1, dtype=np.int64)
        # on a cell two floors claim, the first in header order wins (as for the robot)
        for k in range(len(cells) - 1, -1, -1):
            self.grid[cells[k, 0], cells[k, 1]] = k
        self.cells = cells
        self._adjacent: np.ndarray | None = None

    def of(self, xy: np.ndarray) -> np.ndarray:
        """The floor index of each (x, y) row, -1 off every floor."""
        if not len(self.centres) or not len(xy):
            return np.full(len(xy), -1, dtype=np.int64)
        if not self.on_grid:
            half = self.tile / 2
            inside = np.all(np.abs(xy[:, None, :] - self.centres[None, :, :]) <= half, axis=2)
            return np.where(inside.any(axis=1), inside.argmax(axis=1), -1)
        cell = np.floor((xy - self.origin) / self.tile + 0.5).astype(np.int64)
        ok = (cell >= 0).all(axis=1) & (cell[:, 0] < self.grid.shape[0]) & (
            cell[:, 1] < self.grid.shape[1])
        out = np.full(len(xy), -1, dtype=np.int64)
        out[ok] = self.grid[cell[ok, 0], cell[ok, 1]]
        return out

    def side_by_side(self, a: int, b: int) -> bool:
        """Floors ``a`` and ``b`` (indices, -1 for none) share an edge."""
        if a < 0 or b < 0:
            return False
        step = np.abs(self.centres[a] - self.centres[b]) / self.tile
        return bool(np.isclose(sorted(step), (0.0, 1.0), atol=1e-6).all())

    def adjacent(self) -> np.ndarray:
        """Floors by floors: their tiles share an edge (worked out once, on first use)."""
        if self._adjacent is None:
            n = len(self.centres)
            found = np.zeros((n, n), dtype=bool)
            if self.on_grid:
                for di, dj in ((1, 0), (0, 1)):
                    for k, (i, j) in enumerate(self.cells):
                        ii, jj = i + di, j + dj
                        if ii < self.grid.shape[0] and jj < self.grid.shape[1]:
                            other = self.grid[ii, jj]
                            if other >= 0:
                                found[k, other] = found[other, k] = True
            else:
                for k in range(n):
                    step = np.abs(self.centres - self.centres[k]) / self.tile
                    near = np.isclose(step, 1.0, atol=1e-6)
                    same = np.isclose(step, 0.0, atol=1e-6)
                    found[k] = (near[:, 0] & same[:, 1]) | (same[:, 0] & near[:, 1])
            self._adjacent = found
        return self._adjacent
