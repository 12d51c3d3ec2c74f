"""Fixtures of the generator tests: requests built from the examples and from small rooms."""

from __future__ import annotations

from pathlib import Path

import pytest

from rei.generators.pipeline import build_request
from rei.generators.targets import GenerationRequest


@pytest.fixture
def request_for():  # type: ignore[no-untyped-def]
    """The checked, concretised GenerationRequest of a file: request_for(path, seed='7')."""

    def _request(path: Path, **options: str) -> GenerationRequest:
        request, _ = build_request(Path(path), options)
        return request

    return _request
