"""Entity paths of an episode ``.rrd``: the file format, in one place (no rerun import here, so
:mod:`capmj.replay` can read the names without loading the writer).

``/world/table``, ``/world/floor``      static boxes (table top at z = 0)
``/world/objects/obj<N>``               static shape of object N in its body frame + ``Transform3D``
                                        over time; ``.../verdict`` the failing-object outline and
                                        diagnostic label (static, follows the object)
``/world/robot/<link>``                 static UR5e visual mesh of the link in its body frame +
                                        ``Transform3D`` over time; links rigidly fixed to another
                                        link are its children with a static transform
                                        (``/world/robot/wrist_3_link/suction``); ``.../suction/cup``
                                        the cup cylinder (to the tip), coloured while gripping
``/world/primitives/<k>``               pick (yellow) / place (blue) points and the pick->place arrow of
                                        primitive k, from its start on; ``.../final`` where the moved
                                        object ended, green when its goal condition holds at the end
                                        ``.../planned`` the tool's path (violet lines) of each move of
                                        the primitive that was planned around an obstacle
``/world/perception/detections``        rgbd mode: the planner API's objects after each perception
                                        call (the latest shown), boxes labelled with name and
                                        confidence, green right / orange wrong / red false
``/world/verdict``                      arrows from failing objects to where the task wants them and
                                        the target outlines (from the end of the episode on)
``/camera/<name>/rgb|depth``            camera images (``--log-images``)
``/text/<path>``                        texts as sent by agents (``llm/attempt1/planner/1/code``...);
                                        ``/text/primitives`` and ``/text/planner/say`` are text logs;
                                        ``/text/perception`` one line of errors per perception call
``/attempts/<k>``                       static Markdown of LLM attempt k in reading order
``/summary``, ``/summary_json``         static episode summary (Markdown, JSON ``SUMMARY_SCHEMA``)
"""

from __future__ import annotations

SUMMARY_PATH = "/summary"
SUMMARY_JSON_PATH = "/summary_json"
SUMMARY_SCHEMA = "capmj.episode-summary/1"
WORLD = "/world"
OBJECTS = "/world/objects"
ROBOT = "/world/robot"
PRIMITIVES = "/world/primitives"
VERDICT = "/world/verdict"
PERCEPTION = "/world/perception"
DETECTIONS = f"{PERCEPTION}/detections"
CAMERA = "/camera"
TEXT = "/text"
PRIMITIVE_LOG = "/text/primitives"
PERCEPTION_LOG = "/text/perception"
ATTEMPTS = "/attempts"
LOG_TEXTS = frozenset({"primitives", "planner/say"})
"""Text keys logged as ``TextLog`` lines (one entry per event) instead of documents."""
STATIC_TEXTS = frozenset({"goal", "verdict"})
"""Text keys that hold for the whole episode and are logged static (no "(empty)" before the end)."""


def object_entity(body: str) -> str:
    return f"{OBJECTS}/{body}"


def text_entity(path: str) -> str:
    """The entity path of a text sent as ``recorder.text(path, ...)``: always under ``/text``."""
    p = "/".join(part for part in str(path).strip().split("/") if part)
    if p.startswith("text/"):
        p = p[len("text/"):]
    return f"{TEXT}/" + (p or "untitled")


def attempt_entity(k: int) -> str:
    return f"{ATTEMPTS}/{k}"


__all__ = [
    "ATTEMPTS", "CAMERA", "DETECTIONS", "LOG_TEXTS", "OBJECTS", "PERCEPTION", "PERCEPTION_LOG", "PRIMITIVES",
    "PRIMITIVE_LOG", "ROBOT", "STATIC_TEXTS",
    "SUMMARY_JSON_PATH", "SUMMARY_PATH", "SUMMARY_SCHEMA", "TEXT", "VERDICT", "WORLD", "attempt_entity",
    "object_entity", "text_entity",
]
