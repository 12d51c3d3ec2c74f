"""Search for failing scenarios: candidates from the room generator's factors and continuous
parameters, run on the campaign engines, steered by a requirement's robustness margin.

``strategies`` proposes points of the unit cube (random, Sobol, Halton, Optuna's TPE and
CMA-ES, pyribs' MAP-Elites); ``rei.generators.rooms.design.decode_point`` turns a point into
a suite row; ``candidates`` builds and writes the checked .room/.mission pair; ``run`` runs
each batch as a growing campaign (the search folder is a campaign folder `rei report` reads)
and tells the strategy each run's margin. This package never imports pybullet.
"""

from rei.runtime.campaigns.search.driver import SearchConfig, SearchResult, objective, run_search
from rei.runtime.campaigns.search.errors import SearchError
from rei.runtime.campaigns.search.strategies import (
    STRATEGIES,
    SearchStrategy,
    Told,
    check_strategy,
    make_strategy,
)

__all__ = [
    "STRATEGIES", "SearchConfig", "SearchError", "SearchResult", "SearchStrategy", "Told",
    "check_strategy", "make_strategy", "objective", "run_search",
]
