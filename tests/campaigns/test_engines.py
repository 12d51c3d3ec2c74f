"""Engines conform to the CampaignEngine protocol; bad engine options are refused."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from rei.runtime.campaigns import CampaignEngine, CampaignError, DaskEngine, LocalEngine
from rei.runtime.campaigns.engines import check_engine


@pytest.mark.parametrize("engine", [LocalEngine(2), DaskEngine("tcp://127.0.0.1:8786")])
def test_built_in_engines_conform(engine: object) -> None:
    assert check_engine(engine) == []
    assert isinstance(engine, CampaignEngine)


def test_the_checker_names_what_is_missing() -> None:
    class Half:
        name = 3

        def execute(self) -> None: ...

    assert check_engine(Half()) == ["expected a 'name' attribute of type str",
                                    "expected a method 'describe'"]


def test_local_engine_needs_a_worker() -> None:
    with pytest.raises(CampaignError, match="--workers: expected at least 1, found 0"):
        LocalEngine(0)


def test_engines_describe_themselves_for_the_provenance() -> None:
    assert LocalEngine(3).describe() == {"engine": "local", "workers": 3, "pages": "all"}
    assert DaskEngine("tcp://h:1", pages="failed").describe() == {
        "engine": "dask", "scheduler": "tcp://h:1", "pages": "failed"}


@pytest.mark.parametrize("make", [lambda: LocalEngine(1, pages="some"),
                                  lambda: DaskEngine("tcp://h:1", pages="")])
def test_engines_refuse_an_unknown_page_policy(make: Callable[[], object]) -> None:
    with pytest.raises(CampaignError, match="--pages: expected one of all, failed, none, "
                                            "found 'some'|found ''"):
        make()
