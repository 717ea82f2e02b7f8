"""Configuration of one generator run: what to ask for, which model, how hard to check.

Frozen and validated at construction, so a bad flag fails before any LLM call or process start
with a one-line :class:`~capmj.errors.ConfigError` naming the valid choices.
"""

from __future__ import annotations

import datetime as _dt
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from capmj.confine.jail import Limits
from capmj.confine.manifest import GENERATED_TAG
from capmj.errors import ConfigError
from capmj.llm.config import DEFAULT_TIMEOUT_S
from capmj.taskcheck import DEFAULT_ACCEPT_RATE, DEFAULT_SEEDS

MODES = ("bottom-up", "top-down")
NAME_RE = re.compile(r"^[a-z][a-z0-9]*(-[a-z0-9]+)+$")
_PACKAGE_RE = re.compile(r"^[a-z][a-z0-9]*([-_][a-z0-9]+)*$")


def default_package() -> str:
    """``capmj-generated-<date>`` (UTC)."""
    return f"capmj-generated-{_dt.datetime.now(_dt.timezone.utc):%Y-%m-%d}"


@dataclass(frozen=True)
class GenerateConfig:
    """One run of the generator (the CLI flags, one field each)."""

    mode: Literal["bottom-up", "top-down"]
    model: str
    out: Path
    n: int = 1
    name: str | None = None
    description: str | None = None
    api_base: str | None = None
    temperature: float = 0.0
    package: str = field(default_factory=default_package)
    seeds: int = DEFAULT_SEEDS
    accept_rate: float = DEFAULT_ACCEPT_RATE
    workers: int = 1
    cache_dir: Path | None = None
    timeout_s: float = DEFAULT_TIMEOUT_S
    max_tokens: int = 4096
    limits: Limits = Limits()

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ConfigError(f"unknown --mode {self.mode!r}; valid modes: {', '.join(MODES)}")
        if self.mode == "top-down":
            if not self.name or not self.description:
                raise ConfigError("--mode top-down needs --name NAME and --description TEXT")
            if not NAME_RE.match(self.name):
                raise ConfigError(f"--name {self.name!r} must be kebab-case, e.g. 'stack-red-blocks'")
        elif self.name or self.description:
            raise ConfigError("--name/--description belong to --mode top-down; bottom-up proposes its own tasks")
        if self.n < 1:
            raise ConfigError(f"--n must be >= 1, got {self.n}")
        if self.seeds < 1:
            raise ConfigError(f"--seeds must be >= 1, got {self.seeds}")
        if not 0.0 < self.accept_rate <= 1.0:
            raise ConfigError(f"--accept-rate must be in (0, 1], got {self.accept_rate}")
        if self.workers < 1:
            raise ConfigError(f"--workers must be >= 1, got {self.workers}")
        if not 0.0 <= self.temperature <= 2.0:
            raise ConfigError(f"--temperature must be in [0, 2], got {self.temperature}")
        if not _PACKAGE_RE.match(self.package):
            raise ConfigError(f"--package {self.package!r} must be a distribution name like 'capmj-generated-x'")
        object.__setattr__(self, "out", Path(self.out))
        if self.out.exists() and (not self.out.is_dir() or any(self.out.iterdir())):
            raise ConfigError(f"--out {self.out} exists and is not an empty folder; choose a new one")

    @property
    def import_name(self) -> str:
        """The Python package of the plugin (``capmj-generated-x`` -> ``capmj_generated_x``)."""
        return self.package.replace("-", "_")

    def module_of(self, task_name: str) -> str:
        """The dotted module a task runs under, at its checks and once installed alike."""
        return f"{self.import_name}.{module_name(task_name)}"


def module_name(task_name: str) -> str:
    """The module (file stem) of a generated task: its kebab-case name in snake case."""
    return task_name.replace("-", "_")


__all__ = ["GENERATED_TAG", "GenerateConfig", "Limits", "MODES", "NAME_RE", "default_package", "module_name"]
