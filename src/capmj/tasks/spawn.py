"""Scene sampling utilities: collision-free random placement and colour picking.

A :class:`Spawner` places objects one at a time at random collision-free poses by rejection
sampling on footprint circles (``ObjectSpec.footprint_radius`` + a 0.01 m gap), so no two
objects' footprints overlap — zones included: a block never spawns inside a zone unless a task
puts it there on purpose.  Object centres are drawn from ``SPAWN_BOUNDS`` (x ∈ [0.3, 0.7],
y ∈ [−0.4, 0.4], the reachable part of the workspace) further shrunk so the whole footprint stays
inside the workspace; blocks rest on the table (z = half height), zones lie flat, bowls stand on
the table.  When no pose is found the spawner raises :class:`capmj.tasks.protocol.Resample` and
the caller draws the whole scene again from the same seeded stream.

All randomness comes from the generator passed in, so a seed gives the same scene anywhere.
"""

from __future__ import annotations

import math
from typing import Iterable, Sequence

import numpy as np

from capmj.sim.bounds import WORKSPACE, Bounds
from capmj.sim.objects import ObjectSpec, resting_z
from capmj.sim.palette import COOL, WARM
from capmj.tasks.predicates import area_bounds
from capmj.tasks.protocol import Resample

GAP = 0.01
"""Minimum free distance (m) between two footprint circles."""
AREA_MARGIN = 0.02
"""A centre spawned inside (outside) a named area keeps this distance (m) from its border."""
BATCH = 32
TRIES = 256

DEFAULT_COLORS: tuple[str, ...] = (
    "blue", "red", "green", "orange", "yellow", "purple", "pink", "cyan", "brown", "gray", "white",
)
"""Colours the benchmark tasks draw from: the Tableau palette names.  The thesis extras (indigo,
violet, silver, gold, black) are left out of the default pool because they are hard to tell from
purple / gray / yellow in renders."""
WARM_COLORS: tuple[str, ...] = tuple(c for c in DEFAULT_COLORS if c in WARM)
COOL_COLORS: tuple[str, ...] = tuple(c for c in DEFAULT_COLORS if c in COOL)


def region_bounds(region: str | Bounds | Sequence[float]) -> Bounds:
    """From an area name ("top left"…, see :func:`predicates.area_bounds`), a ``Bounds`` or
    ``(xmin, xmax, ymin, ymax)``."""
    return Bounds(*area_bounds(region)) if isinstance(region, str) else Bounds.of(region)


WORKSPACE_BOUNDS = WORKSPACE
SPAWN_BOUNDS = Bounds(0.3, 0.7, -0.4, 0.4)
"""Default region for object centres (reachable part of the workspace)."""


def centre_bounds(radius: float, bounds: Bounds = SPAWN_BOUNDS) -> Bounds:
    """Where the centre of a footprint of ``radius`` may go: ``bounds`` ∩ workspace shrunk by it."""
    return bounds.intersect(WORKSPACE_BOUNDS.shrink(radius))


class Spawner:
    """Places objects at random collision-free poses; ids are 1..n in creation order.

    ``objects_so_far`` are already placed (their ids continue the numbering).  Every ``place``
    call draws candidate centres uniformly in the allowed rectangle (in batches of 32, at most
    ``tries`` candidates) and keeps the first whose footprint circle is at least ``gap`` away from
    every placed footprint; ``region`` restricts the centre to an area (kept ``AREA_MARGIN`` inside
    its border), ``avoid`` forbids centres in areas (grown by ``AREA_MARGIN``).  Yaw is uniform in
    [0, 2π) unless given.
    """

    def __init__(
        self,
        rng: np.random.Generator,
        objects_so_far: Iterable[ObjectSpec] = (),
        *,
        bounds: Bounds = SPAWN_BOUNDS,
        gap: float = GAP,
        tries: int = TRIES,
        area_margin: float = AREA_MARGIN,
    ) -> None:
        self.rng = rng
        self.bounds = bounds
        self.gap = gap
        self.tries = tries
        self.area_margin = area_margin
        self._objects: list[ObjectSpec] = list(objects_so_far)
        self._cx = [o.pos[0] for o in self._objects]
        self._cy = [o.pos[1] for o in self._objects]
        self._cr = [o.footprint_radius for o in self._objects]

    @property
    def objects(self) -> tuple[ObjectSpec, ...]:
        return tuple(self._objects)

    @property
    def next_id(self) -> int:
        return max((o.obj_id for o in self._objects), default=0) + 1

    def sample_xy(
        self,
        radius: float,
        region: "str | Bounds | Sequence[float] | None" = None,
        avoid: Iterable["str | Bounds | Sequence[float]"] = (),
        extent: tuple[float, float] | None = None,
    ) -> tuple[float, float]:
        """A free centre for a footprint of ``radius``; raises ``Resample`` after ``tries``.

        ``extent`` (the footprint's axis-aligned half sizes, known when the yaw is fixed) keeps
        the footprint itself inside the workspace instead of its circumscribed circle."""
        if extent is None:
            b = centre_bounds(radius, self.bounds)
        else:
            w = WORKSPACE_BOUNDS
            b = self.bounds.intersect(Bounds(w.xmin + extent[0], w.xmax - extent[0], w.ymin + extent[1], w.ymax - extent[1]))
        if region is not None:
            b = b.intersect(region_bounds(region).shrink(self.area_margin))
        if b.empty:
            raise Resample(f"no room for a footprint of radius {radius:.3f} in {region!r}")
        avoid_b = [region_bounds(a) for a in avoid]
        cx, cy, cr = np.asarray(self._cx), np.asarray(self._cy), np.asarray(self._cr) + radius + self.gap
        for _ in range(max(1, self.tries // BATCH)):
            xs = self.rng.uniform(b.xmin, b.xmax, BATCH)
            ys = self.rng.uniform(b.ymin, b.ymax, BATCH)
            ok = np.ones(BATCH, dtype=bool)
            if len(cx):
                d = np.hypot(xs[:, None] - cx[None, :], ys[:, None] - cy[None, :])
                ok &= np.all(d >= cr[None, :], axis=1)
            for a in avoid_b:
                ok &= ~a.contains(xs, ys, self.area_margin)
            if ok.any():
                k = int(np.argmax(ok))
                return float(xs[k]), float(ys[k])
        raise Resample(f"could not place a footprint of radius {radius:.3f} after {self.tries} tries")

    def place(
        self,
        kind: str,
        color: str,
        *,
        size: str | None = None,
        scale: float = 1.0,
        region: "str | Bounds | Sequence[float] | None" = None,
        avoid: Iterable["str | Bounds | Sequence[float]"] = (),
        yaw: float | None = None,
    ) -> ObjectSpec:
        """Create and place one object resting on the table; returns its spec (id = next id).

        With ``yaw`` given, the footprint square at that yaw (not its circumscribed circle) must
        lie inside the workspace: how a 3× zone (0.36 m side) fits the 0.5 m deep table."""
        probe = ObjectSpec(self.next_id, kind, color, (0.0, 0.0, 0.0), yaw=yaw or 0.0, size=size, scale=scale)  # type: ignore[arg-type]
        x, y = self.sample_xy(probe.footprint_radius, region, avoid, None if yaw is None else probe.xy_extent)
        if yaw is None:
            yaw = float(self.rng.uniform(0.0, 2 * math.pi))
        spec = probe.moved((x, y, resting_z(kind, size, scale)), yaw)
        self._objects.append(spec)
        self._cx.append(x)
        self._cy.append(y)
        self._cr.append(spec.footprint_radius)
        return spec

    def block(self, color: str, size: str = "small", **kw) -> ObjectSpec:
        return self.place("block", color, size=size, **kw)

    def zone(self, color: str, scale: float = 1.0, **kw) -> ObjectSpec:
        return self.place("zone", color, scale=scale, **kw)

    def bowl(self, color: str, **kw) -> ObjectSpec:
        return self.place("bowl", color, **kw)

    def reserve(self, xy: Sequence[float], radius: float) -> None:
        """Keep a circle free of later placements (e.g. target spots a task needs empty at reset)."""
        self._cx.append(float(xy[0]))
        self._cy.append(float(xy[1]))
        self._cr.append(float(radius))

    def add(self, spec: ObjectSpec, radius: float | None = None) -> ObjectSpec:
        """Register an object the task placed itself (its id must be :attr:`next_id`); ``radius``
        replaces its footprint circle when the spec's circle is too small for its real shape."""
        if spec.obj_id != self.next_id:
            raise ValueError(f"object id {spec.obj_id} is not the next id {self.next_id}")
        self._objects.append(spec)
        self.reserve(spec.pos, spec.footprint_radius if radius is None else radius)
        return spec


# --------------------------------------------------------------------------------------- colours
def pick_colors(
    rng: np.random.Generator,
    n: int,
    pool: Sequence[str] = DEFAULT_COLORS,
    exclude: Iterable[str] = (),
) -> list[str]:
    """``n`` distinct colour names from ``pool`` minus ``exclude``, in random order."""
    ex = set(exclude)
    cands = [c for c in pool if c not in ex]
    if n > len(cands):
        raise ValueError(f"cannot pick {n} distinct colours from {len(cands)} available")
    idx = rng.choice(len(cands), size=n, replace=False)
    return [cands[int(i)] for i in idx]


def pick_color(rng: np.random.Generator, pool: Sequence[str] = DEFAULT_COLORS, exclude: Iterable[str] = ()) -> str:
    """One colour from ``pool`` minus ``exclude``."""
    return pick_colors(rng, 1, pool, exclude)[0]


# --------------------------------------------------------------------------------------- targets
def free_positions(
    objects: Iterable[ObjectSpec],
    region: "str | Bounds | Sequence[float]",
    radii: Sequence[float],
    *,
    gap: float = GAP,
    reserved: Iterable[tuple[Sequence[float], float]] = (),
    ignore: Iterable[int] = (),
    step: float = 0.005,
    margin: float = AREA_MARGIN,
) -> list[tuple[float, float]]:
    """Deterministic free centres inside ``region``, one per radius, for oracle targets.

    Scans a grid of pitch ``step`` over the region (shrunk by ``margin`` and kept inside the
    reachable ``SPAWN_BOUNDS``) and greedily takes, for each radius in turn, the free point
    closest to the region's centre that leaves ``gap`` to every object footprint (except ids in
    ``ignore``), to every ``reserved`` ``(xy, radius)`` circle and to the positions already taken.
    Raises ``ValueError`` when the region is full.
    """
    ign = set(ignore)
    circles = [(o.pos[0], o.pos[1], o.footprint_radius) for o in objects if o.obj_id not in ign]
    circles += [(float(p[0]), float(p[1]), float(r)) for p, r in reserved]
    out: list[tuple[float, float]] = []
    for r in radii:
        b = centre_bounds(r).intersect(region_bounds(region).shrink(margin))
        if b.empty:
            raise ValueError(f"region {region!r} has no room for radius {r}")
        xs = np.arange(b.xmin, b.xmax + 1e-9, step)
        ys = np.arange(b.ymin, b.ymax + 1e-9, step)
        gx, gy = np.meshgrid(xs, ys, indexing="ij")
        gx, gy = gx.ravel(), gy.ravel()
        ok = np.ones(gx.shape, dtype=bool)
        for cx, cy, cr in circles:
            ok &= np.hypot(gx - cx, gy - cy) >= cr + r + gap
        if not ok.any():
            raise ValueError(f"no free position of radius {r} left in {region!r}")
        c = b.center
        d = np.where(ok, np.hypot(gx - c[0], gy - c[1]), np.inf)
        k = int(np.argmin(d))
        out.append((float(gx[k]), float(gy[k])))
        circles.append((float(gx[k]), float(gy[k]), float(r)))
    return out


__all__ = [
    "AREA_MARGIN", "Bounds", "COOL_COLORS", "DEFAULT_COLORS", "GAP", "SPAWN_BOUNDS", "Spawner", "WARM_COLORS",
    "WORKSPACE_BOUNDS", "centre_bounds", "region_bounds", "free_positions", "pick_color", "pick_colors",
]
