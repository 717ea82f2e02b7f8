"""What the robot perceived, drawn beside the true objects (``--perception rgbd`` episodes).

After every perception call (the first view and one after each pick-and-place) the planner API's
objects arrive as :class:`capmj.record.PerceivedBox` records, already judged against the truth
by :mod:`capmj.agents.api.perception_audit`.  They are drawn as one ``Boxes3D`` at
:data:`~capmj.log.paths.DETECTIONS` at the call's time, so at any point of the timeline the
viewer shows the view the plan was acting on, in the same space as the true objects
(``/world/objects``): a box offset from its object is a position error, a red box is a false
detection, a true object without a box was missed.  The call's figures (the
:class:`~capmj.records.PerceptionCall` of the episode's record) go to a text log line, so the
numbers in ``episodes.jsonl`` can be read next to the picture that produced them.
"""

from __future__ import annotations

from typing import Any, Sequence

from capmj.log.paths import DETECTIONS, PERCEPTION_LOG
from capmj.record import MatchStatus, PerceivedBox
from capmj.records.perception import PerceptionCall
from capmj.sim.pose import xyzw, yaw_quat

MATCH_COLORS: dict[MatchStatus, list[int]] = {"right": [60, 210, 90], "wrong": [255, 160, 0], "false": [255, 40, 40]}
"""Box colour by :data:`capmj.record.MatchStatus` (the verdict's green and red, the target orange)."""
BOX_RADIUS = 0.0015
"""Line width (m) of the wireframe boxes: thin enough to see the true object inside."""


def box_label(b: PerceivedBox) -> str:
    """``<planner name> <confidence>`` (and ``hidden`` for a block kept under a tower)."""
    return f"{b.name} {b.confidence:.2f}" + ("" if b.visible else " hidden")


def error_line(call: PerceptionCall) -> str:
    """The call's figures in one line (millimetres and degrees, as in ``episodes.jsonl``)."""
    def num(v: float | None, unit: str) -> str:
        return "-" if v is None else f"{v:.1f} {unit}"

    return (f"attempt {call.attempt} {call.stage}: {call.detections} detections of {call.objects} objects, "
            f"missed {call.missed}, false {call.false_detections}, errors kind {call.kind_errors} "
            f"colour {call.color_errors} size {call.size_errors}, position median {num(call.median_pos_mm, 'mm')} "
            f"max {num(call.max_pos_mm, 'mm')}, yaw max {num(call.max_yaw_deg, 'deg')}"
            + ("" if call.max_slot_mm is None else f", fixture slot max {num(call.max_slot_mm, 'mm')}"))


def log_perception(rr: Any, rec: Any, call: PerceptionCall, boxes: Sequence[PerceivedBox]) -> None:
    """Draw one perception view at the stream's current time (see the module docstring)."""
    rec.log(DETECTIONS, rr.Boxes3D(
        centers=[list(b.center) for b in boxes], half_sizes=[list(b.half_size) for b in boxes],
        quaternions=[rr.Quaternion(xyzw=xyzw(yaw_quat(b.yaw))) for b in boxes],
        colors=[MATCH_COLORS[b.match] for b in boxes], labels=[box_label(b) for b in boxes],
        radii=[BOX_RADIUS]))
    rec.log(PERCEPTION_LOG, rr.TextLog(error_line(call), level="WARN" if call.erred else "INFO"))


__all__ = ["BOX_RADIUS", "MATCH_COLORS", "box_label", "error_line", "log_perception"]
