"""Fixtures shared by the test modules of the LLM chain, and the ``jail`` marker's skip rule."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from llm_stub_server import StubLLMServer


@pytest.fixture
def server() -> Iterator[StubLLMServer]:
    """A scripted OpenAI-compatible server on 127.0.0.1 (a fixture; its answers are never results)."""
    with StubLLMServer() as stub:
        yield stub


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Tests marked ``jail`` are skipped, with the machine's reason, where no jail can be made
    (capmj then refuses to run LLM-written task code at all, so there is nothing to test)."""
    marked = [item for item in items if item.get_closest_marker("jail")]
    if not marked:
        return
    from capmj.confine import jail

    why = jail.problem()
    if why is not None:
        for item in marked:
            item.add_marker(pytest.mark.skip(reason=f"no jail on this machine: {why}"))
