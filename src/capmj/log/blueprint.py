"""The viewer layout stored in every episode's ``.rrd``: the same views for every episode.

::

    +------------------------------------+-----------------------------------------------+
    |                                    | [summary | attempt 1 | attempt 2 | attempt 3 | |
    |   3D: /world, seen from the front  |  other texts]                                 |
    |   camera's side (fixed eye point)  |                                               |
    |                                    +-----------------------------------------------+
    |                                    | [primitives | say | perception | front rgb |    |
    |                                    |  front depth]                                 |
    +------------------------------------+-----------------------------------------------+

Every recording gets the same views (empty ones stay empty), so opening a second episode in the
same viewer keeps the layout and no tab is lost; only an episode with more than
``ATTEMPT_TABS`` attempts adds tabs.  The side panels and the time panel start collapsed (the
time bar with its play controls stays); the time panel is on the ``primitive`` timeline so that
the arrow keys step from one pick-and-place to the next.  Each view costs ~5 kB in every file,
which is why there are not more of them.
"""

from __future__ import annotations

from capmj.log.paths import ATTEMPTS, CAMERA, PERCEPTION_LOG, PRIMITIVE_LOG, SUMMARY_PATH, TEXT, WORLD, attempt_entity

ATTEMPT_TABS = 3
IMAGE_CAMERA = "front"
"""The camera whose images get views (the others are in the entity tree): each view costs ~5 kB
of every file, images or not."""
OTHER_TEXTS = f"{ATTEMPTS}/other"
SAY_LOG = f"{TEXT}/planner/say"


def eye_point() -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The 3D view's eye and look-at point: the front camera's line of sight, pulled back so the
    whole arm fits."""
    from capmj.sim.scene import camera_view

    (cx, cy, cz), (tx, ty, tz) = camera_view("front")
    k, lift = 1.25, 0.1  # a little farther back, aimed a little higher: table and arm both in view
    return (tx + k * (cx - tx), ty + k * (cy - ty), tz + k * (cz - tz) + lift), (tx - 0.05, ty, tz + lift)


def episode_blueprint(attempts: int = 0, active_document: str | None = None):  # -> rrb.Blueprint
    """The layout; ``active_document`` names the text tab shown first (default: the summary)."""
    import rerun.blueprint as rrb

    eye, target = eye_point()
    world = rrb.Spatial3DView(origin=WORLD, name="world",
                              eye_controls=rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=eye,
                                                             look_target=target, eye_up=(0.0, 0.0, 1.0)))
    docs = [rrb.TextDocumentView(origin=SUMMARY_PATH, name="summary")]
    docs += [rrb.TextDocumentView(origin=attempt_entity(k), name=f"attempt {k}")
             for k in range(1, max(ATTEMPT_TABS, attempts) + 1)]
    docs.append(rrb.TextDocumentView(origin=OTHER_TEXTS, name="other texts"))
    logs: list[rrb.View] = [rrb.TextLogView(origin=PRIMITIVE_LOG, name="primitives"),
                            rrb.TextLogView(origin=SAY_LOG, name="say"),
                            rrb.TextLogView(origin=PERCEPTION_LOG, name="perception")]  # rgbd mode: errors per view
    logs += [rrb.Spatial2DView(origin=f"{CAMERA}/{IMAGE_CAMERA}/{kind}", name=f"{IMAGE_CAMERA} {kind}")
             for kind in ("rgb", "depth")]
    layout = rrb.Horizontal(world, rrb.Vertical(rrb.Tabs(*docs, active_tab=active_document), rrb.Tabs(*logs),
                                                row_shares=[3, 1]),
                            column_shares=[3, 2])
    return rrb.Blueprint(layout, rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
                         rrb.TimePanel(timeline="primitive", state="collapsed"))


__all__ = ["ATTEMPT_TABS", "IMAGE_CAMERA", "OTHER_TEXTS", "SAY_LOG", "episode_blueprint", "eye_point"]
