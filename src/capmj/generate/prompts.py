"""The generator's prompt files (``prompts/generator/``), filled with ``string.Template``.

Prompts are data: edit them without touching code; ``CAPMJ_PROMPTS_DIR`` points elsewhere as for
the planner prompts (the folder is found by :func:`capmj.agents.prompt_files.prompts_dir`, one
place).  ``$name`` placeholders are used instead of ``{}`` because prompts quote Python and JSON.
"""

from __future__ import annotations

import json
from pathlib import Path
from string import Template
from typing import Any

from capmj.agents.prompt_files import prompts_dir
from capmj.errors import ConfigError

FOLDER = "generator"
FILES = ("system.txt", "propose.txt", "propose_repair.txt", "pick.txt", "task_api.txt", "examples.txt", "repair.txt", "reflect.txt", "proposals.json")


def generator_dir() -> Path:
    return prompts_dir() / FOLDER


def read(name: str) -> str:
    path = generator_dir() / name
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"generator prompt {path} not found (set CAPMJ_PROMPTS_DIR to a capmj prompts folder)") from None


def render(file: str, /, **values: Any) -> str:
    """Prompt file ``file`` with every ``$placeholder`` filled; a missing value is a ConfigError."""
    try:
        return Template(read(file)).substitute({k: str(v) for k, v in values.items()}).strip()
    except KeyError as e:
        raise ConfigError(f"generator prompt {file} needs a value for ${e.args[0]}") from None


def proposal_examples() -> dict[str, list[dict[str, Any]]]:
    """Accepted and rejected proposal examples shown when proposing."""
    data = json.loads(read("proposals.json"))
    return {"accepted": list(data.get("accepted", [])), "rejected": list(data.get("rejected", []))}


__all__ = ["FILES", "generator_dir", "proposal_examples", "read", "render"]
