"""Fixtures shared by the test modules of the LLM chain."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from llm_stub_server import StubLLMServer


@pytest.fixture
def server() -> Iterator[StubLLMServer]:
    """A scripted OpenAI-compatible server on 127.0.0.1 (a fixture; its answers are never results)."""
    with StubLLMServer() as stub:
        yield stub
