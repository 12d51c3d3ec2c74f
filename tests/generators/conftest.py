"""Fixtures of the generator tests: requests built from the examples and from small rooms."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from rei.generators.pipeline import build_request
from rei.generators.targets import GenerationRequest

RequestFor = Callable[..., GenerationRequest]
Write = Callable[[str, "str | bytes"], Path]
"""The type of the `write` fixture of tests/conftest.py."""


@pytest.fixture
def request_for() -> RequestFor:
    """The checked, concretised GenerationRequest of a file: request_for(path, seed='7')."""

    def _request(path: Path, **options: str) -> GenerationRequest:
        request, _ = build_request(Path(path), options)
        return request

    return _request
