"""The run manifest in ``config.json``: everything that decides a run's numbers, to compare runs.

Recorded: capmj's git revision and dirty flag (when run from a checkout), the versions of every
package that shapes results, sha256 of every prompt file and every task plugin module used, the
model string and the API base *host* (never a key, never the full URL's credentials), what the
planner API reads (``perception``: ``state`` or the perceiver's name, :mod:`capmj.agents.api.perceived`), the
sandbox, simulation and LLM budgets, ``PYTHONHASHSEED``, and for ``--interaction multi`` the
``interaction`` (its feedback, turn limit and describing model; absent from single-turn manifests), and
for ``--policy tools`` the ``policy`` (with its turn limit; absent under code), and the planner API
level with or without the prompt's examples (``api``: ``{"level", "examples"}`` for ``--api low`` or
``--examples none``; absent at the defaults, high and full).  :func:`differences` lists the
manifest entries in which combined runs disagree, for ``report`` to warn about.
"""

from __future__ import annotations

import dataclasses
import hashlib
import inspect
import os
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence
from urllib.parse import urlsplit

import capmj
from capmj.agents.factory import agent_setting, has_setting
from capmj.agents.prompt_files import load_prompt, prompts_dir
from capmj.tasks import registry

__all__ = ["MANIFEST_KEYS", "build_manifest", "differences", "git_state", "package_versions", "run_manifest",
           "sha256_file"]

PACKAGES = ("capmj", "mujoco", "dm-control", "numpy", "shapely", "litellm", "trimesh", "rerun-sdk", "openai",
            "httpx")
MANIFEST_KEYS = ("git", "packages", "prompts", "task_modules", "model", "api_host", "perception", "budgets",
                 "hash_seed", "interaction", "policy", "api")
"""Entries compared between runs (everything but timestamps, price and cache location)."""


def sha256_file(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def package_versions() -> dict[str, str]:
    out = {"python": platform.python_version(), "platform": platform.platform()}
    for dist in PACKAGES:
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "not installed"
    return out


def git_state(start: str | Path | None = None) -> dict[str, Any] | None:
    """``{"revision", "dirty"}`` of the checkout capmj is imported from; None if not a checkout."""
    root = Path(start) if start is not None else Path(capmj.__file__).resolve().parents[2]
    if not (root / ".git").exists():
        return None
    try:
        rev = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                             timeout=20, check=True).stdout.strip()
        status = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                                capture_output=True, text=True, timeout=20, check=True).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    return {"revision": rev, "dirty": bool(status.strip()), "root": str(root)}


def _prompt_hashes(folder: Path | None) -> dict[str, str]:
    if folder is None or not folder.is_dir():
        return {}
    return {str(p.relative_to(folder)): sha256_file(p) for p in sorted(folder.rglob("*"))
            if p.is_file() and "__pycache__" not in p.parts}


def _task_module_hashes(tasks: Iterable[Any]) -> dict[str, str]:
    """sha256 of every module of the packages the tasks come from (helpers like common.py too)."""
    out: dict[str, str] = {}
    for task in tasks:
        try:
            src = Path(inspect.getsourcefile(type(task)) or "")
        except (TypeError, OSError):
            continue
        if not src.is_file():
            continue
        module = type(task).__module__
        top = module.split(".")[0]
        pkg = sys.modules.get(top)
        pkg_file = getattr(pkg, "__file__", None)
        files = ([Path(pkg_file).parent / f for f in sorted(os.listdir(Path(pkg_file).parent)) if f.endswith(".py")]
                 if pkg_file and Path(pkg_file).name == "__init__.py" else [src])
        for f in files:
            name = f"{top}/{f.name}" if pkg_file and Path(pkg_file).name == "__init__.py" else module
            out[name] = sha256_file(f)
    return dict(sorted(out.items()))


def _asdict(v: Any) -> Any:
    return dataclasses.asdict(v) if dataclasses.is_dataclass(v) and not isinstance(v, type) else v


def build_manifest(agent: Any, task_objects: Sequence[Any]) -> dict[str, Any]:
    """The manifest of a run of ``agent`` over ``task_objects``."""
    from capmj.agents.base import Budget
    from capmj.sim.motion_config import MotionConfig

    model = getattr(agent, "model", None)
    cfg = getattr(agent, "config", None)
    api_base = getattr(cfg, "api_base", None)
    host = urlsplit(api_base).hostname if api_base else None
    port = urlsplit(api_base).port if api_base else None
    prompts: dict[str, str] = {}
    stops: dict[str, list[str]] = {}
    if getattr(agent, "name", "") in ("llm", "reference"):
        folder = Path(agent_setting(agent, "prompts_dir") or prompts_dir())
        prompts = _prompt_hashes(folder)
        stops = {p.stem: list(load_prompt(p.name, folder).stop) for p in sorted(folder.glob("*.py"))}
    budgets: dict[str, Any] = {"episode": _asdict(agent_setting(agent, "budget") or Budget())}
    for name in ("plan_budget", "lmp_budget", "limits"):
        if has_setting(agent, name):
            budgets[name] = _asdict(agent_setting(agent, name))
    if cfg is not None:
        budgets["llm"] = {"timeout_s": cfg.timeout_s, "max_retries": cfg.max_retries, "max_tokens": cfg.max_tokens,
                          "temperature": cfg.temperature, "stream": cfg.stream, "stop": stops}
    price = agent_setting(agent, "price")
    return {
        "git": git_state(),
        "packages": package_versions(),
        "prompts": prompts,
        "task_modules": _task_module_hashes(task_objects),
        "model": model,
        "api_host": f"{host}:{port}" if host and port else host,
        "perception": agent_setting(agent, "perception") or "state",  # the oracle reads the truth
        "budgets": budgets,
        "price": _asdict(price),
        "cache_dir": str(cfg.cache_dir) if cfg is not None and cfg.cache_dir is not None else None,
        "hash_seed": os.environ.get("PYTHONHASHSEED"),
        "motion": _asdict(MotionConfig()),  # every move checked and planned around obstacles, or not
        **_interaction(agent),
        **_policy(agent),
        **_api_level(agent),
    }


def _interaction(agent: Any) -> dict[str, Any]:
    """``interaction`` of a multi-turn LLM agent (``{"interaction": {"mode": "multi", "feedback", "max_turns",
    "describe_model"}}``); nothing for every other agent, so single-turn manifests stay as they were."""
    if agent_setting(agent, "interaction") != "multi":
        return {}
    return {"interaction": {"mode": "multi", "feedback": agent_setting(agent, "feedback"),
                            "max_turns": agent_setting(agent, "max_turns"),
                            "describe_model": agent_setting(agent, "describe_model")}}


def _policy(agent: Any) -> dict[str, Any]:
    """``policy`` of an LLM agent calling the API as tools (``{"policy": {"mode": "tools", "max_turns"}}``);
    nothing for the code policy and every other agent, so their manifests stay as they were."""
    if agent_setting(agent, "policy") != "tools":
        return {}
    return {"policy": {"mode": "tools", "max_turns": agent_setting(agent, "max_turns")}}


def _api_level(agent: Any) -> dict[str, Any]:
    """``api`` of an agent at the low API level or without the prompt's examples (``{"api": {"level",
    "examples"}}``); nothing at the defaults (high, full) and for agents without them, so their
    manifests stay as they were."""
    level, examples = agent_setting(agent, "api") or "high", agent_setting(agent, "examples") or "full"
    if (level, examples) == ("high", "full"):
        return {}
    return {"api": {"level": level, "examples": examples}}


def _flat(prefix: str, v: Any, out: dict[str, Any]) -> None:
    if isinstance(v, Mapping) and v:
        for k, x in v.items():
            _flat(f"{prefix}.{k}", x, out)
    else:
        out[prefix] = v


def differences(manifests: Mapping[str, Mapping[str, Any] | None]) -> list[str]:
    """One sentence per manifest entry in which the runs (by folder name) differ."""
    flats: dict[str, dict[str, Any]] = {}
    missing = [name for name, m in manifests.items() if not m]
    for name, m in manifests.items():
        if m:
            flat: dict[str, Any] = {}
            for key in MANIFEST_KEYS:
                _flat(key, m.get(key), flat)
            flat.pop("git.root", None)
            flats[name] = flat
    out = [f"{name}: no run manifest (config.json from an older capmj)" for name in missing]
    if len(flats) < 2:
        return out
    keys = sorted(set().union(*flats.values()))
    for key in keys:
        values = {name: f.get(key, "(absent)") for name, f in flats.items()}
        if len({repr(v) for v in values.values()}) > 1:
            shown = ", ".join(f"{name}={_short(v)}" for name, v in values.items())
            out.append(f"{key} differs: {shown}")
    return out


def _short(v: Any) -> str:
    s = str(v)
    return s[:12] if len(s) == 64 and all(c in "0123456789abcdef" for c in s) else s


def run_manifest(agent: Any, task_names: Sequence[str], stored: Mapping[str, Any] | None) -> dict[str, Any]:
    """The manifest of a grid run; on a resume, warns (stderr) about what changed since."""
    manifest = build_manifest(agent, [registry.get_task(t) for t in task_names])
    if stored and stored.get("manifest"):
        for warning in differences({"stored run": stored["manifest"], "this resume": manifest}):
            print(f"capmj-bench: warning: resuming under different conditions: {warning}", file=sys.stderr)
    return manifest
