"""The MuJoCo world: scene building, weld suction, motion, pick-and-place, cameras.

This layer knows nothing of tasks or LLMs.

Importing it (or any capmj module) changes nothing in the process: no ``MUJOCO_GL``, no GL probe.
The headless OpenGL backend is chosen when rendering starts (:mod:`capmj.sim.gl`): a user's
``MUJOCO_GL`` as given, else EGL or OSMesa, whichever a short probe finds working.
"""
