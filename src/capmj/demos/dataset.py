"""Oracle demonstrations on disk in the Ravens/CLIPort layout, and a typed loader.

Layout (what ``ravens.dataset.Dataset`` and ``cliport.dataset.RavensDataset`` read unchanged)::

    DIR/<task>-<split>/{action,color,depth,info,reward}/{episode:06d}-{seed}.pkl

Each file holds one list (or array) with one entry per step ``t = 0..T``: the observation *before*
action ``t``, the action (None at ``T``), the reward received *with* that observation (0 at
``t = 0``: Ravens' convention), and an info dict holding ``lang_goal`` (what CLIPort reads).

* ``color``  uint8 ``(T+1, n_cams, H, W, 3)``; ``depth`` float32 ``(T+1, n_cams, H, W)`` metres
  along the optical axis (cameras "front", "left", "right").
* ``action`` ``{"pose0": ((x, y, z), (qx, qy, qz, qw)), "pose1": ...}``: pick and place poses, yaw
  as a z-rotation quaternion (Ravens' xyzw order).
* ``info`` ``{"lang_goal", "task", "seed", "step", "progress", "success", "status", "poses"}``;
  ``poses`` maps object id -> ((x, y, z), (qx, qy, qz, qw)).

Seeds (CLIPort's convention): train uses even seeds 0, 2, 4, ...; val odd seeds 1, 3, 5, ...;
test odd seeds 10001, 10003, ....  As in Ravens, only successful oracle episodes are saved and
numbered consecutively; a seed the oracle fails is listed in ``skipped.jsonl`` and not retried.
``cameras.pkl`` holds the camera configs in Ravens' ``CONFIG`` format, to pass as ``cam_config``
when fusing heightmaps (capmj's cameras are Ravens-like, not Ravens' exact poses).
"""

from __future__ import annotations

import json
import pickle
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Mapping, Sequence

import numpy as np

from capmj.atomic import atomic_write
from capmj.errors import ConfigError
from capmj.sim import pose as sim_pose
from capmj.sim.pose import wxyz, xyzw

FIELDS = ("color", "depth", "reward", "info", "action")
"""Written in this order: ``action/`` last, because it is the index both loaders scan."""
PICKLE_PROTOCOL = 4
SPLIT_FIRST_SEED = {"train": 0, "val": 1, "test": 10001}
SEED_STEP = 2
_NAME = re.compile(r"^(\d{6})-(-?\d+)\.pkl$")


def split_seeds(split: str, start_after: int | None = None) -> Iterator[int]:
    """The seeds of a split in order, optionally only those after ``start_after``."""
    if split not in SPLIT_FIRST_SEED:
        raise ConfigError(f"unknown split {split!r}; valid splits: {', '.join(SPLIT_FIRST_SEED)}")
    seed = SPLIT_FIRST_SEED[split]
    if start_after is not None and start_after >= seed:
        seed += ((start_after - seed) // SEED_STEP + 1) * SEED_STEP
    while True:
        yield seed
        seed += SEED_STEP


def dataset_dir(out: Path | str, task: str, split: str) -> Path:
    return Path(out) / f"{task}-{split}"


def yaw_quat(yaw: float) -> tuple[float, float, float, float]:
    """A rotation about z as an (x, y, z, w) quaternion (Ravens' order)."""
    return xyzw(sim_pose.yaw_quat(yaw))


def quat_yaw(q: Sequence[float]) -> float:
    """The z-rotation of an (x, y, z, w) quaternion."""
    return sim_pose.quat_yaw(wxyz(q))


def ravens_action(action: Mapping[str, np.ndarray]) -> dict[str, tuple[tuple[float, ...], tuple[float, ...]]]:
    """An env action as Ravens' ``{"pose0": (xyz, xyzw), "pose1": (xyz, xyzw)}``."""
    out: dict[str, tuple[tuple[float, ...], tuple[float, ...]]] = {}
    for key, name in (("pose0", "pick"), ("pose1", "place")):
        v = np.asarray(action[name], dtype=np.float64)
        out[key] = (tuple(float(c) for c in v[:3]), yaw_quat(float(v[3])))
    return out


@dataclass(frozen=True)
class DemoStep:
    """One step of a saved demonstration, typed.

    ``pick``/``place`` are ``(x, y, z, yaw)`` float64 (None on the final step, which only shows the
    outcome); ``reward`` was received together with this observation.
    """

    episode: int
    seed: int
    step: int
    color: np.ndarray
    depth: np.ndarray
    pick: np.ndarray | None
    place: np.ndarray | None
    reward: float
    goal: str
    info: Mapping[str, Any]

    @property
    def last(self) -> bool:
        return self.pick is None


@dataclass(frozen=True)
class EpisodeFile:
    episode: int
    seed: int
    name: str


def episodes(path: Path | str) -> list[EpisodeFile]:
    """The saved episodes of one dataset directory, by episode number."""
    adir = Path(path) / "action"
    if not adir.is_dir():
        raise ConfigError(f"{path} is not a demonstration dataset: it has no action/ folder")
    found = []
    for f in sorted(adir.iterdir()):
        m = _NAME.match(f.name)
        if m:
            found.append(EpisodeFile(int(m.group(1)), int(m.group(2)), f.name))
    return found


def load(path: Path | str, *, images: bool = True) -> Iterator[DemoStep]:
    """Yield every step of every episode of a dataset directory (``DIR/<task>-<split>``).

    ``images=False`` skips the colour and depth files (then those fields are empty arrays).
    """
    root = Path(path)
    for ep in episodes(root):
        data = {}
        for field in FIELDS:
            if field in ("color", "depth") and not images:
                continue
            with open(root / field / ep.name, "rb") as fh:
                data[field] = pickle.load(fh)
        actions, rewards, infos = data["action"], data["reward"], data["info"]
        if not (len(actions) == len(rewards) == len(infos)):
            raise ConfigError(f"{root}/*/{ep.name}: fields have different lengths")
        for t, act in enumerate(actions):
            pick = place = None
            if act is not None:
                pick, place = (np.array([*act[k][0], quat_yaw(act[k][1])]) for k in ("pose0", "pose1"))
            yield DemoStep(ep.episode, ep.seed, t,
                           data["color"][t] if images else np.empty(0, np.uint8),
                           data["depth"][t] if images else np.empty(0, np.float32),
                           pick, place, float(rewards[t]), str(infos[t]["lang_goal"]), infos[t])


def write_episode(directory: Path, name: str, record: Mapping[str, Any]) -> None:
    """Write one episode's fields as ``<field>/<name>`` (each atomically, action last)."""
    for field in FIELDS:
        (directory / field).mkdir(parents=True, exist_ok=True)
        target = directory / field / name
        with atomic_write(target, "wb") as fh:
            pickle.dump(record[field], fh, protocol=PICKLE_PROTOCOL)


def resume_point(directory: Path) -> tuple[int, int | None]:
    """(episodes saved, last seed tried) of a dataset directory, for ``--resume``."""
    saved = episodes(directory) if (directory / "action").is_dir() else []
    seeds = [e.seed for e in saved]
    skipped = directory / "skipped.jsonl"
    if skipped.exists():
        for line in skipped.read_text().splitlines():
            if line.strip():
                seeds.append(int(json.loads(line)["seed"]))
    return len(saved), max(seeds, default=None)


def camera_configs(rig: Any, cameras: Sequence[str]) -> list[dict[str, Any]]:
    """Ravens ``CONFIG`` dicts (image_size, intrinsics, position, rotation xyzw, zrange, noise)."""
    out = []
    for name in cameras:
        pose = rig.extrinsics(name)  # camera-to-world, OpenCV axes: what Ravens' rotation means
        out.append({"name": name, "image_size": (rig.height, rig.width),
                    "intrinsics": tuple(float(v) for v in rig.intrinsics(name).ravel()),
                    "position": tuple(float(v) for v in pose[:3, 3]),
                    "rotation": _matrix_quat_xyzw(pose[:3, :3]),
                    "zrange": (0.01, 10.0), "noise": False})
    return out


def _matrix_quat_xyzw(r: np.ndarray) -> tuple[float, float, float, float]:
    return xyzw(sim_pose.mat_to_quat(r))
