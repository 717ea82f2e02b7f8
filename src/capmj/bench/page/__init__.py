"""``python -m capmj.bench report RUN… --html``: one self-contained HTML page of one or several runs.

The page is built from what the run folders hold — the report's summary (``summary.json``'s
shape, :func:`capmj.bench.report.report`), ``episodes.jsonl``, ``config.json`` and the failed
episodes' thumbnails (:mod:`capmj.bench.thumbnail`) — and opens from disk with no server and no
network: plots (matplotlib) and pictures are base64 data URIs, the style is inline, there is no
script, and a Content-Security-Policy forbids loading anything.  Every number a reader compares
carries ``data-*`` attributes holding the summary's value unrounded (tests read them in a real
browser).  Fields a summary lacks (older runs) are left out or said to be absent, never invented.

:mod:`~capmj.bench.page.gallery` gathers the failed episodes, :mod:`~capmj.bench.page.plots`
draws, :mod:`~capmj.bench.page.efficiency` computes the per-episode and per-solved-episode
costs, :mod:`~capmj.bench.page.html` writes the page.
"""

from __future__ import annotations

from capmj.bench.page.html import REPORT_HTML, render_page, write_page

__all__ = ["REPORT_HTML", "render_page", "write_page"]
