"""Oracle demonstrations: the Ravens/CLIPort layout, the typed loader, resume, and determinism
(same seeds -> byte-identical files, whether in-process, resumed, or with two workers)."""

from __future__ import annotations

import itertools
import pickle
from pathlib import Path

import numpy as np
import pytest

from capmj.demos import episodes, load, split_seeds
from capmj.demos.cli import main
from capmj.demos.collect import collect_split, make_pool
from capmj.envs import EnvConfig
from capmj.errors import ConfigError
from capmj.tasks.protocol import make_scene
from capmj.tasks.registry import get_task

TASK = "stack-all-blocks-on-a-zone"
TINY = EnvConfig(width=32, height=24, robot_meshes=False)


def test_split_seeds_follow_the_cliport_convention() -> None:
    assert list(itertools.islice(split_seeds("train"), 3)) == [0, 2, 4]
    assert list(itertools.islice(split_seeds("val"), 3)) == [1, 3, 5]
    assert list(itertools.islice(split_seeds("test"), 3)) == [10001, 10003, 10005]
    assert next(split_seeds("test", start_after=10003)) == 10005
    with pytest.raises(ConfigError, match="valid splits: train, val, test"):
        next(split_seeds("dev"))


def _files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def test_split_round_trips_and_is_byte_identical_across_resume_and_workers(tmp_path: Path) -> None:
    a, b = tmp_path / "a", tmp_path / "b"
    stats = collect_split(TASK, "test", 2, a, config=TINY)
    assert stats.saved == 2 and stats.steps >= 4 and stats.bytes_per_step > 0
    d = a / f"{TASK}-test"

    # Ravens/CLIPort layout: the seed parsed the way their loaders parse it, equal-length fields.
    names = sorted(p.name for p in (d / "action").iterdir())
    assert [int(n[n.find("-") + 1:-4]) for n in names] == [10001, 10003]
    for name in names:
        fields = {f: pickle.loads((d / f / name).read_bytes()) for f in ("color", "depth", "action", "reward", "info")}
        n = len(fields["action"])
        assert all(len(v) == n for v in fields.values()) and fields["action"][-1] is None
        assert fields["color"].shape == (n, 3, 24, 32, 3) and fields["color"].dtype == np.uint8
        assert fields["depth"].shape == (n, 3, 24, 32) and fields["depth"].dtype == np.float32
        pos, quat = fields["action"][0]["pose0"]
        assert len(pos) == 3 and len(quat) == 4 and fields["reward"][0] == 0.0
    cams = pickle.loads((d / "cameras.pkl").read_bytes())
    assert [c["name"] for c in cams] == ["front", "left", "right"] and cams[0]["image_size"] == (24, 32)

    # The typed loader: goal text, shapes, rewards summing to the progress made.
    steps = list(load(d))
    assert [s.episode for s in steps if s.last] == [0, 1]
    for ep in (0, 1):
        ep_steps = [s for s in steps if s.episode == ep]
        seed = ep_steps[0].seed
        assert all(s.goal == make_scene(get_task(TASK), seed).goal for s in ep_steps)
        assert ep_steps[-1].info["success"] and ep_steps[-1].info["progress"] == 1.0
        total = sum(s.reward for s in ep_steps)
        assert total == pytest.approx(ep_steps[-1].info["progress"] - ep_steps[0].info["progress"])
        first = ep_steps[0]
        assert first.pick is not None and first.pick.shape == (4,) and first.pick.dtype == np.float64
        assert first.color.shape == (3, 24, 32, 3) and first.depth.dtype == np.float32
        before = first.info["poses"]
        picked = min(before, key=lambda i: float(np.hypot(*(np.asarray(before[i][0][:2]) - first.pick[:2]))))
        placed = np.asarray(ep_steps[1].info["poses"][picked][0])
        assert np.hypot(*(placed[:2] - first.place[:2])) < 0.02  # the picked object went to the place pose
    assert [s.color.size for s in load(d, images=False)][:1] == [0]

    # Resume from one episode, finish with two workers: the same bytes.
    assert collect_split(TASK, "test", 1, b, config=TINY).saved == 1
    pool = make_pool(2)
    try:
        again = collect_split(TASK, "test", 2, b, config=TINY, workers=2, pool=pool)
    finally:
        pool.shutdown()
    assert again.resumed_from == 1 and again.saved == 2
    assert _files(a) == _files(b)
    assert [e.seed for e in episodes(b / f"{TASK}-test")] == [10001, 10003]


def test_cli_names_valid_tasks_on_a_typo(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["--tasks", "stack-all-blocks-on-a-zonee", "--split", "val", "--n", "1", "--out", str(tmp_path)])
    assert code == 2
    assert "did you mean 'stack-all-blocks-on-a-zone'" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())
