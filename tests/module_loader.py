"""Load a Python file that is not on the import path (a ``benchmarks/`` script, a task candidate)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parent.parent
"""The repository root."""


def load_module(path: Path, name: str | None = None, *, register: bool = False) -> ModuleType:
    """Execute ``path`` as module ``name`` (default: its stem); ``register`` puts it in
    ``sys.modules`` first (needed by dataclasses defined in it)."""
    spec = importlib.util.spec_from_file_location(name or path.stem, path)
    assert spec is not None and spec.loader is not None, path
    module = importlib.util.module_from_spec(spec)
    if register:
        sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module
