"""Prompt files: loading, ``#@`` metadata, rendering a question into the template.

A prompt file is a Python-styled file in ``prompts/`` (imports line, API docs, orientation notes,
rules, few-shot examples, then a ``<<QUESTION>>`` placeholder).  It is kept apart from the LMP
session because tests and benchmarks read prompt files without any LLM: they rebuild and execute
the few-shot examples and count prompt tokens.

Prompt files carry machine-readable metadata on lines that start with ``#@``: these are stripped
before a prompt is sent, and let tests rebuild the scene of every few-shot example and execute it::

    #@ example: stack_in_zone
    #@ scene: {"objects": [["zone", "red", [0.5, 0.3]], ["block", "blue", [0.4, -0.1]]], ...}
    #@ expect: ["movable small blue block with obj_id 2"]
    objects = [...]
    # the blue blocks.
    ret_val = ...
    #@ end
"""

from __future__ import annotations

import ast
import json
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

from capmj.errors import ConfigError
from capmj.resources import prompts_dir

__all__ = [
    "EXAMPLES",
    "META",
    "PLANNER_PROMPTS",
    "QUESTION",
    "Example",
    "PromptFile",
    "load_prompt",
    "planner_prompt",
    "load_system_prompt",
    "object_names",
    "prompts_dir",
]

QUESTION = "<<QUESTION>>"
"""Placeholder in a prompt file replaced by the question of one call."""

META = "#@"
"""Prefix of metadata lines in prompt files (stripped before sending)."""

PLANNER_PROMPTS: dict[str, str] = {"high": "planner", "low": "planner_low"}
"""The planner prompt file of each planner API level (``--api``)."""

EXAMPLES: tuple[str, ...] = ("full", "none")
"""``--examples``: the planner prompt with its few-shot examples, or without any (CaP-X's S4)."""


@dataclass(frozen=True)
class Example:
    """One few-shot example of a prompt file, with the metadata a test needs to execute it."""

    id: str
    body: str
    """The example as it appears in the prompt (valid Python)."""
    meta: Mapping[str, str]
    """Raw metadata values by key (``scene``, ``expect``, ``check``, ``call``...)."""
    line: int
    """1-based line of the ``#@ example:`` marker in the prompt file."""

    def json(self, key: str, default: Any = None) -> Any:
        """A metadata value parsed as JSON (``default`` when absent)."""
        raw = self.meta.get(key)
        if raw is None:
            return default
        try:
            return json.loads(raw)
        except json.JSONDecodeError as exc:
            raise ConfigError(f"example {self.id!r}: '#@ {key}:' is not JSON: {exc}") from None


@dataclass(frozen=True)
class PromptFile:
    """A parsed prompt file."""

    name: str
    path: Path
    raw: str
    template: str
    """The prompt without metadata lines, still containing :data:`QUESTION`."""
    examples: tuple[Example, ...]
    meta: Mapping[str, str] = field(default_factory=dict)
    """File-level metadata: ``#@ key: value`` lines outside every example (e.g. ``stop``)."""

    def render(self, question: str) -> str:
        return self.template.replace(QUESTION, question.rstrip("\n"))

    def without_examples(self) -> "PromptFile":
        """The same prompt with every few-shot example left out (and no examples to run): what
        precedes, separates and follows them is unchanged."""
        return _parse_prompt(self.name, self.path, self.raw, keep_examples=False)

    @property
    def stop(self) -> tuple[str, ...]:
        """The stop sequences of this LMP (``#@ stop: [...]``, JSON): where the prompt's *next*
        example would begin, so a model that runs on after its answer is cut there."""
        raw = self.meta.get("stop")
        if raw is None:
            return ()
        try:
            value = json.loads(raw)
        except json.JSONDecodeError as exc:
            raise ConfigError(f"{self.path}: '#@ stop:' is not JSON: {exc}") from None
        if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
            raise ConfigError(f"{self.path}: '#@ stop:' must be a JSON list of non-empty strings")
        return tuple(value)


def _parse_prompt(name: str, path: Path, raw: str, keep_examples: bool = True) -> PromptFile:
    kept: list[str] = []
    examples: list[Example] = []
    meta: dict[str, str] = {}
    current: dict[str, Any] | None = None
    for lineno, line in enumerate(raw.splitlines(), start=1):
        if line.startswith(META):
            key, _, value = line[len(META):].strip().partition(":")
            key, value = key.strip(), value.strip()
            if key == "example":
                if current is not None:
                    raise ConfigError(f"{path}:{lineno}: example {value!r} starts inside "
                                      f"example {current['id']!r} (missing '#@ end')")
                current = {"id": value, "meta": {}, "lines": [], "line": lineno}
            elif key == "end":
                if current is None:
                    raise ConfigError(f"{path}:{lineno}: '#@ end' outside an example")
                body = "\n".join(current["lines"]).strip("\n") + "\n"
                examples.append(Example(current["id"], body, dict(current["meta"]), current["line"]))
                current = None
            elif current is not None:
                current["meta"][key] = value
            else:
                meta[key] = value
            continue
        if current is not None:
            current["lines"].append(line)
            if not keep_examples:
                continue
        kept.append(line)
    if current is not None:
        raise ConfigError(f"{path}: example {current['id']!r} has no '#@ end'")
    template = re.sub(r"\n{3,}", "\n\n", "\n".join(kept)).strip("\n") + "\n"
    if QUESTION not in template:
        raise ConfigError(f"{path}: prompt has no {QUESTION} placeholder")
    ids = [e.id for e in examples]
    if len(set(ids)) != len(ids):
        raise ConfigError(f"{path}: duplicate example ids in {ids}")
    return PromptFile(name, path, raw, template, tuple(examples) if keep_examples else (), meta)


@lru_cache(maxsize=64)
def _load_cached(path: str, mtime_ns: int) -> PromptFile:
    p = Path(path)
    return _parse_prompt(p.stem, p, p.read_text(encoding="utf-8"))


def load_prompt(name: str, directory: Path | str | None = None) -> PromptFile:
    """Load ``<directory>/<name>.py`` (or ``name`` as given when it has a suffix)."""
    folder = Path(directory) if directory is not None else prompts_dir()
    path = folder / (name if Path(name).suffix else f"{name}.py")
    try:
        stat = path.stat()
    except FileNotFoundError:
        raise ConfigError(f"prompt file {path} not found (set CAPMJ_PROMPTS_DIR to the prompts "
                          "folder of a capmj checkout)") from None
    return _load_cached(str(path), stat.st_mtime_ns)


def planner_prompt(api: str = "high", examples: str = "full", directory: Path | str | None = None) -> PromptFile:
    """The planner prompt of an API level (:data:`PLANNER_PROMPTS`), with its examples or without
    (:data:`EXAMPLES`); an unknown level or choice is a ConfigError naming the valid ones."""
    if api not in PLANNER_PROMPTS:
        raise ConfigError(f"unknown API level {api!r}; valid levels: {', '.join(PLANNER_PROMPTS)}")
    if examples not in EXAMPLES:
        raise ConfigError(f"unknown examples choice {examples!r}; valid: {', '.join(EXAMPLES)}")
    prompt = load_prompt(PLANNER_PROMPTS[api], directory)
    return prompt if examples == "full" else prompt.without_examples()


def load_system_prompt(directory: Path | str | None = None, name: str = "system.txt") -> str:
    folder = Path(directory) if directory is not None else prompts_dir()
    try:
        return (folder / name).read_text(encoding="utf-8").strip()
    except FileNotFoundError:
        raise ConfigError(f"system prompt {folder / name} not found") from None


def object_names(text: str) -> list[str] | None:
    """The names of the first ``objects = [...]`` line of ``text`` (None when there is none)."""
    for line in text.splitlines():
        if line.startswith("objects = "):
            try:
                names = ast.literal_eval(line.partition("=")[2].strip())
            except (ValueError, SyntaxError, MemoryError, RecursionError):
                return None
            if isinstance(names, (list, tuple)):
                return [str(n) for n in names]
    return None
