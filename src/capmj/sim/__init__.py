"""The MuJoCo world: scene building, weld suction, motion, pick-and-place, cameras.

This layer knows nothing of tasks or LLMs.
"""
