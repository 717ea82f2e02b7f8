"""The buffered body poses of an episode log: which rows are sent, and how frames are stacked."""

from __future__ import annotations

import numpy as np

from capmj.log.poses import POSE_EPS, PoseBuffer, changed_rows


def _sequential(rows: list[np.ndarray | None], last: np.ndarray | None) -> list[int]:
    """The rule body by body, row by row: send a row unless it is within POSE_EPS of the last sent."""
    out = []
    for i, cur in enumerate(rows):
        if cur is None:
            continue
        if last is not None and np.max(np.abs(cur - last)) < POSE_EPS:
            continue
        last = cur
        out.append(i)
    return out


def test_changed_rows_follow_the_sequential_rule_for_every_body():
    rng = np.random.default_rng(0)
    frames, bodies = 60, 9
    # steps around POSE_EPS so that drifts accumulate past the last sent pose; one body at rest
    steps = rng.choice([0.0, 0.3 * POSE_EPS, 0.8 * POSE_EPS, 3 * POSE_EPS], size=(frames, bodies, 7),
                       p=[0.8, 0.1, 0.07, 0.03])
    steps[:, 0] = 0.0
    poses = np.cumsum(steps, axis=0)
    poses[17, 3, 2] = np.nan  # a NaN pose is sent (it is not close to anything)
    present = rng.random((frames, bodies)) > 0.2
    last = rng.normal(scale=POSE_EPS, size=(bodies, 7))
    sent = np.arange(bodies) % 2 == 0  # half the bodies had a pose sent in an earlier flush
    keep, new_last, new_sent = changed_rows(poses, present, last, sent)
    for b in range(bodies):
        rows = [poses[f, b] if present[f, b] else None for f in range(frames)]
        expected = _sequential(rows, last[b] if sent[b] else None)
        assert list(np.flatnonzero(keep[:, b])) == expected
        assert new_sent[b] == (sent[b] or bool(expected))
        if expected:
            np.testing.assert_array_equal(new_last[b], poses[expected[-1], b])
        elif sent[b]:
            np.testing.assert_array_equal(new_last[b], last[b])


def test_buffer_keeps_flagged_frames_and_the_last_and_aligns_bodies_by_name():
    buf = PoseBuffer()
    q = np.array([[1.0, 0, 0, 0]])
    buf.add(0.0, 1, ("a",), np.array([[0.0, 0, 0]]), q, keep=True)
    buf.add(0.05, 1, ("a",), np.array([[1.0, 0, 0]]), q, keep=False)          # dropped
    buf.add(0.10, 2, ("b", "a"), np.array([[5.0, 0, 0], [2.0, 0, 0]]), np.vstack([q, q]), keep=False)
    buf.keep_last()
    buf.add(0.15, 2, ("a",), np.array([[3.0, 0, 0]]), q, keep=False)          # the latest: kept
    table = buf.take()
    assert table is not None and len(buf) == 0 and buf.take() is None
    assert table.names == ("a", "b")
    assert table.times.tolist() == [0.0, 0.10, 0.15] and table.labels.tolist() == [1, 2, 2]
    assert table.poses[:, 0, 0].tolist() == [0.0, 2.0, 3.0]
    assert table.present[:, 1].tolist() == [False, True, False] and table.poses[1, 1, 0] == 5.0
