"""The viewer layout stored in each episode's ``.rrd``: 3D world on the left, cameras and texts on the right.

::

    +-----------------------------+----------------------------------+
    |                             | [front rgb | front depth | left…] |  (only with camera images)
    |   3D: /world                +----------------------------------+
    |   (table, objects, robot,   | [summary | goal | verdict | llm…] |
    |    pick/place targets)      +----------------------------------+
    |                             | primitives (text log)            |
    +-----------------------------+----------------------------------+

The time panel starts on the ``primitive`` timeline so that stepping with the arrow keys goes from
one pick-and-place to the next.
"""

from __future__ import annotations

from typing import Sequence


MAX_TEXT_TABS = 40
"""More text documents than this stay reachable through the entity tree only."""


def episode_blueprint(cameras: Sequence[str] = (), texts: Sequence[str] = ()):  # -> rrb.Blueprint
    import rerun.blueprint as rrb

    right: list = []
    if cameras:
        views = []
        for cam in cameras:
            views.append(rrb.Spatial2DView(origin=f"/camera/{cam}/rgb", name=f"{cam} rgb"))
            views.append(rrb.Spatial2DView(origin=f"/camera/{cam}/depth", name=f"{cam} depth"))
        right.append(rrb.Tabs(*views))
    # The summary already holds goal, verdict and diagnostics; other texts (LLM prompts, completions,
    # code...) get a tab each.  Every view costs a few kB in the file, so oracle logs stay minimal.
    extra = [rrb.TextDocumentView(origin=f"/text/{k}", name=k) for k in texts
             if k not in ("goal", "verdict", "primitives")][:MAX_TEXT_TABS]
    summary = rrb.TextDocumentView(origin="/summary", name="summary")
    right.append(rrb.Tabs(summary, *extra) if extra else summary)
    right.append(rrb.TextLogView(origin="/text/primitives", name="primitives"))
    layout = rrb.Horizontal(
        rrb.Spatial3DView(origin="/world", name="world"),
        rrb.Vertical(*right, row_shares=[3, 3, 2][-len(right):]),
        column_shares=[3, 2],
    )
    return rrb.Blueprint(layout, rrb.TimePanel(timeline="primitive"), collapse_panels=False)


__all__ = ["episode_blueprint"]
