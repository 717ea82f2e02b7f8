"""``python -m capmj.bench report RUN… --html``: the page, opened from disk in a real headless Chromium.

Two small real runs are made once for the module (tests/report_runs.py): the LLM agent scripted
through the stub server on task A × two seeds, and a ``--configs`` run of two configurations of
it (temperature 0 and 0.5, from a TOML file) on the same seeds; in each run the first plan fails.  The page must load from ``file://`` with nothing in the browser's console and
no resource fetched, show in its DOM the numbers ``summary.json`` holds, and show exactly the
failed episodes in its gallery, each with its worker-made thumbnail and the command that opens its
``.rrd``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from report_runs import TASK, llm_run

from capmj.bench.cli import report_main
from capmj.bench.page import render_page
from capmj.bench.page.view import legacy_efficiency
from capmj.bench.results import read_records
from capmj.bench.rundir import RunDir

FIRST = "llm openai/stub (reporter=none)"
CONFIGS = """
[configs.cold]
about = "temperature 0"
temperature = 0.0
[configs.warm]
about = "temperature 0.5"
temperature = 0.5
"""


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("runs")
    (root / "configs.toml").write_text(CONFIGS)
    return (llm_run(root / "llm", [TASK], "10001,10003"),
            llm_run(root / "grid", [TASK], "10001,10003", "--configs", "cold,warm", "--configs-file",
                    str(root / "configs.toml")))


def _failed(run: Path) -> list[Any]:
    return [r for r in read_records(run / "episodes.jsonl")[0] if not r.success]


def test_the_worker_draws_the_final_top_down_view_of_failed_episodes_only(runs: tuple[Path, Path]) -> None:
    from PIL import Image

    from capmj.bench.thumbnail import render_top_view
    from capmj.tasks import registry

    for run in runs:  # exactly the failed episodes get a thumbnail, under their configuration's folder
        failed = _failed(run)
        assert len(failed) == 1
        thumbs = sorted(p.relative_to(run).as_posix() for p in (run / "thumbs").rglob("*.png"))
        assert thumbs == [RunDir.thumb_relpath(r.task, r.seed, r.agent, r.model, r.config) for r in failed]
    (rec,) = _failed(runs[1])
    path = runs[1] / RunDir.thumb_relpath(rec.task, rec.seed, rec.agent, rec.model, rec.config)
    assert rec.config == "cold" and path.parent.parent.name == "cold"
    image = np.asarray(Image.open(path).convert("RGB"))
    assert image.shape == (160, 320, 3)
    # the picture is the final state: the block the plan moved is not where it started
    start = render_top_view(registry.get_task(rec.task), rec.seed, {})
    assert np.array_equal(render_top_view(registry.get_task(rec.task), rec.seed, rec.final_poses), image)
    assert (np.abs(start.astype(int) - image.astype(int)).max(axis=2) > 40).sum() > 100


def _cells(summary: dict[str, Any]) -> dict[tuple[str, str], dict[str, Any]]:
    """(config, task or "" for overall) -> the success cell, from the profile when the summary has one."""
    prof = summary.get("profile")
    if prof:
        out = {(c, t): cell for c, per in prof["cells"].items() for t, cell in per.items()}
        out.update({(c, ""): cell for c, cell in prof["overall"].items()})
        return out
    out = {(c, t): cell for t, per in summary["tasks"].items() for c, cell in per.items()}
    out.update({(c, ""): cell for c, cell in summary["overall"].items()})
    return out


def _efficiency(summary: dict[str, Any], config: str) -> dict[str, Any]:
    prof = summary.get("profile")
    return prof["efficiency"][config] if prof else legacy_efficiency(summary["overall"][config])


def _number(text: str) -> float | None:
    return None if text == "" else float(text)


def _open(browser: Any, page: Path) -> list[dict[str, Any]]:
    browser.get(page.resolve().as_uri())
    assert browser.execute_script("return document.readyState") == "complete"
    return [e for e in browser.get_log("browser")]


@pytest.mark.browser
def test_the_page_opens_from_disk_shows_the_summary_and_the_failed_episodes(runs: tuple[Path, Path], browser: Any,
                                                                          tmp_path: Path) -> None:
    from selenium.webdriver.common.by import By

    out = tmp_path / "cmp"
    assert report_main([str(runs[0]), str(runs[1]), "--out", str(out), "--html"]) == 0  # same stamps: comparable
    page = out / "report.html"
    summary = json.loads((out / "summary.json").read_text())
    log = _open(browser, page)
    assert log == [], log  # no console error, no warning, nothing blocked by the page's CSP
    assert browser.execute_script("return performance.getEntriesByType('resource').length") == 0
    links = browser.execute_script("return [...document.querySelectorAll('[src],[href]')]"
                                   ".map(e => e.getAttribute('src') || e.getAttribute('href'))")
    assert links and all(x.startswith(("data:", "#")) for x in links), links  # nothing outside the file
    # every picture decoded (plots as SVG, thumbnails as PNG, all data: URIs)
    images = browser.find_elements(By.TAG_NAME, "img")
    assert len(images) >= 3
    assert all(browser.execute_script("return arguments[0].complete && arguments[0].naturalWidth > 0", i)
               for i in images)

    # the profile table: every cell's numbers are summary.json's
    cells = _cells(summary)
    shown = {}
    for td in browser.find_elements(By.CSS_SELECTOR, "#profile-table td.rate"):
        key = (td.get_attribute("data-config"), td.get_attribute("data-task"))
        if td.get_attribute("data-n") == "0":
            assert key not in cells
            continue
        shown[key] = {k: _number(td.get_attribute(f"data-{k}")) for k in ("n", "successes", "rate", "lo", "hi")}
    assert set(shown) == set(cells)
    for key, cell in cells.items():
        assert shown[key] == {"n": cell["n"], "successes": cell["successes"], "rate": cell["success_rate"],
                              "lo": cell["ci95"][0], "hi": cell["ci95"][1]}, key
    assert [shown[(c, "")]["rate"] for c in (FIRST, "cold", "warm")] == [0.5, 0.5, 1.0]

    # the efficiency table: per episode and per solved episode
    for row in browser.find_elements(By.CSS_SELECTOR, "#efficiency-table tr[data-config]"):
        eff = _efficiency(summary, row.get_attribute("data-config"))
        for td in row.find_elements(By.CSS_SELECTOR, "td[data-metric]"):
            want = eff[td.get_attribute("data-per")][td.get_attribute("data-metric")]
            assert _number(td.get_attribute("data-value")) == want
    row = browser.find_element(By.CSS_SELECTOR, f'#efficiency-table tr[data-config="{FIRST}"]')
    tokens = row.find_element(By.CSS_SELECTOR, 'td[data-metric="tokens"][data-per="per_solved"]')
    total = summary["overall"][FIRST]["llm_usage"]["tokens"]
    assert _number(tokens.get_attribute("data-value")) == total / 1 > 0  # one episode solved

    # the paired comparisons against the first configuration: cold failed the same pair, warm solved it
    tables = {t.get_attribute("data-b"): t for t in browser.find_elements(By.CSS_SELECTOR, "table.comparison")}
    assert set(tables) == {"cold", "warm"}
    for b, only_b in (("cold", "0"), ("warm", "1")):
        overall = tables[b].find_element(By.CSS_SELECTOR, 'tr[data-task=""]')
        assert (overall.get_attribute("data-n"), overall.get_attribute("data-only-a"),
                overall.get_attribute("data-only-b")) == ("2", "0", only_b)

    # the gallery: exactly the failed episodes of both folders, each with its thumbnail, error, plan and .rrd command
    cards = {(c.get_attribute("data-config"), c.get_attribute("data-task"), c.get_attribute("data-seed")): c
             for c in browser.find_elements(By.CSS_SELECTOR, "#gallery article.failed-episode")}
    failed = {(FIRST if run == runs[0] else str(r.config), r.task, str(r.seed)): (run, r)
              for run in runs for r in _failed(run)}
    assert set(cards) == set(failed)
    for key, card in cards.items():
        run, rec = failed[key]
        assert card.get_attribute("data-failure") == rec.failure == "unknown_object"
        thumb = card.find_element(By.TAG_NAME, "img")
        assert browser.execute_script("return arguments[0].naturalWidth", thumb) == 320
        assert "fixed purple bowl with obj_id 99" in card.text  # the error message
        card.find_element(By.CSS_SELECTOR, "details.attempt summary").click()
        assert "put_first_on_second(blocks[1], 'fixed purple bowl with obj_id 99')" in \
            card.find_element(By.CSS_SELECTOR, "pre.code").text
        command = card.find_element(By.CSS_SELECTOR, "code.cmd").text
        rrd = (run / str(rec.rrd)).resolve()
        assert rrd.is_file() and command == f"capmj-replay {rrd} --open"
    browser.save_screenshot(str(tmp_path / "page.png"))


def test_a_run_without_thumbnails_profile_or_anomalies_still_gets_a_page(runs: tuple[Path, Path],
                                                                       tmp_path: Path) -> None:
    """An older run: no thumbs/, a summary with only the per-task cells — the page says what is missing."""
    import shutil

    llm = runs[0]
    old = tmp_path / "old"
    shutil.copytree(llm, old)
    shutil.rmtree(old / "thumbs")
    summary = json.loads((llm / "summary.json").read_text())
    for key in ("profile", "anomalies", "stamp"):
        summary.pop(key, None)
    html = render_page(summary, [old])
    assert 'data-source="tasks"' in html
    assert "no thumbnail" in html and "no anomaly accounting" in html
    assert html.count('class="failed-episode agent"') == 1
    # the efficiency of an older summary comes from its cells: totals over the episodes solved
    (cell,) = summary["overall"].values()
    found = re.search(r'data-metric="tokens" data-per="per_solved" data-value="([^"]*)"', html)
    assert found and float(found.group(1)) == cell["llm_usage"]["tokens"] / cell["successes"]
    found = re.search(r'data-metric="wall_s" data-per="per_episode" data-value="([^"]*)"', html)
    assert found and float(found.group(1)) == cell["wall_s_total"] / cell["n"]


def test_without_chromium_the_browser_tests_say_how_to_get_it(monkeypatch: pytest.MonkeyPatch) -> None:
    import conftest

    monkeypatch.setattr(conftest.shutil, "which", lambda name: None)
    assert "apt install chromium chromium-driver" in str(conftest.browser_problem())


def test_a_card_shows_each_turn_and_escapes_what_the_model_wrote() -> None:
    """LLM-written text (plans, feedback, errors) is data on the page, never markup."""
    from capmj.bench.page.gallery import Attempt, FailedEpisode
    from capmj.bench.page.html import _card

    hostile = "print('</pre><script>alert(1)</script>')"
    ep = FailedEpisode(config="M1", task=TASK, seed=10001, failure="no_finish", error=None, goal="<b>goal</b>",
                       progress=0.0, diagnostics=("<img src=x onerror=alert(1)>",),
                       attempts=(Attempt(1, hostile, feedback="ran: <ok>", finish=False),
                                 Attempt(2, "x = 1", error="NameError: <y>", finish=False)),
                       turns=True, thumbnail=None, rrd=None, transcript=None)
    html = _card(ep, anomaly=False)
    assert "Turn 1: plan (1 lines) · no FINISH" in html and "Turn 2: plan" in html
    assert "&lt;/pre&gt;&lt;script&gt;alert(1)&lt;/script&gt;" in html and "ran: &lt;ok&gt;" in html
    assert "<script" not in html and "<img src=x" not in html and "<b>goal" not in html
    assert "no thumbnail" in html and "No .rrd log" in html
