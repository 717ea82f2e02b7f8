"""Cutting the top-down map into segments: one colour, one surface, connected.

Every up-facing cell above the table is named by the nearest palette colour
(:mod:`capmj.perception.colour`); cells too far from every colour, and cells on slanted or vertical
surfaces (lit differently, so their colour is unreliable), stay unnamed.  Named cells are then
split by height into two layers: *flat* (a zone's face, 1 mm above the table) and *raised*
(everything standing on the table).  A segment is a connected set of named cells of one colour
and one layer in which neighbours differ in height by less than :data:`MAX_STEP`, so a block
standing on a zone of its own colour, a block on top of another, and a bowl's rim and floor are
all different segments.  Finally each unnamed raised cell (a ball's flanks, block edges) joins
the nearest raised segment within :data:`GROW_CELLS`: geometry without colour.

Connectivity is computed as a graph (:func:`scipy.sparse.csgraph.connected_components` over
8-neighbour edges), which lets the height test be part of the adjacency; it is exact and
deterministic.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from capmj.perception.cloud import TABLE_TOL, TABLE_Z, TopDownMap

FLAT_MAX = 0.0025
"""Cells up to this height (m) are the flat layer (zones); above it they stand on the table."""
MAX_STEP = 0.006
"""Neighbouring cells of one segment differ in height by less than this (m)."""
MAX_DELTA_E = 30.0
"""Cells farther than this (CIE76 ΔE) from every palette colour stay unnamed (arm, shadows)."""
GROW_CELLS = 9
"""Unnamed raised cells within this many cells of a raised segment join it (a ball's flanks)."""
MIN_CELLS = {"flat": 120, "raised": 10}
"""Smaller segments are noise (a zone is ~2300 cells, a tiny block's top ~50, a ball's cap ~80)."""


@dataclass(frozen=True, eq=False)
class Segment:
    """One connected single-colour surface and the unnamed cells that joined it."""

    colour: int
    """Palette index (:data:`capmj.sim.palette.COLOR_NAMES`)."""
    layer: str
    """"flat" or "raised"."""
    xy: np.ndarray
    """(N, 2) world centres of the named cells."""
    heights: np.ndarray
    """(N,) heights of the named cells (m)."""
    grown_xy: np.ndarray
    """(M, 2) centres of the unnamed cells that joined (raised segments only)."""
    grown_heights: np.ndarray
    delta_e: float
    """Median ΔE of the named cells to the segment's colour."""
    runner_up: float
    """Median ΔE of the named cells to the second-nearest colour (the margin of the naming)."""

    @property
    def all_xy(self) -> np.ndarray:
        return np.concatenate([self.xy, self.grown_xy])

    @property
    def all_heights(self) -> np.ndarray:
        return np.concatenate([self.heights, self.grown_heights])


def _name_cells(m: TopDownMap) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(palette index or -1, ΔE to it, ΔE to the runner-up) per cell."""
    shape = m.height.shape
    h = np.nan_to_num(m.height, nan=-1.0)
    candidates = m.upright & (h > TABLE_Z + TABLE_TOL)
    idx = np.flatnonzero(candidates)
    d = m.colours.distances(m.lab.reshape(-1, 3)[idx], m.camera.reshape(-1)[idx])
    order = np.argsort(d, axis=1, kind="stable")
    best, second = order[:, 0], order[:, 1]
    rows = np.arange(len(idx))
    label = np.full(h.size, -1, dtype=np.int64)
    de = np.full(h.size, np.inf)
    de2 = np.full(h.size, np.inf)
    ok = d[rows, best] <= MAX_DELTA_E
    label[idx[ok]] = best[ok]
    de[idx] = d[rows, best]
    de2[idx] = d[rows, second]
    return label.reshape(shape), de.reshape(shape), de2.reshape(shape)


def _components(key: np.ndarray, height: np.ndarray) -> np.ndarray:
    """Component id per cell (-1 where ``key`` < 0): 8-neighbours join when their keys are equal
    and their heights differ by less than :data:`MAX_STEP` (diagonals keep a bowl's 3-cell-wide
    rim in one piece where a cell of it is unnamed)."""
    rows, cols = key.shape
    n = rows * cols
    flat_key, flat_h = key.reshape(-1), height.reshape(-1)
    ids = np.arange(n).reshape(rows, cols)
    src, dst = [], []
    pairs = ((ids[:, :-1], ids[:, 1:]), (ids[:-1, :], ids[1:, :]), (ids[:-1, :-1], ids[1:, 1:]), (ids[:-1, 1:], ids[1:, :-1]))
    for a, b in pairs:
        a, b = a.reshape(-1), b.reshape(-1)
        join = (flat_key[a] >= 0) & (flat_key[a] == flat_key[b]) & (np.abs(flat_h[a] - flat_h[b]) < MAX_STEP)
        src.append(a[join])
        dst.append(b[join])
    s, t = np.concatenate(src), np.concatenate(dst)
    graph = coo_matrix((np.ones(len(s), dtype=np.int8), (s, t)), shape=(n, n))
    _, comp = connected_components(graph, directed=False)
    comp = comp.astype(np.int64)
    comp[flat_key < 0] = -1
    return comp.reshape(rows, cols)


def segment(m: TopDownMap) -> list[Segment]:
    """The segments of a top-down map, flat ones first, each group in order of first cell."""
    label, de, de2 = _name_cells(m)
    h = np.nan_to_num(m.height, nan=-1.0)
    layer = np.where(h > FLAT_MAX, 1, 0)
    key = np.where(label >= 0, label * 2 + layer, -1)
    comp = _components(key, h)
    return _collect(m, comp, label, layer, de, de2)


def _collect(m: TopDownMap, comp: np.ndarray, label: np.ndarray, layer: np.ndarray,
             de: np.ndarray, de2: np.ndarray) -> list[Segment]:
    """Segments from component ids: small ones dropped, unnamed raised cells attached."""
    rows, cols = np.nonzero(comp >= 0)
    cids = comp[rows, cols]
    if len(cids) == 0:
        return []
    order = np.argsort(cids, kind="stable")
    rows, cols, cids = rows[order], cols[order], cids[order]
    starts = np.r_[0, np.flatnonzero(np.diff(cids)) + 1]
    ends = np.r_[starts[1:], len(cids)]
    groups = []
    for a, b in zip(starts, ends):
        r, c = rows[a:b], cols[a:b]
        lay = "raised" if layer[r[0], c[0]] else "flat"
        if b - a >= MIN_CELLS[lay]:
            groups.append((lay, r, c))
    # Unnamed raised cells join the nearest kept raised segment (within GROW_CELLS).
    owner = np.full(comp.shape, -1, dtype=np.int64)
    for g, (lay, r, c) in enumerate(groups):
        if lay == "raised":
            owner[r, c] = g
    h = np.nan_to_num(m.height, nan=-1.0)
    unnamed = (h > FLAT_MAX) & (label < 0)
    grown: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    if (owner >= 0).any() and unnamed.any():
        dist, (ir, ic) = ndimage.distance_transform_edt(owner < 0, return_indices=True)
        take = unnamed & (dist <= GROW_CELLS)
        ur, uc = np.nonzero(take)
        gid = owner[ir[ur, uc], ic[ur, uc]]
        for g in np.unique(gid):
            sel = gid == g
            grown[int(g)] = (ur[sel], uc[sel])
    segments = []
    empty = np.zeros(0, dtype=np.int64)
    for g, (lay, r, c) in enumerate(groups):
        gr, gc = grown.get(g, (empty, empty))
        segments.append(Segment(
            colour=int(label[r[0], c[0]]), layer=lay, xy=m.xy(r, c), heights=m.height[r, c].astype(np.float64),
            grown_xy=m.xy(gr, gc), grown_heights=m.height[gr, gc].astype(np.float64),
            delta_e=float(np.median(de[r, c])), runner_up=float(np.median(de2[r, c]))))
    segments.sort(key=lambda s: (s.layer != "flat",))
    return segments


__all__ = ["FLAT_MAX", "MAX_STEP", "Segment", "segment"]
