"""Reading the world's MJCF files (``mjcf/``) into ``MjSpec`` and composing them.

Templates are attached with a name prefix (MuJoCo warns that an empty prefix may make the saved
XML ambiguous), then the names a composed model needs are set: an object template's body becomes
``obj<N>`` with geoms ``obj<N>_g0``…, the suction tool's body becomes ``suction``, and the table's
elements keep their own names.
"""

from __future__ import annotations

from functools import cache

import mujoco

from capmj.resources import mjcf_path


@cache
def _text(name: str) -> str:
    return mjcf_path(name).read_text(encoding="utf-8")


def load(name: str) -> mujoco.MjSpec:
    """A fresh spec of ``mjcf/<name>`` (the file is read once per process)."""
    return mujoco.MjSpec.from_string(_text(name))


def attach_body(parent: mujoco.MjsBody, template: mujoco.MjSpec, body: str, prefix: str,
                name: str, **frame: object) -> mujoco.MjsBody:
    """Attach a copy of ``template``'s body ``body`` under ``parent`` (in a frame with ``frame``'s
    pos/quat) with every name prefixed, and name the copied body ``name``."""
    copy = parent.add_frame(**frame).attach_body(template.body(body), prefix, "")
    copy.name = name
    return copy


def attach_frame_contents(spec: mujoco.MjSpec, template: mujoco.MjSpec, frame: str) -> None:
    """Attach ``template``'s frame ``frame`` to ``spec``'s world body, keeping its elements' names."""
    prefix = f"{frame}/"
    spec.worldbody.attach_frame(template.frame(frame), prefix, "")
    for group in (spec.geoms, spec.cameras, spec.lights, spec.sites, spec.bodies, spec.frames):
        for el in group:
            if el.name.startswith(prefix):
                el.name = el.name[len(prefix):]


__all__ = ["attach_body", "attach_frame_contents", "load"]
