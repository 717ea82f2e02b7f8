"""The LLM task generator (``python -m capmj.generate``): GenSim-style bottom-up / top-down task
writing, judged by physics, delivered as an installable plugin package.  See docs/generate.md.

Modules: :mod:`config` (the run), :mod:`library` (installed tasks as examples, API reference),
:mod:`prompts` (``prompts/generator/``), :mod:`conversation` (recorded multi-turn chat),
:mod:`static` (AST checks), :mod:`isolate` (the checks of a candidate whose code runs in the jail),
:mod:`candidate` (one candidate's stages), :mod:`package` (the plugin package), :mod:`run`, :mod:`cli`.
"""

from capmj.generate.config import GENERATED_TAG, GenerateConfig, Limits
from capmj.generate.run import RunResult, generate

__all__ = ["GENERATED_TAG", "GenerateConfig", "Limits", "RunResult", "generate"]
