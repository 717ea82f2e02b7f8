"""One ``.rrd`` file per episode, written without a viewer: :class:`RerunRecorder`.

What the file holds (entity paths are part of the format; :mod:`capmj.replay` reads them back):

``/world/table``                 static box of the workspace (table top at z = 0)
``/world/objects/obj<N>``        static shapes of object N in its body frame (boxes; bowls as floor
                                 disc + ring of wall boxes; balls as spheres; zones as flat boxes) and
                                 its ``Transform3D`` over time (``sim_time`` and ``primitive`` timelines)
``/world/robot``                 the arm as a polyline through its link origins (base ... suction), per frame
``/world/primitives/targets``    pick (yellow), place (blue) and final object position (green ok / red
                                 failed) of the latest primitive; ``.../path`` the pick->place arrow
``/camera/<name>/rgb|depth``     JPEG RGB and uint16-millimetre depth at each primitive (``--log-images``)
``/text/<path>``                 text documents: ``goal``, ``verdict`` and anything an agent sends
                                 (``llm/planner/prompt``, ``.../completion``, ``.../code``...);
                                 ``/text/primitives`` is a text log with one line per primitive
``/summary``                     static Markdown summary of the episode, written at :meth:`finish`
``/summary_json``                the same summary as JSON (``SUMMARY_SCHEMA``), parsed by replay

Timelines: ``sim_time`` (simulated seconds, kept monotonic across re-plan resets) and ``primitive``
(the index of the primitive; frames carry the index of the primitive being executed, so selecting
primitive k shows the world when primitive k ended, and the last index shows the final judged state).

Frames arrive every 25 physics steps; they are buffered and sent as columns (one ``send_columns``
per body) every 400 frames and at the end, and a body's pose is only re-sent when it changed
(fixed objects and resting blocks cost one row), which keeps logging cheap in time and bytes.

rerun is imported when a recorder is created, never by importing this module's package.
"""

from __future__ import annotations

import json
import math
import time as _time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

if TYPE_CHECKING:
    from capmj.sim.objects import ObjectSpec
    from capmj.sim.world import World

SUMMARY_PATH = "/summary"
SUMMARY_JSON_PATH = "/summary_json"
SUMMARY_SCHEMA = "capmj.episode-summary/1"
APPLICATION_ID = "capmj"
CAMERAS: tuple[str, ...] = ("front", "left", "right")
MARKDOWN_TEXTS = frozenset({"goal", "verdict"})
_FLUSH_FRAMES = 400          # frames buffered before a flush (20 s of simulated time)
_RESET_GAP_S = 0.05          # sim_time gap inserted where the world was reset (one frame period)
_POSE_EPS = 1e-5             # poses changing less than this (m / quaternion units) are not re-sent
_DEPTH_MAX_MM = 65535


def _u8(rgba: Sequence[float]) -> list[int]:
    return [int(round(255 * max(0.0, min(1.0, float(c))))) for c in rgba]


def _xyzw(q_wxyz: Sequence[float]) -> list[float]:
    w, x, y, z = (float(v) for v in q_wxyz)
    return [x, y, z, w]


def _jsonable(v: Any) -> Any:
    if isinstance(v, Mapping):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if v is None or isinstance(v, (str, int, float, bool)):
        return v
    return str(v)


def _is_object(body: str) -> bool:
    return body.startswith("obj") and body[3:].isdigit()


def text_entity(path: str) -> str:
    """The entity path of a text sent as ``recorder.text(path, ...)``: always under ``/text``."""
    p = "/".join(part for part in str(path).strip().split("/") if part)
    if p.startswith("text/"):
        p = p[len("text/"):]
    return "/text/" + (p or "untitled")


def _fmt(v: Any) -> str:
    if isinstance(v, (list, tuple)) and v and all(isinstance(x, (int, float)) for x in v):
        return "(" + ", ".join(f"{float(x):.3f}" for x in v) + ")"
    return "-" if v is None else str(v)


def summary_markdown(s: Mapping[str, Any]) -> str:
    """The Markdown rendering of a summary dict (what ``/summary`` holds and replay prints)."""
    verdict = "SUCCESS" if s.get("success") else "FAILURE"
    lines = [f"# {s.get('task')} — seed {s.get('seed')}", "",
             f"**{verdict}** (progress {float(s.get('progress') or 0):.2f}, reward {float(s.get('reward') or 0):.2f})",
             "",
             f"- agent: {s.get('agent')}" + (f" (model {s.get('model')})" if s.get("model") else ""),
             f"- goal: {s.get('goal') or '-'}",
             f"- primitives: {s.get('primitives')}  attempts: {s.get('attempts')}",
             f"- simulated: {float(s.get('sim_s') or 0):.2f} s  wall: {float(s.get('wall_s') or 0):.2f} s"]
    if s.get("error"):
        lines.append(f"- error: `{s['error']}`")
    diags = s.get("diagnostics") or []
    if diags:
        lines += ["", "## Diagnostics", ""] + [f"- {d}" for d in diags]
    prims = s.get("primitive_log") or []
    if prims:
        lines += ["", "## Primitives", "", "| # | attempt | status | object | pick | place | final |",
                  "|---|---|---|---|---|---|---|"]
        for p in prims:
            lines.append(f"| {p.get('index')} | {p.get('attempt')} | {p.get('status')} | {_fmt(p.get('obj_id'))} | "
                         f"{_fmt(p.get('pick'))} | {_fmt(p.get('place'))} | {_fmt(p.get('final_pos'))} |")
    llm = s.get("llm") or {}
    if llm:
        lines += ["", "## LLM calls", "", "```json", json.dumps(llm, indent=2, sort_keys=True), "```"]
    texts = s.get("texts") or {}
    if texts:
        lines += ["", "## Text documents", ""] + [f"- `{k}` ×{n}" for k, n in sorted(texts.items())]
    return "\n".join(lines) + "\n"


class RerunRecorder:
    """A :class:`capmj.record.Recorder` writing one ``.rrd`` file, no viewer needed.

    ``objects`` (the scene's :class:`ObjectSpec` tuple) gives the static shapes when the world is
    not attached; :meth:`attach` (done by :func:`capmj.log.record_episode`) gives exact shapes from
    the compiled MuJoCo model and enables camera images.  Call :meth:`finish` with the episode
    result to write the summary, then :meth:`close`.
    """

    def __init__(self, path: str | Path, *, task: str | None = None, seed: int | None = None,
                 agent: str | None = None, model: str | None = None, images: bool = False,
                 cameras: Sequence[str] = CAMERAS, objects: Sequence["ObjectSpec"] | None = None,
                 recording_id: str | None = None) -> None:
        import rerun as rr

        self._rr = rr
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.meta = {"task": task, "seed": seed, "agent": agent, "model": model}
        self.images = bool(images)
        self.cameras = tuple(cameras)
        rid = recording_id or f"{task}/{seed}/{agent}/{model or '-'}"
        self.rec = rr.RecordingStream(APPLICATION_ID, recording_id=rid)
        self.rec.set_log_time_enabled(False)  # wall-clock time would make files differ run to run
        self.rec.save(str(self.path))
        self._frames: list[tuple[float, int, Mapping[str, Any]]] = []
        self._bodies: set[str] = set()
        self._sent: dict[str, np.ndarray] = {}  # last pose sent per body (pos + quat)
        self._static_done: set[str] = set()
        self._offset = 0.0          # added to raw sim times after a world reset, to stay monotonic
        self._last_raw = -math.inf
        self._now = 0.0             # latest mapped sim time
        self._prim = 0              # primitives finished so far
        self._attached = False
        self._world: "World | None" = None
        self._rig: Any = None
        self._image_error: str | None = None
        self.primitive_log: list[dict[str, Any]] = []
        self.text_counts: dict[str, int] = {}
        self.images_logged = 0
        self.summary: dict[str, Any] | None = None
        self._closed = False
        self._log_static_table()
        if objects:
            self._log_objects_from_specs(objects)

    # ------------------------------------------------------------------ time
    def _map(self, t: float | None, *, frame: bool = False) -> float:
        """Episode time of a simulated time.  Only frames (which come from stepping the world) can
        reveal a reset; other events are placed at their time or, if that lies in the past of the
        log (a stale time, or a text logged right after a reset), at the latest logged time."""
        if t is None:
            return self._now
        t = float(t)
        if not frame:
            self._now = max(t + self._offset, self._now)
            return self._now
        if t < self._last_raw - 1e-9:  # the world was reset to its initial state (re-plan):
            self._offset += self._last_raw - t + _RESET_GAP_S  # continue the timeline after a small gap
        self._last_raw = t
        self._now = max(self._now, t + self._offset)
        return t + self._offset

    def _stamp(self, t: float) -> None:
        self.rec.set_time("sim_time", duration=t)
        self.rec.set_time("primitive", sequence=self._prim)

    # ------------------------------------------------------------------ static geometry
    def _log_static_table(self) -> None:
        rr = self._rr
        self.rec.log("/world/table", rr.Boxes3D(centers=[[0.5, 0.0, -0.0004]], half_sizes=[[0.25, 0.5, 0.0003]],
                                               colors=[[140, 128, 115]], fill_mode="solid"), static=True)
        self.rec.log("/world/floor", rr.Boxes3D(centers=[[0.4, 0.0, -0.002]], half_sizes=[[0.8, 0.9, 0.001]],
                                               colors=[[64, 64, 69]], fill_mode="solid"), static=True)
        self.rec.log("/world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)

    def _log_objects_from_specs(self, objects: Sequence["ObjectSpec"]) -> None:
        """Approximate shapes from the specs alone (used when no world is attached)."""
        from capmj.sim.palette import rgba

        rr = self._rr
        for o in objects:
            ent = f"/world/objects/{o.body}"
            if ent in self._static_done:
                continue
            col = _u8(rgba(o.color))
            hx, hy, hz = o.half_extents
            label = f"{o.color} {o.kind} {o.obj_id}"
            if o.kind == "bowl":
                self.rec.log(ent, rr.Cylinders3D(lengths=[2 * hz], radii=[hx], colors=[col], labels=[label]),
                             static=True)
            elif o.kind == "ball":
                self.rec.log(ent, rr.Ellipsoids3D(half_sizes=[[hx, hy, hz]], colors=[col], labels=[label],
                                                  fill_mode="solid"), static=True)
            else:
                self.rec.log(ent, rr.Boxes3D(half_sizes=[[hx, hy, hz]], colors=[col], labels=[label],
                                             fill_mode="solid"), static=True)
            self.rec.log(ent, rr.Transform3D(translation=list(o.pos),
                                             quaternion=rr.Quaternion(xyzw=[0, 0, math.sin(o.yaw / 2),
                                                                            math.cos(o.yaw / 2)])), static=False)
            self._static_done.add(ent)

    def _log_geoms(self, ent: str, model: Any, body_id: int, color: list[int] | None, label: str | None) -> bool:
        """Log the box/cylinder/sphere geoms of one body in its frame; False if it has none."""
        import mujoco

        rr = self._rr
        geoms = np.flatnonzero(model.geom_bodyid == body_id)
        boxes: dict[str, list] = {"c": [], "q": [], "h": [], "col": []}
        cyls: dict[str, list] = {"c": [], "q": [], "len": [], "r": [], "col": []}
        spheres: dict[str, list] = {"c": [], "h": [], "col": []}
        for g in geoms:
            gtype = int(model.geom_type[g])
            size = model.geom_size[g]
            pos = model.geom_pos[g].tolist()
            quat = _xyzw(model.geom_quat[g])
            col = color or _u8(model.geom_rgba[g])
            if gtype == mujoco.mjtGeom.mjGEOM_BOX:
                boxes["c"].append(pos), boxes["q"].append(quat), boxes["h"].append(size.tolist())
                boxes["col"].append(col)
            elif gtype == mujoco.mjtGeom.mjGEOM_CYLINDER:
                cyls["c"].append(pos), cyls["q"].append(quat), cyls["len"].append(2 * float(size[1]))
                cyls["r"].append(float(size[0])), cyls["col"].append(col)
            elif gtype == mujoco.mjtGeom.mjGEOM_SPHERE:
                spheres["c"].append(pos), spheres["h"].append([float(size[0])] * 3), spheres["col"].append(col)
        lab = {"labels": [label], "show_labels": False} if label else {}
        parts = []
        if boxes["c"]:
            parts.append(rr.Boxes3D(centers=boxes["c"], quaternions=[rr.Quaternion(xyzw=q) for q in boxes["q"]],
                                    half_sizes=boxes["h"], colors=boxes["col"], fill_mode="solid", **lab))
            lab = {}
        if cyls["c"]:
            parts.append(rr.Cylinders3D(centers=cyls["c"], quaternions=[rr.Quaternion(xyzw=q) for q in cyls["q"]],
                                        lengths=cyls["len"], radii=cyls["r"], colors=cyls["col"], fill_mode="solid",
                                        **lab))
            lab = {}
        if spheres["c"]:
            parts.append(rr.Ellipsoids3D(centers=spheres["c"], half_sizes=spheres["h"], colors=spheres["col"],
                                         fill_mode="solid", **lab))
        if not parts:
            return False
        self.rec.log(ent, *parts, static=True)
        return True

    def attach(self, world: "World") -> None:
        """Use the live world: exact object shapes, robot links, and camera images if enabled."""
        from capmj.sim.palette import rgba

        self._world = world
        self._attached = True
        m = world.model
        obj_bodies = set()
        for o in world.objects:
            obj_bodies.add(o.body)
            ent = f"/world/objects/{o.body}"
            if self._log_geoms(ent, m, m.body(o.body).id, _u8(rgba(o.color)), f"{o.color} {o.kind} {o.obj_id}"):
                self._static_done.add(ent)
        if not self._static_done.issuperset(f"/world/objects/{o.body}" for o in world.objects):
            self._log_objects_from_specs(world.objects)
        if self.images:
            self._log_images("initial")

    # ------------------------------------------------------------------ Recorder protocol
    def frame(self, time: float, poses: Mapping[str, tuple[tuple[float, ...], tuple[float, ...]]]) -> None:
        t = self._map(time, frame=True)
        label = self._prim + 1 if self._attached else self._prim
        self._frames.append((t, label, dict(poses)))
        if len(self._frames) >= _FLUSH_FRAMES:
            self._flush_frames()

    def _flush_frames(self, final_label: int | None = None) -> None:
        if not self._frames:
            return
        rr = self._rr
        frames, self._frames = self._frames, []
        names: list[str] = []
        for _, _, poses in frames:
            for n in poses:
                if n not in names:
                    names.append(n)
        objs = [n for n in names if _is_object(n)]
        robot = [n for n in names if not _is_object(n)]
        for n in objs:
            rows = self._changed_rows(n, [(t, lab, poses[n]) for t, lab, poses in frames if n in poses])
            if not rows:
                continue
            self.rec.send_columns(f"/world/objects/{n}", indexes=self._index(rows, final_label),
                                  columns=rr.Transform3D.columns(
                                      translation=np.array([r[2][0] for r in rows], dtype=np.float32),
                                      quaternion=np.array([_xyzw(r[2][1]) for r in rows], dtype=np.float32)))
        if robot:
            # The arm as one entity: a polyline through the link origins (base ... suction), in world.
            chain = [(t, lab, (tuple(c for n in robot for c in poses[n][0]), ())) for t, lab, poses in frames
                     if all(n in poses for n in robot)]
            rows = self._changed_rows("/robot", chain)
            if rows:
                k = len(robot)
                pts = np.array([r[2][0] for r in rows], dtype=np.float32).reshape(len(rows), k, 3)
                idx = self._index(rows, final_label)
                self.rec.send_columns("/world/robot", indexes=idx,
                                      columns=[*rr.LineStrips3D.columns(strips=list(pts)),
                                               *rr.Points3D.columns(positions=pts.reshape(-1, 3)).partition([k] * len(rows))])
            if "/world/robot" not in self._static_done:
                self.rec.log("/world/robot", rr.LineStrips3D.from_fields(radii=[0.02], colors=[[150, 160, 175]]),
                             rr.Points3D.from_fields(radii=[0.03], colors=[[110, 120, 135]],
                                                     labels=[", ".join(robot)], show_labels=False), static=True)
                self._static_done.add("/world/robot")

    def _changed_rows(self, key: str, rows: list) -> list:
        """The rows whose pose differs from the last one sent for ``key`` (latest-at fills the gaps)."""
        out = []
        last = self._sent.get(key)
        for t, lab, (pos, quat) in rows:
            cur = np.concatenate([np.asarray(pos, float).ravel(), np.asarray(quat, float).ravel()])
            if last is not None and last.shape == cur.shape and np.max(np.abs(cur - last)) < _POSE_EPS:
                continue
            last = cur
            out.append((t, lab, (pos, quat)))
        if last is not None:
            self._sent[key] = last
        self._bodies.add(key.lstrip("/"))
        return out

    def _index(self, rows: list, final_label: int | None) -> list:
        rr = self._rr
        labels = [r[1] if final_label is None else min(r[1], final_label) for r in rows]
        return [rr.TimeColumn("sim_time", duration=np.array([r[0] for r in rows], dtype=np.float64)),
                rr.TimeColumn("primitive", sequence=np.array(labels, dtype=np.int64))]

    def primitive(self, index: int, time: float, info: Mapping[str, Any]) -> None:
        rr = self._rr
        t = self._map(time)
        self._prim = int(index)
        self._stamp(t)
        rec = {"index": int(index), "time": t, **_jsonable(dict(info))}
        self.primitive_log.append(rec)
        pick = [float(v) for v in info.get("pick") or (0, 0, 0)]
        place = [float(v) for v in info.get("place") or (0, 0, 0)]
        ok = bool(info.get("ok", info.get("status") == "ok"))
        col = [60, 200, 90] if ok else [230, 60, 60]
        pts, cols, labels = [pick, place], [[255, 200, 40], [40, 160, 255]], [f"pick {index}", f"place {index}"]
        if info.get("final_pos") is not None:
            pts.append([float(v) for v in info["final_pos"]]), cols.append(col), labels.append(f"final {index}")
        self.rec.log("/world/primitives/targets", rr.Points3D(pts, radii=[0.008] * len(pts), colors=cols, labels=labels))
        self.rec.log("/world/primitives/path", rr.Arrows3D(origins=[pick], vectors=[np.subtract(place, pick).tolist()],
                                                            colors=[col], radii=[0.003]))
        line = (f"#{index} attempt {info.get('attempt', 0)}: {info.get('status')} obj {info.get('obj_id')} "
                f"pick {_fmt(pick)} -> place {_fmt(place)} final {_fmt(info.get('final_pos'))}"
                + (f" ({info['message']})" if info.get("message") else ""))
        self.rec.log("/text/primitives", rr.TextLog(line, level="INFO" if ok else "WARN"))
        if self.images:
            self._log_images(f"primitive {index}")

    def text(self, path: str, body: str, time: float | None = None) -> None:
        rr = self._rr
        t = self._map(time)
        self._stamp(t)
        ent = text_entity(path)
        key = ent[len("/text/"):]
        self.text_counts[key] = self.text_counts.get(key, 0) + 1
        media = rr.MediaType.MARKDOWN if key in MARKDOWN_TEXTS or key.endswith(".md") else rr.MediaType.TEXT
        self.rec.log(ent, rr.TextDocument(str(body), media_type=media))

    def image(self, path: str, rgb: np.ndarray, time: float | None = None) -> None:
        rr = self._rr
        self._stamp(self._map(time))
        arr = np.ascontiguousarray(np.asarray(rgb)[..., :3], dtype=np.uint8)
        self.rec.log(self._image_entity(path, "rgb"), rr.Image(arr).compress(jpeg_quality=90))
        self.images_logged += 1

    def depth(self, path: str, depth: np.ndarray, time: float | None = None) -> None:
        rr = self._rr
        self._stamp(self._map(time))
        d = np.asarray(depth, dtype=np.float64)
        mm = np.clip(np.nan_to_num(d * 1000.0, nan=0.0, posinf=_DEPTH_MAX_MM, neginf=0.0), 0, _DEPTH_MAX_MM)
        self.rec.log(self._image_entity(path, "depth"), rr.DepthImage(mm.astype(np.uint16), meter=1000.0))
        self.images_logged += 1

    @staticmethod
    def _image_entity(path: str, kind: str) -> str:
        p = "/".join(part for part in str(path).strip().split("/") if part)
        if p.startswith("camera/"):
            p = p[len("camera/"):]
        if not p.endswith("/" + kind) and p != kind:
            p = f"{p}/{kind}"
        return "/camera/" + p

    # ------------------------------------------------------------------ cameras
    def _log_images(self, when: str) -> None:
        if self._world is None or self._image_error is not None:
            return
        try:
            if self._rig is None:
                from capmj.sim.cameras import CameraRig

                self._rig = CameraRig(self._world)
            for name in self.cameras:
                fr = self._rig.render(name)
                rgb = fr["rgb"] if isinstance(fr, Mapping) else fr.rgb
                depth = fr["depth"] if isinstance(fr, Mapping) else fr.depth
                self.image(f"{name}/rgb", rgb)
                self.depth(f"{name}/depth", depth)
        except Exception as exc:  # noqa: BLE001 - images are optional; never fail the episode for them
            self._image_error = f"{type(exc).__name__}: {exc}"
            self.text("images", f"camera images disabled at {when}: {self._image_error}")

    # ------------------------------------------------------------------ summary and close
    def finish(self, result: Any) -> dict[str, Any]:
        """Write the episode summary (from an ``EpisodeResult`` or its dict) as Markdown and JSON."""
        rr = self._rr
        self._flush_frames(final_label=self._prim)
        res = result.to_dict() if hasattr(result, "to_dict") else dict(result or {})
        res.pop("calls", None)  # the LLM messages are logged under llm/ already (and kept in transcripts/)
        s: dict[str, Any] = {"schema": SUMMARY_SCHEMA}
        s.update({k: v for k, v in self.meta.items() if v is not None})
        s.update(_jsonable(res))
        s["primitive_log"] = self.primitive_log
        s["texts"] = dict(self.text_counts)
        s["images_logged"] = self.images_logged
        if self._image_error:
            s["image_error"] = self._image_error
        s["bodies"] = sorted(self._bodies)
        from capmj import __version__

        s["versions"] = {"capmj": __version__, "rerun": getattr(rr, "__version__", "?")}
        s["written_at"] = _time.strftime("%Y-%m-%dT%H:%M:%S%z")
        self.summary = s
        self.rec.log(SUMMARY_PATH, rr.TextDocument(summary_markdown(s), media_type=rr.MediaType.MARKDOWN), static=True)
        self.rec.log(SUMMARY_JSON_PATH, rr.TextDocument(json.dumps(s, sort_keys=True), media_type="application/json"),
                     static=True)
        return s

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._flush_frames(final_label=self._prim)
        try:
            from capmj.log.blueprint import episode_blueprint

            self.rec.send_blueprint(episode_blueprint(self.cameras if self.images_logged else (),
                                                      sorted(self.text_counts)), make_active=True, make_default=True)
        except Exception:  # noqa: BLE001 - a layout is a convenience; the data is already written
            pass
        rec, self.rec = self.rec, None
        rec.flush()
        rec.disconnect()
        # Drop the stream now: its writer/batcher threads live as long as the Python object, and the
        # recorder itself may linger in reference cycles (world <-> listeners) until the next GC.
        del rec
        if self._rig is not None and hasattr(self._rig, "close"):
            try:
                self._rig.close()
            except Exception:  # noqa: BLE001
                pass
        self._rig = None
        self._world = None

    def __enter__(self) -> "RerunRecorder":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
