"""One ``.rrd`` file per episode, written without a viewer: :class:`RerunRecorder`.

The entity paths are listed in :mod:`capmj.log.paths`.  Timelines: ``sim_time`` (simulated seconds,
kept monotonic across re-plan resets) and ``primitive`` (frames carry the index of the primitive
being executed, so selecting primitive k shows the world when primitive k ended, and the last
index shows the final judged state).

Frames arrive every 25 physics steps (20 Hz); every other one is kept (see ``KEEP_EVERY``), they
are buffered as arrays (:mod:`capmj.log.poses`) and sent as columns (one ``send_columns`` per
body) at the end, and a body's pose is only re-sent when it changed (resting blocks cost one row; fixed objects have a static
transform), which keeps logging cheap in time and bytes.  Meshes and shapes are static and logged
once; only transforms change over time.

What the episode's end decides (the verdict in 3D, the colour of each primitive's "final" marker,
the per-attempt documents, the summary) is written by :meth:`RerunRecorder.finish`.
"""

from __future__ import annotations

import json
import os
import sys
import time as _time
from datetime import timedelta
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

from capmj import __version__
from capmj.log import geometry as G
from capmj.log.clock import EpisodeClock
from capmj.log.images import SceneCameras, depth_mm, image_entity
from capmj.log.paths import (LOG_TEXTS, OBJECTS, PRIMITIVE_LOG, PRIMITIVES, ROBOT, STATIC_TEXTS, SUMMARY_JSON_PATH,
                             SUMMARY_PATH, SUMMARY_SCHEMA, attempt_entity, text_entity)
from capmj.log.poses import PoseBuffer, changed_rows
from capmj.log.summary import fmt_vec, jsonable, summary_markdown
from capmj.sim.cameras import VIEW_CAMERAS
from capmj.sim.pose import xyzw

if TYPE_CHECKING:
    from capmj.record import PerceivedBox
    from capmj.records.perception import PerceptionCall
    from capmj.sim.objects import ObjectSpec
    from capmj.sim.world import World

APPLICATION_ID = "capmj"
CAMERAS: tuple[str, ...] = VIEW_CAMERAS
MARKDOWN_TEXTS = frozenset({"goal", "verdict"})
PICK_COLOR, PLACE_COLOR, PATH_COLOR, FAILED_PATH_COLOR = [255, 210, 0], [40, 150, 255], [200, 200, 200], [230, 60, 60]
PLANNED_PATH_COLOR = [170, 90, 255]
"""The tool's path of a move planned around an obstacle (``/world/primitives/<k>/planned``)."""
_FLUSH_FRAMES = 4000         # frames buffered before a flush (200 s of simulated time)
KEEP_EVERY = 2
"""Every KEEP_EVERY-th frame is written (10 Hz of simulated time), plus the last frame of each
primitive and of the episode and the first after a reset: the robot's link transforms are most
of a log's bytes."""
_XYZW = [4, 5, 6, 3]          # the quaternion of a [x, y, z, qw, qx, qy, qz] pose in rerun's order


def _is_object(body: str) -> bool:
    return body.startswith("obj") and body[3:].isdigit()


class RerunRecorder:
    """A :class:`capmj.record.Recorder` writing one ``.rrd`` file, no viewer needed.

    ``objects`` (the scene's :class:`ObjectSpec` tuple) gives the static shapes when the world is
    not attached; :meth:`attach` (done by the runner) gives exact shapes, the robot's meshes, grip
    state and camera images.  ``goals`` (the task's oracle goals) tell where failing objects should
    be.  Call :meth:`finish` with the episode result to write the verdict and summary, then
    :meth:`close`.
    """

    def __init__(self, path: str | Path, *, task: str | None = None, seed: int | None = None,
                 agent: str | None = None, model: str | None = None, images: bool = False,
                 cameras: Sequence[str] = CAMERAS, objects: Sequence["ObjectSpec"] | None = None,
                 goals: Sequence[Any] = (), recording_id: str | None = None) -> None:
        if "rerun" not in sys.modules:  # hush the SDK's per-file warning about the footer we leave out
            os.environ.setdefault("RUST_LOG", "warn,re_log_encoding::rrd::file_sink=error")
        import rerun as rr

        self._rr = rr
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.meta = {"task": task, "seed": seed, "agent": agent, "model": model}
        self.images = bool(images)
        self.cameras = tuple(cameras)
        self.goals = tuple(goals)
        rid = recording_id or f"{task}/{seed}/{agent}/{model or '-'}"
        # Batch each entity's rows of the whole episode into one chunk: every chunk carries its
        # schema (~0.5 kB per component), which would otherwise outweigh the data.
        batching = rr.ChunkBatcherConfig(flush_tick=timedelta(hours=1), flush_num_bytes=8 << 20,
                                         flush_num_rows=1 << 20, chunk_max_rows_if_unsorted=1 << 20)
        self.rec = rr.RecordingStream(APPLICATION_ID, recording_id=rid, batcher_config=batching)
        self.rec.set_log_time_enabled(False)  # wall-clock time would make files differ run to run
        # No footer: the manifest is for random access into large recordings and would double a
        # small episode log (measured 369 kB -> 200 kB); viewers and RrdReader read the stream.
        self.rec.save(str(self.path), write_footer=False)
        self._poses = PoseBuffer()
        self._bodies: set[str] = set()
        self._sent: dict[str, np.ndarray] = {}  # last pose sent per body (pos + quat)
        self._objects: dict[int, "ObjectSpec"] = {o.obj_id: o for o in objects or ()}
        self._clock = EpisodeClock()
        self._prim = 0              # primitives finished so far
        self._next_start: float | None = None  # time of the first frame after the latest primitive
        self._held_id: int | None = None  # the gripped object, and its label (the cup shows it)
        self._held: str | None = None
        self._links: dict[str, str] = {}  # robot body -> entity path (after attach)
        self._static_bodies: set[str] = set()  # bodies with a static transform (fixed objects)
        self._frame_no = 0
        self._attached = False
        self._world: "World | None" = None
        self._cameras: SceneCameras | None = None
        self._image_error: str | None = None
        self._texts: list[tuple[str, str]] = []  # (key, body) of documents, in arrival order
        self.primitive_log: list[dict[str, Any]] = []
        self.text_counts: dict[str, int] = {}
        self.images_logged = 0
        self.perception_views = 0
        self.summary: dict[str, Any] | None = None
        self._documents_written = False
        self._closed = False
        G.log_table(rr, self.rec)
        if objects:
            G.log_object_specs(rr, self.rec, objects)

    # ------------------------------------------------------------------ time
    def _stamp(self, t: float, prim: int | None = None) -> None:
        self.rec.set_time("sim_time", duration=t)
        self.rec.set_time("primitive", sequence=self._prim if prim is None else prim)

    # ------------------------------------------------------------------ Recorder protocol
    def attach(self, world: "World") -> None:
        """Use the live world: exact object shapes, robot meshes, grip state, camera images."""
        rr = self._rr
        self._world = world
        self._attached = True
        self._objects.update({o.obj_id: o for o in world.objects})
        G.log_world_objects(rr, self.rec, world)
        fixed = [o.body for o in world.objects if o.fixed]  # they never move: one static transform each
        for body, pos, quat in zip(fixed, *world.body_poses(world.body_index(fixed))):
            self._static_bodies.add(body)
            self._sent[body] = np.concatenate([pos, quat])
            self.rec.log(f"{OBJECTS}/{body}", rr.Transform3D(
                translation=pos.tolist(), quaternion=rr.Quaternion(xyzw=xyzw(quat))), static=True)
        self._links = G.robot_entities(world, world.link_names)
        G.log_robot(rr, self.rec, world, self._links)
        self._stamp(self._clock.now)
        G.cup_color(rr, self.rec, world, self._links, None)
        if self.images:
            self._cameras = SceneCameras(world, self.cameras)
            self._log_images("initial")

    def frame(self, time: float, poses: Mapping[str, tuple[tuple[float, ...], tuple[float, ...]]]) -> None:
        names = tuple(poses)
        self.frame_arrays(time, names, np.array([poses[n][0] for n in names], dtype=float).reshape(-1, 3),
                          np.array([poses[n][1] for n in names], dtype=float).reshape(-1, 4))

    def frame_arrays(self, time: float, names: tuple[str, ...], pos: np.ndarray, quat: np.ndarray) -> None:
        """:meth:`frame` with the poses as arrays, as they are buffered (:class:`capmj.record.ArrayFrames`)."""
        t, reset = self._clock.frame(time)  # the first frame after a reset is always kept
        label = self._prim + 1 if self._attached else self._prim
        if self._next_start is None:
            self._next_start = t
        self._frame_no += 1
        self._poses.add(t, label, names, pos, quat, reset or (self._frame_no - 1) % KEEP_EVERY == 0)
        if self._world is not None:
            held_id = self._world.suction.held
            if held_id != self._held_id:  # the label only changes with the gripped object
                held = None if held_id is None else G.object_label(self._world.objects_by_id[held_id])
                self._held_id = held_id
                if held != self._held:
                    self._held = held
                    self._stamp(t, label)
                    G.cup_color(self._rr, self.rec, self._world, self._links, held)
        if len(self._poses) >= _FLUSH_FRAMES:
            self._flush_frames()

    def _flush_frames(self, final_label: int | None = None) -> None:
        table = self._poses.take()
        if table is None:
            return
        rr = self._rr
        bodies, entities = [], []  # the bodies with a transform over time, and their entities
        for b, n in enumerate(table.names):
            ent = f"{OBJECTS}/{n}" if _is_object(n) else f"{ROBOT}/{n}"
            if self._links.get(n, ent) == ent and n not in self._static_bodies:  # not nested in a link, not fixed
                bodies.append(b)
                entities.append(ent)
        names = [table.names[b] for b in bodies]
        poses, present = table.poses[:, bodies], table.present[:, bodies]
        last = np.array([self._sent.get(n, np.zeros(7)) for n in names]).reshape(-1, 7)
        keep, last, sent = changed_rows(poses, present, last, np.array([n in self._sent for n in names], dtype=bool))
        labels = table.labels if final_label is None else np.minimum(table.labels, final_label)
        for j, (n, ent) in enumerate(zip(names, entities)):
            if sent[j]:
                self._sent[n] = last[j]
            self._bodies.add(n)
            rows = np.flatnonzero(keep[:, j])
            if not len(rows):
                continue
            pose = poses[rows, j]
            self.rec.send_columns(ent, indexes=[rr.TimeColumn("sim_time", duration=table.times[rows]),
                                                rr.TimeColumn("primitive", sequence=labels[rows])],
                                  columns=rr.Transform3D.columns(translation=pose[:, :3].astype(np.float32),
                                                                 quaternion=pose[:, _XYZW].astype(np.float32)))

    def primitive(self, index: int, time: float, info: Mapping[str, Any]) -> None:
        """Log the primitive's pick/place markers on their own entity at the time it started (so
        they stay visible from then on) and a line in the primitive log at its end."""
        rr = self._rr
        t = self._clock.event(time)
        start = self._next_start if self._next_start is not None and self._next_start <= t else t
        self._next_start = None
        self._poses.keep_last()  # the state at the end of a primitive is always kept
        self._prim = int(index)
        rec = {"index": int(index), "time": t, "start": start, **jsonable(dict(info))}
        self.primitive_log.append(rec)
        pick = [float(v) for v in info.get("pick") or (0, 0, 0)]
        place = [float(v) for v in info.get("place") or (0, 0, 0)]
        ok = bool(info.get("ok", info.get("status") == "ok"))
        self._stamp(start, index)
        ent = f"{PRIMITIVES}/{index}"
        self.rec.log(ent, rr.Points3D([pick, place], colors=[PICK_COLOR, PLACE_COLOR]),
                     rr.Arrows3D(origins=[pick], vectors=[np.subtract(place, pick).tolist()],
                                 colors=[PATH_COLOR if ok else FAILED_PATH_COLOR], labels=[f"#{index}"]))
        planned = [np.asarray(line, dtype=np.float32) for line in info.get("planned") or () if len(line) > 1]
        if planned:  # the tool's path of each move planned around an obstacle
            self.rec.log(f"{ent}/planned", rr.LineStrips3D(planned, colors=[PLANNED_PATH_COLOR]))
        self._stamp(t, index)
        line = (f"#{index} attempt {info.get('attempt', 0)}: {info.get('status')} obj {info.get('obj_id')} "
                f"pick {fmt_vec(pick)} -> place {fmt_vec(place)} final {fmt_vec(info.get('final_pos'))}"
                + (f" ({info['message']})" if info.get("message") else ""))
        self.rec.log(PRIMITIVE_LOG, rr.TextLog(line, level="INFO" if ok else "WARN"))
        if self.images:
            self._log_images(f"primitive {index}")

    def text(self, path: str, body: str, time: float | None = None) -> None:
        rr = self._rr
        t = self._clock.event(time)
        self._stamp(t)
        ent = text_entity(path)
        key = ent[len("/text/"):]
        self.text_counts[key] = self.text_counts.get(key, 0) + 1
        if key in LOG_TEXTS:
            self.rec.log(ent, rr.TextLog(str(body)))
            return
        media = rr.MediaType.MARKDOWN if key in MARKDOWN_TEXTS or key.endswith(".md") else rr.MediaType.TEXT
        self.rec.log(ent, rr.TextDocument(str(body), media_type=media), static=key in STATIC_TEXTS)
        if key not in STATIC_TEXTS:
            self._texts.append((key, str(body)))

    def image(self, path: str, rgb: np.ndarray, time: float | None = None) -> None:
        self._stamp(self._clock.event(time))
        arr = np.ascontiguousarray(np.asarray(rgb)[..., :3], dtype=np.uint8)
        self.rec.log(image_entity(path, "rgb"), self._rr.Image(arr).compress(jpeg_quality=90))
        self.images_logged += 1

    def depth(self, path: str, depth: np.ndarray, time: float | None = None) -> None:
        self._stamp(self._clock.event(time))
        self.rec.log(image_entity(path, "depth"), self._rr.DepthImage(depth_mm(depth), meter=1000.0))
        self.images_logged += 1

    def perception(self, time: float, call: "PerceptionCall", boxes: Sequence["PerceivedBox"]) -> None:
        """A perception view (:class:`capmj.record.PerceptionViews`): :mod:`capmj.log.perception3d`."""
        from capmj.log.perception3d import log_perception

        self._stamp(self._clock.event(time))
        log_perception(self._rr, self.rec, call, boxes)
        self.perception_views += 1

    def _log_images(self, when: str) -> None:
        if self._cameras is not None and not self._cameras.log(self.image, self.depth) and not self._image_error:
            self._image_error = self._cameras.error
            self.text("images", f"camera images disabled at {when}: {self._image_error}")

    # ------------------------------------------------------------------ end of episode
    def _final_positions(self) -> dict[int, np.ndarray]:
        return {i: self._sent[o.body][:3].copy() for i, o in self._objects.items() if o.body in self._sent}

    def _log_verdict(self, success: bool, diagnostics: Sequence[str]) -> dict[str, Any]:
        """The verdict in 3D (at the end of the timeline) and each primitive's final marker."""
        from capmj.log.verdict3d import NEUTRAL_COLOR, FAIL_COLOR, OK_COLOR, log_verdict, verdict_view

        rr = self._rr
        kinds = {i: o.kind for i, o in self._objects.items()}
        view = verdict_view(success, diagnostics, kinds, self.goals)
        self._stamp(self._clock.now)
        arrows = log_verdict(rr, self.rec, view, self._objects, self._final_positions(), self.goals)
        for p in self.primitive_log:
            if p.get("final_pos") is None:
                continue
            holds = view.holds(p.get("obj_id"))
            col = NEUTRAL_COLOR if holds is None else OK_COLOR if holds else FAIL_COLOR
            oid = p.get("obj_id")
            o = self._objects.get(oid) if oid is not None else None
            half = list(o.half_extents) if o is not None else [0.01, 0.01, 0.01]
            self._stamp(p["time"], p["index"])
            self.rec.log(f"{PRIMITIVES}/{p['index']}/final",
                         rr.Boxes3D(centers=[p["final_pos"]], half_sizes=[half], colors=[col]))  # wireframe
        return {"failing_objects": sorted(view.failing), "named_objects": list(view.named), "verdict_arrows": arrows}

    def _write_documents(self) -> int:
        """The per-attempt Markdown documents (static) and the other texts; returns the attempts."""
        from capmj.log.attempts import attempt_markdown, other_markdown, split_attempts
        from capmj.log.blueprint import OTHER_TEXTS

        rr = self._rr
        self._documents_written = True
        attempts, other = split_attempts(self._texts)
        for k, parts in sorted(attempts.items()):
            self.rec.log(attempt_entity(k), rr.TextDocument(attempt_markdown(k, parts), media_type=rr.MediaType.MARKDOWN),
                         static=True)
        if other:
            self.rec.log(OTHER_TEXTS, rr.TextDocument(other_markdown(other), media_type=rr.MediaType.MARKDOWN),
                         static=True)
        return max(attempts, default=0)

    def finish(self, result: Any) -> dict[str, Any]:
        """Write the verdict in 3D, the per-attempt documents and the episode summary (Markdown and
        JSON) from an ``EpisodeResult`` or its dict."""
        rr = self._rr
        self._flush_frames(final_label=self._prim)
        res = result.to_dict() if hasattr(result, "to_dict") else dict(result or {})
        res.pop("calls", None)  # the LLM messages are logged under llm/ already (and kept in transcripts/)
        s: dict[str, Any] = {"schema": SUMMARY_SCHEMA}
        s.update({k: v for k, v in self.meta.items() if v is not None})
        s.update(jsonable(res))
        s.update(self._log_verdict(bool(res.get("success")), list(res.get("diagnostics") or ())))
        s["attempt_documents"] = self._write_documents()
        s["primitive_log"] = self.primitive_log
        s["texts"] = dict(self.text_counts)
        s["images_logged"] = self.images_logged
        if self.perception_views:
            s["perception_views"] = self.perception_views
        if self._image_error:
            s["image_error"] = self._image_error
        s["bodies"] = sorted(self._bodies | self._static_bodies)
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
        attempts = (self.summary or {}).get("attempt_documents", 0)
        try:
            if not self._documents_written:  # an episode that ended without finish(): keep its texts readable
                attempts = self._write_documents()
            from capmj.log.blueprint import episode_blueprint

            self.rec.send_blueprint(episode_blueprint(attempts), make_active=True, make_default=True)
        except Exception:  # noqa: BLE001 - a layout is a convenience; the data is already written
            pass
        rec = self.rec
        del self.rec  # a closed recorder has no stream (using it raises AttributeError)
        rec.flush()
        rec.disconnect()
        # Drop the stream now: its writer/batcher threads live as long as the Python object, and the
        # recorder itself may linger in reference cycles (world <-> listeners) until the next GC.
        del rec
        if self._cameras is not None:
            self._cameras.close()
        self._cameras = None
        self._world = None

    def __enter__(self) -> "RerunRecorder":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


__all__ = ["APPLICATION_ID", "CAMERAS", "RerunRecorder"]
