"""Learning-agent interfaces over the bench's world: a dm_env environment, a Gymnasium wrapper
(``capmj[gym]``) and the oracle as a policy.  See docs/learning.md."""

from capmj.envs.tabletop import EnvConfig, TabletopEnv

__all__ = ["EnvConfig", "TabletopEnv"]
