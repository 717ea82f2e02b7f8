"""Importing this module registers ``capmj/<task>-v0`` with Gymnasium for every installed task.

It exists for Gymnasium's ``"module:env-id"`` form, which imports a module so that it registers its
environments: ``gymnasium.make("capmj.envs.gym_ids:capmj/stack-all-blocks-on-a-zone-v0")``.  It is
the one capmj module that does work at import (``tests/test_import_effects.py`` lists it); elsewhere
call :func:`capmj.envs.register`.
"""

from capmj.envs.gym_env import register_all

IDS: tuple[str, ...] = tuple(register_all())
"""The ids registered at import."""
