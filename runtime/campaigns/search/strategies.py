"""How a search picks its next candidates: points of the unit cube, asked and told in batches.

Every strategy proposes points in [0, 1]^d (``rei.generators.rooms.design.decode_point`` turns
a point into a suite row) and is told, per point, the objective to minimise (the chosen
requirement's margin) and the point's difficulty descriptors. Strategies are asked for one
fixed-size batch at a time and told the whole batch in proposal order, so the order in which
runs finish (one worker or many, a resumed session) never changes what comes next; with the
same seed and the same answers a strategy asks the same points, which is what lets a resumed
search replay its history instead of storing the optimiser's state.

Baselines: ``random`` (NumPy's PCG64) and the scrambled quasi-random ``sobol`` and ``halton``
sequences of scipy.stats.qmc (even coverage of the space for the same budget). Optimisers:
Optuna's ``tpe`` (Tree-structured Parzen Estimator, categorical factors as categories) and
``cmaes`` (CMA-ES through the ``cmaes`` package). Quality diversity: ``map-elites``, pyribs'
GridArchive over two difficulty descriptors with a Gaussian emitter, so the failures found
spread over the descriptor grid instead of piling into one kind of room.

The heavy libraries are imported only when their strategy is chosen, with an install hint
when missing. This module never runs a simulation and never reads the clock.
"""

from __future__ import annotations

import importlib
import logging
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any, Protocol, runtime_checkable

from rei.generators.rooms.design import SearchDimension
from rei.runtime.campaigns.search.errors import SearchError

STRATEGIES: tuple[str, ...] = ("random", "sobol", "halton", "tpe", "cmaes", "map-elites")
INSTALL_HINT = "pip install 'rei-testbed[search]'"

Point = tuple[float, ...]


@dataclass(frozen=True)
class Told:
    """What a strategy learns about one point it proposed."""

    objective: float
    """The value to minimise (a margin; finite)."""
    measures: tuple[float, float]
    """The point's two difficulty descriptors (map-elites' grid; the others ignore them)."""
    built: bool = True
    """False when the generator could not build the point's room: its objective and
    descriptors describe no room (map-elites keeps it out of the archive)."""


@runtime_checkable
class SearchStrategy(Protocol):
    """Proposes batches of points in [0, 1]^d and learns from their objectives."""

    @property
    def name(self) -> str: ...

    def ask(self, count: int) -> list[Point]: ...

    def tell(self, points: Sequence[Point], told: Sequence[Told]) -> None: ...


def check_strategy(strategy: object, dims: int = 2) -> list[str]:
    """Problems that keep ``strategy`` from being a search strategy (empty: conforms): the
    methods, points of the right size inside the unit cube, and one batch told back."""
    problems = []
    if not isinstance(getattr(strategy, "name", None), str):
        problems.append("expected a 'name' attribute of type str")
    for method in ("ask", "tell"):
        if not callable(getattr(strategy, method, None)):
            problems.append(f"expected a method '{method}'")
    if problems:
        return problems
    points = strategy.ask(3)  # type: ignore[attr-defined]
    if len(points) != 3:
        problems.append(f"ask(3) returned {len(points)} points")
    for p in points:
        if len(p) != dims or not all(math.isfinite(u) and 0.0 <= u <= 1.0 for u in p):
            problems.append(f"ask returned {p!r}, expected {dims} coordinates in [0, 1]")
            break
    strategy.tell(points, [Told(float(k), (0.0, 0.0)) for k in range(len(points))])  # type: ignore[attr-defined]
    return problems


def import_optional(module: str, strategy: str) -> ModuleType:
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise SearchError(f"--strategy {strategy}: needs the Python package of '{module}': "
                          f"{INSTALL_HINT}") from exc


def _clip(point: Sequence[float]) -> Point:
    return tuple(min(max(float(u), 0.0), 1.0) for u in point)


@dataclass
class RandomStrategy:
    """Independent uniform points: the baseline every other strategy is measured against."""

    dims: int
    seed: int
    name: str = field(default="random", init=False)

    def __post_init__(self) -> None:
        import numpy as np  # noqa: PLC0415

        self._rng = np.random.Generator(np.random.PCG64(self.seed))

    def ask(self, count: int) -> list[Point]:
        return [_clip(row) for row in self._rng.random((count, self.dims))]

    def tell(self, points: Sequence[Point], told: Sequence[Told]) -> None:
        return None


@dataclass
class QuasiRandomStrategy:
    """Scrambled Sobol or Halton points (scipy.stats.qmc), continuing one sequence."""

    dims: int
    seed: int
    name: str = "sobol"

    def __post_init__(self) -> None:
        qmc = import_optional("scipy.stats.qmc", self.name)
        engine = qmc.Sobol if self.name == "sobol" else qmc.Halton
        self._engine = engine(self.dims, scramble=True, seed=self.seed)

    def ask(self, count: int) -> list[Point]:
        with warnings.catch_warnings():
            # Sobol's balance is best at powers of two; any batch size is still valid.
            warnings.simplefilter("ignore", UserWarning)
            return [_clip(row) for row in self._engine.random(count)]

    def tell(self, points: Sequence[Point], told: Sequence[Told]) -> None:
        return None


@dataclass
class OptunaStrategy:
    """Optuna's TPE or CMA-ES sampler through its ask-and-tell interface, minimising."""

    dimensions: tuple[SearchDimension, ...]
    seed: int
    batch: int
    name: str = "tpe"

    def __post_init__(self) -> None:
        optuna = import_optional("optuna", self.name)
        optuna.logging.set_verbosity(logging.WARNING)
        sampler: Any
        if self.name == "cmaes":
            import_optional("cmaes", self.name)
            # One generation per batch: the batch is the population, so each tell completes
            # a generation whatever order the runs finished in.
            sampler = optuna.samplers.CmaEsSampler(seed=self.seed, n_startup_trials=0,
                                                   popsize=max(self.batch, 2),
                                                   warn_independent_sampling=False)
        else:
            # The first batch explores at random, every later one uses the model.
            sampler = optuna.samplers.TPESampler(seed=self.seed,
                                                 n_startup_trials=max(self.batch, 2))
        self._optuna = optuna
        self._study = optuna.create_study(direction="minimize", sampler=sampler)
        self._pending: dict[Point, list[Any]] = {}

    def _distributions(self) -> dict[str, Any]:
        dist = self._optuna.distributions
        out: dict[str, Any] = {}
        for k, d in enumerate(self.dimensions):
            if d.categorical and self.name == "tpe":
                out[f"x{k}"] = dist.CategoricalDistribution(list(range(len(d.levels))))
            else:  # CMA-ES needs numbers: categorical levels take equal slices of [0, 1]
                out[f"x{k}"] = dist.FloatDistribution(0.0, 1.0)
        return out

    def ask(self, count: int) -> list[Point]:
        points = []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", self._optuna.exceptions.ExperimentalWarning)
            for _ in range(count):
                trial = self._study.ask(self._distributions())
                point = []
                for k, d in enumerate(self.dimensions):
                    value = trial.params[f"x{k}"]
                    if d.categorical and self.name == "tpe":
                        value = (int(value) + 0.5) / len(d.levels)
                    point.append(float(value))
                clipped = _clip(point)
                self._pending.setdefault(clipped, []).append(trial)
                points.append(clipped)
        return points

    def tell(self, points: Sequence[Point], told: Sequence[Told]) -> None:
        for point, answer in zip(points, told, strict=True):
            trial = self._pending[point].pop(0)
            self._study.tell(trial, answer.objective)


ARCHIVE_FLOOR = -1e6
"""map-elites' archive admits only (negated) objectives above this; every real one is."""
UNBUILT = 2 * ARCHIVE_FLOOR
"""What map-elites tells pyribs for a candidate that was not built: below ARCHIVE_FLOOR."""


@dataclass
class MapElitesStrategy:
    """MAP-Elites (pyribs): a grid archive over two difficulty descriptors keeps the lowest
    margin found in each cell; a Gaussian emitter mutates elites into new points."""

    dims: int
    seed: int
    batch: int
    ranges: tuple[tuple[float, float], tuple[float, float]]
    bins: int = 8
    sigma: float = 0.15
    name: str = field(default="map-elites", init=False)

    def __post_init__(self) -> None:
        import numpy as np  # noqa: PLC0415

        archives = import_optional("ribs.archives", self.name)
        emitters = import_optional("ribs.emitters", self.name)
        schedulers = import_optional("ribs.schedulers", self.name)
        self._np = np
        # A finite threshold_min (with learning_rate 1, i.e. plain MAP-Elites) lets every
        # told objective above it in, and keeps out the points told UNBUILT below it.
        self.archive = archives.GridArchive(solution_dim=self.dims, dims=[self.bins] * 2,
                                            ranges=list(self.ranges), seed=self.seed,
                                            learning_rate=1.0, threshold_min=ARCHIVE_FLOOR)
        emitter = emitters.GaussianEmitter(self.archive, sigma=self.sigma,
                                           x0=np.full(self.dims, 0.5),
                                           bounds=[(0.0, 1.0)] * self.dims,
                                           batch_size=self.batch, seed=self.seed)
        self._scheduler = schedulers.Scheduler(self.archive, [emitter])
        self._asked: list[Point] = []

    def ask(self, count: int) -> list[Point]:
        if count > self.batch:
            raise ValueError(f"map-elites asks at most {self.batch} points at once")
        self._asked = [_clip(row) for row in self._scheduler.ask()]
        return self._asked[:count]

    def tell(self, points: Sequence[Point], told: Sequence[Told]) -> None:
        if len(told) < len(self._asked):
            return  # the search's last, shortened batch: nothing comes after it
        np = self._np
        # pyribs maximises: the objective is the negated margin. An unbuilt candidate is
        # still told (the emitter's batch must stay whole) but below the archive's floor,
        # so it never becomes an elite the emitter mutates from.
        self._scheduler.tell(np.array([-t.objective if t.built else UNBUILT for t in told]),
                             np.array([list(t.measures) for t in told]))


DEFAULT_MEASURES = ("closest_obstacle_m", "tortuosity")
MEASURE_RANGES: dict[str, tuple[float, float]] = {
    "closest_obstacle_m": (0.0, 2.0), "visibility_m": (0.0, 3.5), "dispersion": (0.0, 1.0),
    "characteristic_dimension_m": (0.0, 5.0), "tortuosity": (1.0, 2.5),
    "narrowest_m": (0.0, 3.0), "path_length_m": (0.0, 40.0), "human_count": (0.0, 6.0),
    "crossings": (0.0, 6.0), "object_density": (0.0, 0.5),
}
"""The grid's range per difficulty descriptor (values outside fall into the edge cells)."""


def refuse_unusable(name: str, dims: int) -> None:
    """SearchError when strategy ``name`` cannot search ``dims`` dimensions."""
    if name not in STRATEGIES:
        raise SearchError(f"--strategy: expected one of {', '.join(STRATEGIES)}, found "
                          f"'{name}'")
    if name == "cmaes" and dims < 2:
        # Optuna's CMA-ES samples a one-dimensional space at random, with a warning: say so.
        raise SearchError("--strategy cmaes: expected at least two searched dimensions (CMA-ES "
                          "adapts a covariance), found one; use tpe for a single parameter")


def make_strategy(name: str, dimensions: tuple[SearchDimension, ...], seed: int, batch: int,
                  measures: tuple[str, str] = DEFAULT_MEASURES) -> SearchStrategy:
    """A fresh strategy; two made with the same arguments propose the same points."""
    dims = len(dimensions)
    if name == "random":
        return RandomStrategy(dims, seed)
    if name in ("sobol", "halton"):
        return QuasiRandomStrategy(dims, seed, name)
    refuse_unusable(name, dims)
    if name in ("tpe", "cmaes"):
        return OptunaStrategy(dimensions, seed, batch, name)
    if name == "map-elites":
        ranges = (MEASURE_RANGES[measures[0]], MEASURE_RANGES[measures[1]])
        return MapElitesStrategy(dims, seed, batch, ranges)
    raise AssertionError(name)  # refuse_unusable knows every name
