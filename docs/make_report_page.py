"""The example report page of docs/bench.md and its screenshots, in a real headless Chromium.

    python docs/make_report_page.py                  # two small runs, the page, docs/img/report_page*.png
    python docs/make_report_page.py --keep runs/demo-page

Two configurations of the LLM agent on task A (stack-all-blocks-on-a-zone) × five seeds, its
plans scripted through the tests' local stub server (a fixture, not a model result): in the first,
the first three plans fail three ways (a name that does not exist, the wrong zone, a syntax
error) and the others succeed; in the second (another temperature) every plan succeeds.  Then
``python -m capmj.bench report A B --html`` and Selenium with the system chromedriver
(apt ``chromium chromium-driver``): the top of the page and the failure gallery, scaled to
``--width`` and palette-quantised to stay small in git.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import threading
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

WRONG_ZONE = """```python
zone = [n for n in get_obj_names() if ' zone ' in n and get_color(n) != {color!r}][0]
for block in [n for n in get_obj_names() if ' block ' in n]:
    put_first_on_second(block, zone)
```"""
SYNTAX = """```python
for block in [n for n in get_obj_names() if ' block ' in n]
    put_first_on_second(block, {color!r})
```"""


def _responder(failures: list[str]) -> Any:
    from llm_stub_server import Reply, prompt_text
    from stub_solver import _GOAL, PLAN

    lock = threading.Lock()
    queue = list(failures)

    def respond(request: dict[str, Any]) -> Reply:
        found = _GOAL.findall(prompt_text(request))
        if not found:
            return Reply.error(400, "stub: this server only plans task A")
        with lock:
            plan = queue.pop(0) if queue else PLAN
        return Reply(text=plan.format(color=found[-1]))

    return respond


def _run(out: Path, failures: list[str], *extra: str) -> Path:
    from llm_stub_server import StubLLMServer
    from report_runs import TASK

    from capmj.bench.cli import main

    with StubLLMServer() as server:
        server.respond_with(_responder(failures))
        rc = main(["--agent", "llm", "--model", "openai/stub", "--api-base", server.base_url, "--reporter", "none",
                   "--tasks", TASK, "--seeds", "10001:10011:2", "--workers", "0", "--concurrency", "1",
                   "--out", str(out), "--no-progress", *extra])
    if rc != 0:
        raise SystemExit(f"the run into {out} failed ({rc})")
    return out


def _save(png: bytes, target: Path, width: int, crop: tuple[int, int] | None = None) -> None:
    import io

    from PIL import Image

    img = Image.open(io.BytesIO(png)).convert("RGB")
    if crop is not None:
        img = img.crop((0, crop[0], img.width, min(crop[1], img.height)))
    img = img.resize((width, round(img.height * width / img.width)), Image.LANCZOS)
    target.parent.mkdir(parents=True, exist_ok=True)
    img.quantize(colors=256, method=Image.Quantize.FASTOCTREE).save(target, optimize=True)  # keeps small areas' colours
    print(f"wrote {target} ({target.stat().st_size // 1024} KB)")


def _screenshots(page: Path, out: Path, width: int) -> None:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By

    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium") or shutil.which("chromium-browser") or "chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--hide-scrollbars",
                "--window-size=1280,1000"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(shutil.which("chromedriver") or "chromedriver"), options=options)
    try:
        driver.get(page.resolve().as_uri())
        height = driver.execute_script("return document.body.scrollHeight")
        driver.set_window_size(1280, height)
        top = driver.find_element(By.ID, "failures").location["y"]
        gallery = driver.find_element(By.ID, "gallery").location["y"]
        stamp = driver.find_element(By.ID, "stamp").location["y"]
        png = driver.get_screenshot_as_png()
    finally:
        driver.quit()
    _save(png, out / "report_page.png", width, (0, top))
    _save(png, out / "report_page_gallery.png", width, (gallery, stamp))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=ROOT / "docs" / "img", help="folder of the screenshots")
    p.add_argument("--width", type=int, default=1000, help="width of the written PNGs")
    p.add_argument("--keep", type=Path, default=None, metavar="DIR", help="make the runs and the page here and keep them")
    args = p.parse_args(argv)
    from capmj.bench.cli import report_main

    with tempfile.TemporaryDirectory(prefix="capmj-report-page-") as tmp:
        root = args.keep or Path(tmp)
        from report_runs import BROKEN_PLAN

        a = _run(root / "llm", [BROKEN_PLAN, WRONG_ZONE, SYNTAX])
        b = _run(root / "llm-t05", [], "--temperature", "0.5")
        page = root / "report.html"
        if report_main([str(a), str(b), "--out", str(root / "cmp"), "--html", str(page)]) != 0:
            raise SystemExit("report failed")
        _screenshots(page, args.out, args.width)
    return 0


if __name__ == "__main__":
    sys.exit(main())
