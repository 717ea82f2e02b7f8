"""The page's figures as SVG documents (matplotlib, Agg backend), drawn from the page's
:class:`~capmj.bench.page.view.ProfileView`: the capability profile as a heat map (tasks × configurations,
the success rate as colour, ``k/n`` written in each cell) and the bars of ``summary.png``
(:func:`capmj.bench.report.plot`: the success rate per task with 95 % Wilson intervals) as SVG."""

from __future__ import annotations

import io
import textwrap
import tempfile
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from capmj.bench.page.view import ProfileView
from capmj.bench.report import plot, task_label

__all__ = ["bars_svg", "heatmap_svg"]


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    plt.rcParams["svg.hashsalt"] = "capmj"  # the same ids in every drawing
    return plt


def _rows(view: ProfileView, order: Callable[[str], Any]) -> list[tuple[str, Mapping[str, Mapping[str, Any]]]]:
    """(row name, {configuration: cell}) per task in ``order``, then the overall row."""
    tasks = sorted(view.tasks, key=order)
    return [(task_label(t), {c: view.cells.get(c, {}).get(t) or {} for c in view.configs}) for t in tasks] + \
        [("Overall", {c: view.overall.get(c) or {} for c in view.configs})]


def _svg(fig: Any, plt: Any) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="svg", metadata={"Date": None}, bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()


def heatmap_svg(view: ProfileView, order: Callable[[str], Any]) -> bytes:
    """Tasks as rows (and the overall row), configurations as columns; a cell without an agent episode
    is grey (and says how many anomalies it had)."""
    plt = _pyplot()
    import matplotlib
    import numpy as np

    rows = _rows(view, order)
    labels: Sequence[str] = view.configs
    rates = np.full((len(rows), len(labels)), np.nan)
    fig, ax = plt.subplots(figsize=(3.0 + 1.9 * len(labels), 1.2 + 0.4 * len(rows)))
    for i, (_, per) in enumerate(rows):
        for j, lab in enumerate(labels):
            st = per[lab]
            if st.get("n"):
                rates[i, j] = 100 * st["success_rate"]
                ax.text(j, i, f"{st['successes']}/{st['n']}", ha="center", va="center", fontsize=8)
            elif st.get("anomalies"):  # every episode of the cell was a harness failure
                ax.text(j, i, f"{st['anomalies']} anomal{'ies' if st['anomalies'] != 1 else 'y'}", ha="center",
                        va="center", fontsize=7, color="#555")
    cmap = matplotlib.colormaps["RdYlGn"].with_extremes(bad="#dddddd")
    image = ax.imshow(np.ma.masked_invalid(rates), cmap=cmap, vmin=0, vmax=100, aspect="auto", zorder=0)
    ax.set_xticks(range(len(labels)))
    ax.set_xticklabels([textwrap.fill(lab, 24) for lab in labels], fontsize=8)
    ax.get_xaxis().tick_top()
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels([name for name, _ in rows], fontsize=8)
    ax.axhline(len(rows) - 1.5, color="black", linewidth=1)
    fig.colorbar(image, ax=ax, label="success rate (%)", fraction=0.05, pad=0.02)
    fig.tight_layout()
    return _svg(fig, plt)


def bars_svg(view: ProfileView) -> bytes:
    """The view's cells as :func:`capmj.bench.report.plot` draws ``summary.png`` (grouped bars per
    task and configuration, Wilson error bars), as SVG."""
    cells = {"tasks": {t: {c: view.cells[c][t] for c in view.configs if t in view.cells.get(c, {})}
                       for t in view.tasks},
             "overall": {c: view.overall[c] for c in view.configs}}
    with tempfile.TemporaryDirectory(prefix="capmj-page-") as tmp:
        return plot(cells, Path(tmp) / "bars.svg", title="success rate per task").read_bytes()
