"""The final top-down view of an episode as a small PNG, made by the worker when the episode ends.

The picture is the orthographic ``top`` camera's colour image of the workspace (the heightmap
camera, :meth:`capmj.sim.cameras.CameraRig.heightmap`) with every object at the pose the episode
recorded as final (``final_poses``): the task's scene of (task, seed) is built again, its objects
put at those poses (:meth:`~capmj.sim.world.World.place_objects`, no physics step) and drawn
without the arm, whose final pose the record does not hold.  Oriented as seen from the front
camera: the robot's side at the top, +y to the right.  Pure function of (task, seed, final poses).

Only failed episodes get one (the report's failure gallery shows them); a thumbnail that cannot be
made (no GL, a task that no longer builds) is skipped, never the episode's failure.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

from capmj.atomic import atomic_write

__all__ = ["make_thumbnail", "render_top_view", "write_thumbnail"]

def render_top_view(task: Any, seed: int, final_poses: Mapping[str, Sequence[float]]) -> Any:
    """The top-down colour image (uint8, rows = x from the robot's side, columns = y ascending) of
    the scene of (task, seed) with its movable objects at ``final_poses`` (name -> x y z qw qx qy qz)."""
    from capmj.sim.cameras import CameraRig
    from capmj.sim.state import Pose
    from capmj.sim.world import World
    from capmj.tasks.protocol import make_scene

    world = World(make_scene(task, seed).objects)
    by_name = {o.name: o.obj_id for o in world.objects}
    world.place_objects({by_name[name]: Pose.of(v[:3], v[3:7]) for name, v in final_poses.items()
                         if name in by_name and by_name[name] in world.movable_ids})
    with CameraRig(world) as rig:  # drawn under the process's render lock (capmj.sim.gl)
        colour = rig.heightmap(include_robot=False).colormap  # rows = y ascending, columns = x ascending
    return colour.transpose(1, 0, 2)


def write_thumbnail(path: str | Path, task: Any, seed: int, final_poses: Mapping[str, Sequence[float]]) -> Path:
    """Render :func:`render_top_view` and write it to ``path`` as PNG (atomically); returns ``path``."""
    from capmj.sim.image_colour import to_png

    png = to_png(render_top_view(task, seed, final_poses))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path, mode="wb") as f:
        f.write(png)
    return path


def make_thumbnail(path: str | Path | None, task: Any, record: Mapping[str, Any]) -> bool:
    """The worker's hook: write the thumbnail of a failed episode's ``record`` (a result dict with
    ``seed``, ``success`` and ``final_poses``) to ``path``.  True when one was written; False for a
    successful episode, no path, no final poses, or any error while rendering (never raised)."""
    if path is None or record.get("success") or not record.get("final_poses"):
        return False
    try:
        write_thumbnail(path, task, int(record["seed"]), record["final_poses"])
    except Exception:  # noqa: BLE001 - a picture for the report must never fail an episode
        return False
    return True
