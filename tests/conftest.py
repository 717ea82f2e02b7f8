"""Fixtures shared by the test modules of the LLM chain, the ``jail`` and ``browser`` markers' skip
rules, and the headless browser of the ``browser`` tests."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from typing import Any

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
    why_no_browser = browser_problem() if any(item.get_closest_marker("browser") for item in items) else None
    for item in items:
        if why_no_browser is not None and item.get_closest_marker("browser"):
            item.add_marker(pytest.mark.skip(reason=f"no headless browser on this machine: {why_no_browser}"))
    marked = [item for item in items if item.get_closest_marker("jail")]
    if not marked:
        return
    from capmj.confine import jail

    why = jail.problem()
    if why is not None:
        for item in marked:
            item.add_marker(pytest.mark.skip(reason=f"no jail on this machine: {why}"))


# ---------------------------------------------------------------------- the browser marker
BROWSERS = ("chromium", "chromium-browser")
"""Debian's and Ubuntu's names of the Chromium binary (apt ``chromium``)."""
DRIVER = "chromedriver"
"""The system's ChromeDriver (apt ``chromium-driver``): Selenium is given its path, so Selenium
Manager never runs and nothing is downloaded."""


def browser_problem() -> str | None:
    """Why no headless Chromium can be driven here (None when it can): tests marked ``browser`` are
    skipped with this reason."""
    if not any(shutil.which(b) for b in BROWSERS):
        return f"no Chromium ({' or '.join(BROWSERS)}; apt install chromium chromium-driver)"
    if shutil.which(DRIVER) is None:
        return f"no {DRIVER} (apt install chromium-driver)"
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed (pip install -e '.[dev]')"
    return None


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """A headless Chromium driven by Selenium through the system chromedriver, with the browser's
    console log readable (``browser.get_log("browser")``); one per test module."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = next(str(shutil.which(b)) for b in BROWSERS if shutil.which(b))
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                "--window-size=1280,1600", "--hide-scrollbars"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(executable_path=str(shutil.which(DRIVER))), options=options)
    try:
        yield driver
    finally:
        driver.quit()
