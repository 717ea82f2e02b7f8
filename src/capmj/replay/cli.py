"""``python -m capmj.replay FILE.rrd``: what happened in one logged episode, from the file alone.

Prints the episode summary (task, seed, agent, verdict, diagnostics, primitives, LLM calls) that
:class:`capmj.log.RerunRecorder` stored at ``/summary_json``; when the summary is missing (an
episode killed before it ended) it falls back to the goal/verdict texts and the primitive log.
``--frames DIR`` writes every logged camera image as PNG (depth as 16-bit millimetres);
``--open`` starts the rerun viewer on the file.

Reading uses ``rerun.chunk.RrdReader`` offline: no viewer, no network.
"""

from __future__ import annotations

import argparse
import io
import json
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, Sequence

SUMMARY_JSON_PATH = "/summary_json"  # mirrors capmj.log.rerun_log (kept here to avoid importing it)
SUMMARY_PATH = "/summary"


class ReplayError(Exception):
    """The file is missing, unreadable, or not a capmj episode log."""


@dataclass
class LoggedImage:
    entity: str          # e.g. /camera/front/rgb
    kind: str            # "rgb" or "depth"
    primitive: int | None
    sim_time: float | None
    data: Any            # JPEG/PNG bytes for encoded images, numpy array for raw buffers
    media_type: str | None = None


@dataclass
class EpisodeLog:
    path: Path
    summary: dict[str, Any] | None
    texts: dict[str, list[str]] = field(default_factory=dict)       # /text/<key> -> documents in order
    primitive_lines: list[str] = field(default_factory=list)        # /text/primitives log lines
    entities: set[str] = field(default_factory=set)
    timelines: set[str] = field(default_factory=set)


def _chunks(path: Path) -> Iterator[Any]:
    if not path.is_file():
        raise ReplayError(f"no such file: {path}")
    import warnings

    try:
        from rerun.chunk import RrdReader

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            reader = RrdReader(str(path))
            yield from reader.stream().to_chunks()
    except ReplayError:
        raise
    except Exception as exc:  # noqa: BLE001 - rerun raises various errors for foreign/truncated files
        raise ReplayError(f"cannot read {path} as a rerun .rrd file: {type(exc).__name__}: {exc}") from exc


def _index_values(rb: Any, name: str) -> list[Any]:
    if name not in rb.schema.names:
        return [None] * rb.num_rows
    col = rb.column(name)
    if str(col.type).startswith("duration"):
        # pyarrow refuses nanosecond durations that are not whole microseconds as timedelta
        import pyarrow as pa

        return [None if v is None else v / 1e9 for v in col.cast(pa.int64()).to_pylist()]
    return col.to_pylist()


def _seconds(v: Any) -> float | None:
    if v is None:
        return None
    return v.total_seconds() if hasattr(v, "total_seconds") else float(v)


def read_episode(path: str | Path) -> EpisodeLog:
    """Summary, texts and primitive log of an episode ``.rrd`` (images are left out; see :func:`iter_images`)."""
    path = Path(path)
    summary: dict[str, Any] | None = None
    log = EpisodeLog(path, None)
    rows: list[tuple[float, str, str]] = []
    prim_rows: list[tuple[float, str]] = []
    for c in _chunks(path):
        ent = c.entity_path
        log.entities.add(ent)
        log.timelines.update(c.timeline_names)
        if ent == SUMMARY_JSON_PATH or ent.startswith("/text/"):
            rb = c.to_record_batch()
            if ent == SUMMARY_JSON_PATH and "TextDocument:text" in rb.schema.names:
                for texts in rb.column("TextDocument:text").to_pylist():
                    for t in texts or []:
                        try:
                            summary = json.loads(t)
                        except json.JSONDecodeError as exc:
                            raise ReplayError(f"{path}: the episode summary is not valid JSON ({exc})") from exc
            elif ent == "/text/primitives" and "TextLog:text" in rb.schema.names:
                times = _index_values(rb, "sim_time")
                for t, texts in zip(times, rb.column("TextLog:text").to_pylist()):
                    prim_rows.extend((_seconds(t) or 0.0, x) for x in texts or [])
            elif "TextDocument:text" in rb.schema.names:
                times = _index_values(rb, "sim_time")
                for t, texts in zip(times, rb.column("TextDocument:text").to_pylist()):
                    rows.extend((_seconds(t) or 0.0, ent[len("/text/"):], x) for x in texts or [])
    for _, key, body in sorted(rows, key=lambda r: r[0]):
        log.texts.setdefault(key, []).append(body)
    log.primitive_lines = [x for _, x in sorted(prim_rows, key=lambda r: r[0])]
    if summary is None and not log.entities - {"/__properties"}:
        raise ReplayError(f"{path} holds no recording data")
    log.summary = summary
    return log


def iter_images(path: str | Path) -> Iterator[LoggedImage]:
    """Every camera image logged in the file (``/camera/...``), in file order."""
    import numpy as np

    path = Path(path)
    for c in _chunks(path):
        ent = c.entity_path
        if not ent.startswith("/camera/"):
            continue
        rb = c.to_record_batch()
        names = rb.schema.names
        prims = _index_values(rb, "primitive")
        times = _index_values(rb, "sim_time")
        kind = "depth" if ent.endswith("depth") else "rgb"
        if "EncodedImage:blob" in names:
            media = _index_values(rb, "EncodedImage:media_type")
            for i, blobs in enumerate(rb.column("EncodedImage:blob").to_pylist()):
                for b in blobs or []:
                    mt = (media[i] or [None])[0] if media[i] is not None else None
                    yield LoggedImage(ent, kind, prims[i], _seconds(times[i]), bytes(b), mt)
        for comp in ("DepthImage", "Image"):
            if f"{comp}:buffer" not in names:
                continue
            fmts = rb.column(f"{comp}:format").to_pylist()
            for i, bufs in enumerate(rb.column(f"{comp}:buffer").to_pylist()):
                if not bufs:
                    continue
                fmt = fmts[i][0]
                raw = bytes(bufs[0])
                dtype = _channel_dtype(fmt.get("channel_datatype"))
                arr = np.frombuffer(raw, dtype=dtype)
                h, w = int(fmt["height"]), int(fmt["width"])
                chans = arr.size // (h * w) if h * w else 1
                arr = arr.reshape((h, w) if chans == 1 else (h, w, chans))
                yield LoggedImage(ent, "depth" if comp == "DepthImage" else kind, prims[i], _seconds(times[i]), arr)


_CHANNEL_DTYPES = {6: "uint8", 7: "int8", 8: "uint16", 9: "int16", 10: "uint32", 11: "int32", 12: "uint64",
                   13: "int64", 33: "float16", 34: "float32", 35: "float64"}
"""rerun's ``ChannelDatatype`` codes (as stored in ``ImageFormat.channel_datatype``) -> numpy dtype."""


def _channel_dtype(code: Any) -> Any:
    import numpy as np

    return np.dtype(_CHANNEL_DTYPES.get(int(code), "uint8") if code is not None else "uint8")


def export_frames(path: str | Path, out_dir: str | Path) -> list[Path]:
    """Write the file's camera images as PNG into ``out_dir``; returns the written paths."""
    import numpy as np
    from PIL import Image

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ReplayError(f"cannot create {out}: {exc.strerror or exc}") from exc
    written: list[Path] = []
    seen: dict[str, int] = {}
    for img in iter_images(path):
        cam = img.entity[len("/camera/"):].rsplit("/", 1)[0].replace("/", "_") or "camera"
        p = f"p{img.primitive:03d}" if img.primitive is not None else "static"
        stem = f"{cam}_{img.kind}_{p}"
        seen[stem] = seen.get(stem, 0) + 1
        if seen[stem] > 1:
            stem += f"_{seen[stem]}"
        target = out / f"{stem}.png"
        if isinstance(img.data, bytes):
            pil = Image.open(io.BytesIO(img.data))
            pil.load()
        else:
            arr = np.asarray(img.data)
            if arr.dtype == np.uint16:
                pil = Image.fromarray(arr if arr.ndim == 2 else arr[..., 0])  # 16-bit greyscale PNG
            elif arr.dtype.kind == "f":  # metres -> uint16 millimetres
                pil = Image.fromarray(np.clip(np.nan_to_num(arr * 1000), 0, 65535).astype(np.uint16))
            else:
                pil = Image.fromarray(arr.astype(np.uint8))
        pil.save(target, format="PNG")
        written.append(target)
    return written


def _fmt_summary(log: EpisodeLog) -> str:
    s = log.summary
    lines = [f"capmj episode log: {log.path}"]
    if s is None:
        lines.append("(no episode summary in the file: the episode was probably interrupted; showing what was logged)")
        for key in ("goal", "verdict"):
            if key in log.texts:
                lines.append(f"{key}: " + log.texts[key][-1].replace("\n", "\n  "))
        lines.append(f"primitives logged: {len(log.primitive_lines)}")
        lines += [f"  {x}" for x in log.primitive_lines]
        return "\n".join(lines)
    verdict = "SUCCESS" if s.get("success") else "FAILURE"
    model = f" (model {s['model']})" if s.get("model") else ""
    lines += [
        f"task:        {s.get('task')}",
        f"seed:        {s.get('seed')}",
        f"agent:       {s.get('agent')}{model}",
        f"verdict:     {verdict} (progress {float(s.get('progress') or 0):.2f}, reward {float(s.get('reward') or 0):.2f})",
        f"goal:        {s.get('goal') or '-'}",
    ]
    if s.get("error"):
        lines.append(f"error:       {s['error']}")
    diags = s.get("diagnostics") or []
    lines.append(f"diagnostics: {len(diags)}")
    lines += [f"  - {d}" for d in diags]
    lines.append(f"primitives:  {s.get('primitives')} (attempts {s.get('attempts')}, "
                 f"simulated {float(s.get('sim_s') or 0):.2f} s, wall {float(s.get('wall_s') or 0):.2f} s)")
    for p in s.get("primitive_log") or []:
        def f3(v: Any) -> str:
            return "-" if v is None else "(" + ", ".join(f"{float(x):.3f}" for x in v) + ")"
        lines.append(f"  #{p.get('index')} attempt {p.get('attempt')}: {p.get('status')} obj {p.get('obj_id')} "
                     f"pick {f3(p.get('pick'))} -> place {f3(p.get('place'))} final {f3(p.get('final_pos'))}"
                     + (f" ({p['message']})" if p.get("message") else ""))
    llm = s.get("llm") or {}
    if llm:
        lines.append("LLM calls:")
        lines += ["  " + ln for ln in json.dumps(llm, indent=2, sort_keys=True).splitlines()]
    else:
        lines.append("LLM calls:   none")
    texts = s.get("texts") or {}
    other = {k: n for k, n in texts.items() if k not in ("goal", "verdict")}
    if other:
        lines.append("text documents: " + ", ".join(f"/text/{k} x{n}" for k, n in sorted(other.items())))
    if s.get("images_logged"):
        lines.append(f"camera images: {s['images_logged']}")
    if s.get("image_error"):
        lines.append(f"camera images failed: {s['image_error']}")
    return "\n".join(lines)


def open_viewer(path: str | Path) -> int:
    """Start the rerun viewer on ``path`` (blocks until it is closed); 1 with a message if unavailable."""
    exe = shutil.which("rerun")
    if exe is None:
        print(f"capmj-replay: the rerun viewer is not on PATH (it comes with `pip install rerun-sdk==0.41.*`); "
              f"alternatively drop {path} into https://app.rerun.io", file=sys.stderr)
        return 1
    try:
        return subprocess.call([exe, str(path)])
    except OSError as exc:
        print(f"capmj-replay: could not start the rerun viewer ({exe}): {exc}", file=sys.stderr)
        return 1


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m capmj.replay",
        description="Print the summary of a logged capmj episode (.rrd), export its camera frames, or open it.",
        epilog="examples:\n"
               "  python -m capmj.replay runs/x/rrd/stack-all-blocks-on-a-zone/10001-oracle.rrd\n"
               "  python -m capmj.replay EP.rrd --json            # the summary as JSON\n"
               "  python -m capmj.replay EP.rrd --frames frames/  # camera images as PNG\n"
               "  python -m capmj.replay EP.rrd --open            # rerun viewer",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", type=Path, help="an episode .rrd written by capmj (python -m capmj.bench)")
    p.add_argument("--json", action="store_true", help="print the summary JSON instead of the text report")
    p.add_argument("--texts", action="store_true", help="also print every text document (prompts, code...)")
    p.add_argument("--frames", type=Path, metavar="DIR", help="export the logged camera images to DIR as PNG")
    p.add_argument("--open", action="store_true", help="open the file in the rerun viewer")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        log = read_episode(args.file)
        if args.json:
            print(json.dumps(log.summary, indent=2, sort_keys=True))
        else:
            print(_fmt_summary(log))
        if args.texts:
            for key, docs in sorted(log.texts.items()):
                for i, body in enumerate(docs):
                    print(f"\n----- /text/{key}" + (f" [{i + 1}]" if len(docs) > 1 else "") + " -----")
                    print(body)
        if args.frames is not None:
            written = export_frames(args.file, args.frames)
            if written:
                print(f"wrote {len(written)} PNG frames to {args.frames}")
            else:
                print(f"no camera images in {args.file} (record with python -m capmj.bench --log-images)")
    except ReplayError as exc:
        print(f"capmj-replay: error: {exc}", file=sys.stderr)
        return 2
    if args.open:
        return open_viewer(args.file)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
