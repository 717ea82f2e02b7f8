"""Static 3D geometry of an episode log: the table, the objects' shapes, the robot's meshes.

Everything here is logged once, ``static=True``, in the body frame of its entity; only transforms
change over time (see :mod:`capmj.log.recorder`).  Shapes come from the world's geom parts
(:meth:`capmj.sim.world.World.body_parts`: exact) when the world is attached, else from the object
specs (approximate).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

from capmj.log.paths import ROBOT, WORLD, object_entity
from capmj.sim.pose import xyzw, yaw_quat

if TYPE_CHECKING:
    from capmj.sim.objects import ObjectSpec
    from capmj.sim.parts import GeomPart
    from capmj.sim.world import World

GRIP_COLOR = [255, 140, 0]
"""The suction cup's colour while it holds an object (it is the model's dark grey otherwise)."""


def u8(rgba: "Sequence[float] | np.ndarray") -> list[int]:
    return [int(round(255 * max(0.0, min(1.0, float(c))))) for c in rgba]


def object_label(o: "ObjectSpec") -> str:
    """The object's diagnostic name (``small red block 3``), as tasks write it."""
    from capmj.tasks.predicates import short_label

    return short_label(o)


def log_table(rr: Any, rec: Any) -> None:
    rec.log(f"{WORLD}/table", rr.Boxes3D(centers=[[0.5, 0.0, -0.0004]], half_sizes=[[0.25, 0.5, 0.0003]],
                                         colors=[[140, 128, 115]], fill_mode="solid"), static=True)
    rec.log(f"{WORLD}/floor", rr.Boxes3D(centers=[[0.4, 0.0, -0.002]], half_sizes=[[0.8, 0.9, 0.001]],
                                         colors=[[64, 64, 69]], fill_mode="solid"), static=True)
    rec.log(WORLD, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)


def log_object_specs(rr: Any, rec: Any, objects: Sequence["ObjectSpec"]) -> None:
    """Approximate shapes and initial poses from the specs alone (no world attached)."""
    from capmj.sim.palette import rgba

    for o in objects:
        ent = object_entity(o.body)
        col = u8(rgba(o.color))
        hx, hy, hz = o.half_extents
        if o.kind == "bowl":
            shape = rr.Cylinders3D(lengths=[2 * hz], radii=[hx], colors=[col])
        elif o.kind == "ball":
            shape = rr.Ellipsoids3D(half_sizes=[[hx, hy, hz]], colors=[col], fill_mode="solid")
        else:
            shape = rr.Boxes3D(half_sizes=[[hx, hy, hz]], colors=[col], fill_mode="solid")
        rec.log(ent, shape, static=True)
        rec.log(ent, rr.Transform3D(translation=list(o.pos),
                                    quaternion=rr.Quaternion(xyzw=xyzw(yaw_quat(o.yaw)))))


def body_geoms(rr: Any, geoms: Sequence["GeomPart"], color: list[int] | None) -> list[Any]:
    """rerun archetypes for the box/cylinder/sphere geoms of one body, in its frame (names are
    not drawn here: :mod:`capmj.log.verdict3d` shows the names that matter)."""
    boxes: dict[str, list] = {"centers": [], "quaternions": [], "half_sizes": [], "colors": []}
    cyls: dict[str, list] = {"centers": [], "quaternions": [], "lengths": [], "radii": [], "colors": []}
    spheres: dict[str, list] = {"centers": [], "half_sizes": [], "colors": []}
    for g in geoms:
        size = g.size
        pos, quat = g.pos.tolist(), xyzw(g.quat)
        col = color or u8(g.rgba)
        if g.kind == "box":
            for k, v in zip(boxes, (pos, quat, size.tolist(), col)):
                boxes[k].append(v)
        elif g.kind == "cylinder":
            for k, v in zip(cyls, (pos, quat, 2 * float(size[1]), float(size[0]), col)):
                cyls[k].append(v)
        elif g.kind == "sphere":
            for k, v in zip(spheres, (pos, [float(size[0])] * 3, col)):
                spheres[k].append(v)
    parts = []
    for cls, fields in ((rr.Boxes3D, boxes), (rr.Cylinders3D, cyls), (rr.Ellipsoids3D, spheres)):
        if not fields["centers"]:
            continue
        # Leave out what equals the default (one geom at the body origin, one colour): every
        # component costs its schema in the file.
        if len(fields["centers"]) == 1 and not np.any(fields["centers"]) and \
                np.allclose(fields.get("quaternions", [[0, 0, 0, 1]]), [[0, 0, 0, 1]]):
            fields.pop("centers"), fields.pop("quaternions", None)
        if "quaternions" in fields:
            fields["quaternions"] = [rr.Quaternion(xyzw=q) for q in fields["quaternions"]]
        if all(c == fields["colors"][0] for c in fields["colors"]):
            fields["colors"] = fields["colors"][:1]
        parts.append(cls.from_fields(fill_mode="solid", **fields))
    return parts


def log_world_objects(rr: Any, rec: Any, world: "World") -> None:
    """Exact object shapes from the compiled model (specs as fallback for shapeless bodies)."""
    from capmj.sim.palette import rgba

    missing = []
    for o in world.objects:
        parts = body_geoms(rr, world.body_parts(o.body), u8(rgba(o.color)))
        if parts:
            rec.log(object_entity(o.body), *parts, static=True)
        else:
            missing.append(o)
    if missing:
        log_object_specs(rr, rec, missing)


def robot_entities(world: "World", links: Sequence[str]) -> dict[str, str]:
    """Entity path of each robot link.  A link without joints whose parent is another link (the
    suction tool on the wrist) is nested under its parent, so it needs no transform over time."""
    out: dict[str, str] = {}
    for name in links:
        link = world.link(name)
        if link.joints == 0 and link.parent in out:
            out[name] = f"{out[link.parent]}/{name}"
        else:
            out[name] = f"{ROBOT}/{name}"
    return out


def cup_entity(entities: Mapping[str, str]) -> str:
    from capmj.sim.robot import SUCTION_BODY

    return f"{entities.get(SUCTION_BODY, f'{ROBOT}/{SUCTION_BODY}')}/cup"


def log_robot(rr: Any, rec: Any, world: "World", entities: Mapping[str, str]) -> None:
    """The arm's link meshes (static, in link frames), the static transforms of nested links, and
    the suction tool's cylinders.  The cup cylinder goes to its own entity so that its colour can
    change while it grips."""
    from capmj.log.robot_mesh import cached_link_meshes
    from capmj.sim.robot import SUCTION_BODY

    for name, ent in entities.items():
        if ent != f"{ROBOT}/{name}":
            link = world.link(name)
            rec.log(ent, rr.Transform3D(translation=list(link.pos), quaternion=rr.Quaternion(xyzw=xyzw(link.quat))),
                    static=True)
    for lm in cached_link_meshes(world, tuple(n for n in entities if n != SUCTION_BODY)):
        rec.log(entities[lm.body], rr.Mesh3D(vertex_positions=lm.vertices, triangle_indices=lm.faces,
                                             vertex_normals=lm.normals, vertex_colors=lm.colors), static=True)
    if SUCTION_BODY not in entities:
        return
    others = [g for g in world.body_parts(SUCTION_BODY) if g.geom != world.cup_geom]
    parts = body_geoms(rr, others, None)
    if parts:
        rec.log(entities[SUCTION_BODY], *parts, static=True)
    cup = world.geom_part(world.cup_geom)  # shape static; colour and label over time (static components would hide them)
    rec.log(cup_entity(entities), rr.Cylinders3D.from_fields(
        centers=[cup.pos.tolist()], quaternions=[rr.Quaternion(xyzw=xyzw(cup.quat))],
        lengths=[2 * float(cup.size[1])], radii=[float(cup.size[0])], fill_mode="solid"), static=True)


def cup_color(rr: Any, rec: Any, world: "World", entities: Mapping[str, str], held: str | None) -> None:
    """Colour the cup (and label what it holds) from the current time on."""
    col = GRIP_COLOR if held else u8(world.geom_part(world.cup_geom).rgba)
    rec.log(cup_entity(entities), rr.Cylinders3D.from_fields(
        colors=[col], labels=[f"gripping {held}" if held else "suction cup"], show_labels=bool(held)))


__all__ = ["GRIP_COLOR", "body_geoms", "cup_color", "cup_entity", "robot_entities", "log_object_specs", "log_robot", "log_table",
           "log_world_objects", "object_label", "u8", "xyzw"]
