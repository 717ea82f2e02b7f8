"""What crosses between capmj and a jailed task: size-bounded JSON frames, validated into records.

The jailed process speaks data only.  Each message is one frame: a 4-byte big-endian length and
that many bytes of strict JSON (no NaN, no infinity).  A frame longer than its direction allows
(:data:`MAX_FROM_JAIL`, :data:`MAX_TO_JAIL`) ends the conversation before it is read, so a task
cannot make the parent buffer gigabytes.  Every value the jail sends is then checked field by
field and rebuilt as capmj's own frozen records (:class:`~capmj.tasks.protocol.Scene`,
:class:`~capmj.tasks.protocol.OracleGoal`, :class:`~capmj.tasks.protocol.Verdict`): known kinds,
colours and sizes only, finite numbers in range, bounded counts and string lengths.  A value that
fails is a :class:`WireError` naming the field; nothing of it reaches the simulator.

Both directions use the same codecs, so a scene the parent sends back to the jail (to ask for its
oracle goals or a verdict) is the one it validated.
"""

from __future__ import annotations

import json
import math
import os
import select
import struct
import time
from typing import IO, Any, Mapping

import numpy as np

from capmj.errors import ConfinementError
from capmj.sim.objects import BLOCK_SIZES, KINDS, ObjectSpec
from capmj.sim.palette import COLORS
from capmj.sim.state import Pose, SceneState
from capmj.tasks.protocol import OracleGoal, Scene, Target, Verdict

MAX_FROM_JAIL = 1 << 20
"""Largest frame a jailed task may send (bytes)."""
MAX_TO_JAIL = 4 << 20
"""Largest frame capmj sends (the module text, a scene state)."""
MAX_OBJECTS = 64
MAX_GOALS = 64
MAX_TEXT = 2_000
"""Longest goal text or diagnostic (characters)."""
MAX_DOC = 20_000
MAX_TAGS = 32
MAX_INFO_NODES = 20_000
MAX_COORD = 10.0
"""Largest absolute coordinate (metres) of a position or target; the workspace is under 1 m."""
_HEADER = struct.Struct(">I")


class WireError(ConfinementError):
    """A message from a jailed task is malformed, too large or out of range."""


# ------------------------------------------------------------------------------------------ frames
def write_frame(out: IO[bytes], message: Mapping[str, Any]) -> None:
    """Send one message as a frame (strict JSON)."""
    data = json.dumps(message, allow_nan=False, separators=(",", ":")).encode()
    out.write(_HEADER.pack(len(data)) + data)
    out.flush()


def frame_length(header: bytes, limit: int) -> int:
    """The payload length a 4-byte header announces; :class:`WireError` above ``limit``."""
    if len(header) != _HEADER.size:
        raise WireError("the jailed process closed the channel")
    (n,) = _HEADER.unpack(header)
    if n > limit:
        raise WireError(f"a message of {n} bytes exceeds the limit of {limit} bytes")
    return int(n)


def decode_frame(payload: bytes) -> dict[str, Any]:
    """A frame's payload as a JSON object; :class:`WireError` for anything else."""
    def no_constants(name: str) -> Any:
        raise ValueError(f"{name} is not JSON")

    try:
        value = json.loads(payload.decode(), parse_constant=no_constants)
    except (UnicodeDecodeError, ValueError, RecursionError) as e:
        raise WireError(f"not a JSON message: {type(e).__name__}: {str(e)[:200]}") from None
    if not isinstance(value, dict):
        raise WireError(f"a message must be a JSON object, got {type(value).__name__}")
    return value


def read_exact(fd: int, n: int, deadline: float | None = None) -> bytes:
    """Exactly ``n`` bytes from descriptor ``fd``: ``EOFError`` if it closes first, ``TimeoutError``
    if ``deadline`` (a ``time.monotonic()`` value) passes first."""
    chunks, got = [], 0
    while got < n:
        if deadline is not None:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise TimeoutError
        chunk = os.read(fd, min(n - got, 1 << 16))
        if not chunk:
            raise EOFError
        chunks.append(chunk)
        got += len(chunk)
    return b"".join(chunks)


def read_frame(inp: IO[bytes], limit: int) -> dict[str, Any]:
    """Read one frame from a blocking stream (the jailed side's reader)."""
    n = frame_length(inp.read(_HEADER.size), limit)
    payload = inp.read(n)
    if len(payload) != n:
        raise WireError("the channel closed inside a message")
    return decode_frame(payload)


# ------------------------------------------------------------------------------------------ checks
def _field(obj: Any, key: str, where: str) -> Any:
    if not isinstance(obj, dict) or key not in obj:
        raise WireError(f"{where}: missing field {key!r}")
    return obj[key]


def _int(v: Any, where: str, lo: int = -(2**31), hi: int = 2**31) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise WireError(f"{where}: expected an integer in [{lo}, {hi}], got {str(v)[:60]}")
    return v


def _num(v: Any, where: str, bound: float = MAX_COORD) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or abs(v) > bound:
        raise WireError(f"{where}: expected a finite number within ±{bound:g}, got {str(v)[:60]}")
    return float(v)


def _str(v: Any, where: str, limit: int = MAX_TEXT) -> str:
    if not isinstance(v, str) or len(v) > limit:
        raise WireError(f"{where}: expected a string of at most {limit} characters")
    return v


def _list(v: Any, where: str, limit: int) -> list[Any]:
    if not isinstance(v, list) or len(v) > limit:
        raise WireError(f"{where}: expected a list of at most {limit} items")
    return v


def _vec(v: Any, n: int, where: str, bound: float = MAX_COORD) -> tuple[float, ...]:
    items = _list(v, where, n)
    if len(items) != n:
        raise WireError(f"{where}: expected {n} numbers, got {len(items)}")
    return tuple(_num(x, f"{where}[{i}]", bound) for i, x in enumerate(items))


def _info(v: Any, where: str) -> dict[str, Any]:
    """A scene's ``info``: a JSON object of bounded size (it came through JSON, so it is data)."""
    if not isinstance(v, dict):
        raise WireError(f"{where}: expected an object")
    nodes, stack = 0, [v]
    while stack:
        x = stack.pop()
        nodes += 1
        if nodes > MAX_INFO_NODES:
            raise WireError(f"{where}: more than {MAX_INFO_NODES} values")
        if isinstance(x, dict):
            stack.extend(x.values())
        elif isinstance(x, list):
            stack.extend(x)
        elif isinstance(x, str) and len(x) > MAX_TEXT:
            raise WireError(f"{where}: a string longer than {MAX_TEXT} characters")
    return v


# ------------------------------------------------------------------------------------------ records
def spec_to_wire(o: ObjectSpec) -> dict[str, Any]:
    return {"obj_id": o.obj_id, "kind": o.kind, "color": o.color, "pos": list(o.pos), "yaw": o.yaw, "size": o.size,
            "scale": o.scale}


def spec_from_wire(v: Any, where: str) -> ObjectSpec:
    kind, color, size = (_field(v, k, where) for k in ("kind", "color", "size"))
    if kind not in KINDS:
        raise WireError(f"{where}: unknown kind {str(kind)[:40]!r}; valid kinds: {', '.join(KINDS)}")
    if color not in COLORS:
        raise WireError(f"{where}: unknown colour {str(color)[:40]!r}")
    if size is not None and size not in BLOCK_SIZES:
        raise WireError(f"{where}: unknown size {str(size)[:40]!r}; valid sizes: {', '.join(BLOCK_SIZES)}")
    scale = _num(_field(v, "scale", where), f"{where}.scale", 10.0)
    if scale <= 0:
        raise WireError(f"{where}.scale must be positive")
    try:
        return ObjectSpec(_int(_field(v, "obj_id", where), f"{where}.obj_id", 1, 10_000), kind, color,
                          _vec(_field(v, "pos", where), 3, f"{where}.pos"),  # type: ignore[arg-type]
                          _num(_field(v, "yaw", where), f"{where}.yaw", 1e3), size, scale)
    except ValueError as e:  # ObjectSpec's own rules
        raise WireError(f"{where}: {e}") from None


def scene_to_wire(s: Scene) -> dict[str, Any]:
    return {"objects": [spec_to_wire(o) for o in s.objects], "goal": s.goal, "info": dict(s.info)}


def scene_from_wire(v: Any, where: str = "scene") -> Scene:
    objs = tuple(spec_from_wire(o, f"{where}.objects[{i}]")
                 for i, o in enumerate(_list(_field(v, "objects", where), f"{where}.objects", MAX_OBJECTS)))
    if len({o.obj_id for o in objs}) != len(objs):
        raise WireError(f"{where}.objects: obj_id values repeat")
    return Scene(objs, _str(_field(v, "goal", where), f"{where}.goal"), _info(_field(v, "info", where), f"{where}.info"))


def state_to_wire(s: SceneState) -> dict[str, Any]:
    return {"objects": [spec_to_wire(o) for o in s.objects],
            "poses": [[i, list(p.pos), list(p.quat)] for i, p in s.poses.items()], "time": s.time, "held": s.held}


def state_from_wire(v: Any, where: str = "state") -> SceneState:
    objs = tuple(spec_from_wire(o, f"{where}.objects[{i}]")
                 for i, o in enumerate(_list(_field(v, "objects", where), f"{where}.objects", MAX_OBJECTS)))
    poses = {}
    for i, row in enumerate(_list(_field(v, "poses", where), f"{where}.poses", MAX_OBJECTS)):
        r = _list(row, f"{where}.poses[{i}]", 3)
        if len(r) != 3:
            raise WireError(f"{where}.poses[{i}]: expected [obj_id, pos, quat]")
        poses[_int(r[0], f"{where}.poses[{i}][0]", 1, 10_000)] = Pose.of(_vec(r[1], 3, f"{where}.poses[{i}].pos", 1e3),
                                                                     _vec(r[2], 4, f"{where}.poses[{i}].quat", 2.0))
    held = _field(v, "held", where)
    return SceneState(objs, poses, _num(_field(v, "time", where), f"{where}.time", 1e9),
                      None if held is None else _int(held, f"{where}.held", 1, 10_000))


def goal_to_wire(g: OracleGoal) -> dict[str, Any]:
    return {"objects": list(g.objects), "targets": [{"pos": list(t.pos), "yaw": t.yaw} for t in g.targets],
            "matches": [list(r) for r in g.matches], "replace": g.replace, "rotations": g.rotations,
            "metric": g.metric, "tolerance": g.tolerance, "zone_size": g.zone_size}


def _bool(v: Any, where: str) -> bool:
    if not isinstance(v, bool):
        raise WireError(f"{where}: expected true or false")
    return v


def goal_from_wire(v: Any, where: str) -> OracleGoal:
    objs = tuple(_int(x, f"{where}.objects", 1, 10_000) for x in _list(_field(v, "objects", where), f"{where}.objects", MAX_OBJECTS))
    targets = []
    for i, t in enumerate(_list(_field(v, "targets", where), f"{where}.targets", MAX_OBJECTS)):
        yaw = _field(t, "yaw", f"{where}.targets[{i}]")
        targets.append(Target(_vec(_field(t, "pos", f"{where}.targets[{i}]"), 3, f"{where}.targets[{i}].pos"),  # type: ignore[arg-type]
                              None if yaw is None else _num(yaw, f"{where}.targets[{i}].yaw", 1e3)))
    matches = tuple(tuple(_int(x, f"{where}.matches", 0, 1) for x in _list(r, f"{where}.matches", MAX_OBJECTS))
                    for r in _list(_field(v, "matches", where), f"{where}.matches", MAX_OBJECTS))
    metric = _field(v, "metric", where)
    if metric not in ("pose", "zone"):
        raise WireError(f"{where}.metric must be 'pose' or 'zone'")
    try:
        return OracleGoal(objs, tuple(targets), matches, _bool(_field(v, "replace", where), f"{where}.replace"),
                          _bool(_field(v, "rotations", where), f"{where}.rotations"), metric,
                          _num(_field(v, "tolerance", where), f"{where}.tolerance", 1.0),
                          _num(_field(v, "zone_size", where), f"{where}.zone_size", 1.0))
    except ValueError as e:  # OracleGoal's own shape rule
        raise WireError(f"{where}: {e}") from None


def goals_from_wire(v: Any) -> list[OracleGoal]:
    return [goal_from_wire(g, f"goals[{i}]") for i, g in enumerate(_list(v, "goals", MAX_GOALS))]


def verdict_to_wire(v: Verdict) -> dict[str, Any]:
    return {"success": bool(v.success), "progress": float(v.progress), "diagnostics": [str(d) for d in v.diagnostics]}


def verdict_from_wire(v: Any) -> Verdict:
    progress = _num(_field(v, "progress", "verdict"), "verdict.progress", 1.0)
    if progress < 0:
        raise WireError("verdict.progress must be in [0, 1]")
    diags = tuple(_str(d, "verdict.diagnostics") for d in _list(_field(v, "diagnostics", "verdict"), "verdict.diagnostics", 50))
    return Verdict(_bool(_field(v, "success", "verdict"), "verdict.success"), progress, diags)


def rng_to_wire(rng: np.random.Generator) -> dict[str, Any]:
    """A generator's whole state (PCG64: two 128-bit integers and a cached word), as JSON."""
    state = rng.bit_generator.state
    if state.get("bit_generator") != "PCG64":
        raise WireError(f"only PCG64 generators cross to a jailed task, not {state.get('bit_generator')}")
    return dict(state)


def rng_from_wire(v: Any) -> dict[str, Any]:
    """A PCG64 state checked field by field (set it with ``rng.bit_generator.state = ...``)."""
    if _field(v, "bit_generator", "rng") != "PCG64":
        raise WireError("rng: only PCG64 states are accepted")
    inner = _field(v, "state", "rng")
    state = {k: _int(_field(inner, k, "rng.state"), f"rng.state.{k}", 0, 2**128 - 1) for k in ("state", "inc")}
    return {"bit_generator": "PCG64", "state": state,
            "has_uint32": _int(_field(v, "has_uint32", "rng"), "rng.has_uint32", 0, 1),
            "uinteger": _int(_field(v, "uinteger", "rng"), "rng.uinteger", 0, 2**32 - 1)}


__all__ = ["MAX_FROM_JAIL", "MAX_TO_JAIL", "WireError", "decode_frame", "frame_length", "goal_to_wire", "read_exact",
           "goals_from_wire", "read_frame", "rng_from_wire", "rng_to_wire", "scene_from_wire", "scene_to_wire",
           "state_from_wire", "state_to_wire", "verdict_from_wire", "verdict_to_wire", "write_frame"]
