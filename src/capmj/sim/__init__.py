"""The MuJoCo world: scene building, weld suction, motion, pick-and-place, cameras.

This layer knows nothing of tasks or LLMs.

Importing this package selects the headless OpenGL default before any ``capmj.sim`` module imports
mujoco: ``MUJOCO_GL`` is set to ``egl`` when unset (``osmesa`` if only libOSMesa is present); a
user's own ``MUJOCO_GL`` is kept.  MuJoCo reads the variable only at its first import; if mujoco was
imported earlier without it (GLFW, no display), the camera rig loads EGL/OSMesa itself when PyOpenGL
is not yet bound to another platform.  See :mod:`capmj.sim.gl`.
"""

from capmj.sim.gl import set_default_backend as _set_default_backend

_set_default_backend()  # = os.environ.setdefault("MUJOCO_GL", "egl"), but never to a missing library
