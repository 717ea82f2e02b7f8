"""Learning-agent interfaces over the bench's world: a dm_env environment, a Gymnasium wrapper
(``capmj[gym]``) and the oracle as a policy.  See docs/learning.md.

Importing registers nothing with Gymnasium: call :func:`register` (or use the
``"capmj.envs.gym_ids:capmj/<task>-v0"`` id form).
"""

from capmj.envs.tabletop import EnvConfig, TabletopEnv


def register() -> list[str]:
    """Register ``capmj/<task>-v0`` with Gymnasium for every installed task (idempotent; needs the
    ``gym`` extra); returns the ids."""
    from capmj.envs.gym_env import register_all

    return register_all()


__all__ = ["EnvConfig", "TabletopEnv", "register"]
