"""Reading an episode ``.rrd`` offline (``rerun.chunk.RrdReader``): no viewer, no network."""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from capmj.log.paths import ATTEMPTS, CAMERA, SUMMARY_JSON_PATH, TEXT


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
    texts: dict[str, list[str]] = field(default_factory=dict)       # /text/<key> documents in time order
    logs: dict[str, list[str]] = field(default_factory=dict)        # /text/<key> text-log lines in time order
    attempts: dict[str, str] = field(default_factory=dict)          # /attempts/<k> Markdown documents
    entities: set[str] = field(default_factory=set)
    timelines: set[str] = field(default_factory=set)

    @property
    def primitive_lines(self) -> list[str]:
        return self.logs.get("primitives", [])


def iter_chunks(path: Path) -> Iterator[Any]:
    """The rerun chunks of an ``.rrd`` file in stream order; a missing or unreadable file is a
    :class:`ReplayError` saying so."""
    if not path.is_file():
        raise ReplayError(f"no such file: {path}")
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


def index_values(rb: Any, name: str) -> list[Any]:
    """A time column as Python values (durations in seconds); Nones when the chunk lacks it."""
    if name not in rb.schema.names:
        return [None] * rb.num_rows
    col = rb.column(name)
    if str(col.type).startswith("duration"):
        # pyarrow refuses nanosecond durations that are not whole microseconds as timedelta
        import pyarrow as pa

        return [None if v is None else v / 1e9 for v in col.cast(pa.int64()).to_pylist()]
    return col.to_pylist()


def read_episode(path: str | Path) -> EpisodeLog:
    """Summary, texts, text logs and attempt documents of an episode ``.rrd`` (images are left
    out; see :func:`iter_images`)."""
    path = Path(path)
    log = EpisodeLog(path, None)
    docs: list[tuple[float, str, str]] = []
    lines: list[tuple[float, str, str]] = []
    for c in iter_chunks(path):
        ent = c.entity_path
        log.entities.add(ent)
        log.timelines.update(c.timeline_names)
        if not (ent == SUMMARY_JSON_PATH or ent.startswith(TEXT + "/") or ent.startswith(ATTEMPTS + "/")):
            continue
        rb = c.to_record_batch()
        times = index_values(rb, "sim_time")
        if "TextLog:text" in rb.schema.names:
            for t, texts in zip(times, rb.column("TextLog:text").to_pylist()):
                lines.extend((t or 0.0, ent[len(TEXT) + 1:], x) for x in texts or [])
        if "TextDocument:text" not in rb.schema.names:
            continue
        for t, texts in zip(times, rb.column("TextDocument:text").to_pylist()):
            for x in texts or []:
                if ent == SUMMARY_JSON_PATH:
                    try:
                        log.summary = json.loads(x)
                    except json.JSONDecodeError as exc:
                        raise ReplayError(f"{path}: the episode summary is not valid JSON ({exc})") from exc
                elif ent.startswith(ATTEMPTS + "/"):
                    log.attempts[ent[len(ATTEMPTS) + 1:]] = x
                else:
                    docs.append((t or 0.0, ent[len(TEXT) + 1:], x))
    for _, key, body in sorted(docs, key=lambda r: r[0]):
        log.texts.setdefault(key, []).append(body)
    for _, key, body in sorted(lines, key=lambda r: r[0]):
        log.logs.setdefault(key, []).append(body)
    if log.summary is None and not log.entities - {"/__properties"}:
        raise ReplayError(f"{path} holds no recording data")
    return log


_CHANNEL_DTYPES = {6: "uint8", 7: "int8", 8: "uint16", 9: "int16", 10: "uint32", 11: "int32", 12: "uint64",
                   13: "int64", 33: "float16", 34: "float32", 35: "float64"}
"""rerun's ``ChannelDatatype`` codes (as stored in ``ImageFormat.channel_datatype``) -> numpy dtype."""


def _channel_dtype(code: Any) -> Any:
    return np.dtype(_CHANNEL_DTYPES.get(int(code), "uint8") if code is not None else "uint8")


def iter_images(path: str | Path) -> Iterator[LoggedImage]:
    """Every camera image logged in the file (``/camera/...``), in file order."""
    for c in iter_chunks(Path(path)):
        ent = c.entity_path
        if not ent.startswith(CAMERA + "/"):
            continue
        rb = c.to_record_batch()
        names = rb.schema.names
        prims = index_values(rb, "primitive")
        times = index_values(rb, "sim_time")
        kind = "depth" if ent.endswith("depth") else "rgb"
        if "EncodedImage:blob" in names:
            media = index_values(rb, "EncodedImage:media_type")
            for i, blobs in enumerate(rb.column("EncodedImage:blob").to_pylist()):
                for b in blobs or []:
                    mt = (media[i] or [None])[0] if media[i] is not None else None
                    yield LoggedImage(ent, kind, prims[i], times[i], bytes(b), mt)
        for comp in ("DepthImage", "Image"):
            if f"{comp}:buffer" not in names:
                continue
            fmts = rb.column(f"{comp}:format").to_pylist()
            for i, bufs in enumerate(rb.column(f"{comp}:buffer").to_pylist()):
                if not bufs:
                    continue
                fmt = fmts[i][0]
                arr = np.frombuffer(bytes(bufs[0]), dtype=_channel_dtype(fmt.get("channel_datatype")))
                h, w = int(fmt["height"]), int(fmt["width"])
                chans = arr.size // (h * w) if h * w else 1
                arr = arr.reshape((h, w) if chans == 1 else (h, w, chans))
                yield LoggedImage(ent, "depth" if comp == "DepthImage" else kind, prims[i], times[i], arr)


__all__ = ["EpisodeLog", "LoggedImage", "ReplayError", "index_values", "iter_chunks", "iter_images", "read_episode"]
