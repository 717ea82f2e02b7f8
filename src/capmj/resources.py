"""Data files shipped inside the package: the prompt folder and the world's MJCF files.

In the source tree they are the top-level ``prompts/`` and ``mjcf/`` folders; ``src/capmj/prompts``
and ``src/capmj/mjcf`` are symlinks to them, so an editable install and a built wheel (where the
folders are copied in as package data, see ``pyproject.toml``) find them at the same place:
``importlib.resources.files("capmj") / folder``.  Nothing here looks at the working directory.
"""

from __future__ import annotations

import os
from importlib.resources import files
from pathlib import Path

from capmj.errors import ConfigError

PROMPTS_ENV = "CAPMJ_PROMPTS_DIR"
"""Environment variable naming a prompt folder used instead of the packaged one."""


def packaged(folder: str) -> Path:
    """The on-disk path of a folder shipped inside the ``capmj`` package."""
    path = Path(str(files("capmj") / folder))
    if not path.is_dir():
        raise ConfigError(f"capmj's {folder}/ folder is missing at {path}; reinstall capmj "
                          "(a wheel ships it as package data, a source checkout links it from the top level)")
    return path


def prompts_dir() -> Path:
    """The prompt folder: ``$CAPMJ_PROMPTS_DIR`` when set, else the packaged ``prompts/``."""
    env = os.environ.get(PROMPTS_ENV, "").strip()
    return Path(env) if env else packaged("prompts")


def mjcf_path(name: str) -> Path:
    """An MJCF file of the world (``mjcf/<name>``), e.g. ``mjcf_path("table.xml")``."""
    path = packaged("mjcf") / name
    if not path.is_file():
        valid = sorted(p.name for p in packaged("mjcf").glob("*.xml"))
        raise ConfigError(f"no MJCF file {name!r}; valid files: {', '.join(valid)}")
    return path
