"""Layers depend downward: above ``sim/``, ``World``'s read API is the only door to MuJoCo.

``docs/architecture.md`` promises that nothing above ``sim/`` touches ``MjModel`` or ``MjData``.
This reads every module of the package outside ``sim/`` (and the built-in task plugins) as an AST
and fails on an ``import mujoco``, on ``.model``/``.data`` taken from a world, or on an attribute
that is a field of MuJoCo's structs (``xpos``, ``geom_rgba``, ``nbody``…) — save the few words
MuJoCo shares with ordinary code and the names of ``World``'s own API.
"""

from __future__ import annotations

import ast
from pathlib import Path

import mujoco
import pytest

from capmj.sim.world import World

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "src" / "capmj"

EXCEPTIONS: dict[str, str] = {}
"""Modules above ``sim/`` allowed through, each with the reason (path relative to ``src/capmj``)."""

COMMON_WORDS = {"act", "bind", "body", "camera", "key", "model", "names", "signature", "stat", "time", "warning",
                "data", "text", "light", "contact", "energy", "solver", "opt", "vis", "tuple", "numeric",
                "exclude", "pair", "plugin", "sensor", "texture", "material", "actuator", "joint", "site", "geom"}
"""MuJoCo field and method names that ordinary code uses for its own attributes."""
_m = mujoco.MjModel.from_xml_string("<mujoco/>")
MUJOCO_FIELDS = ({n for n in dir(_m) if not n.startswith("_")} | {n for n in dir(mujoco.MjData(_m)) if not n.startswith("_")}) \
    - COMMON_WORDS - {n for n in dir(World) if not n.startswith("_")}
WORLD_NAMES = {"world", "w", "_world"}


def _is_world(node: ast.expr) -> bool:
    return (isinstance(node, ast.Name) and node.id in WORLD_NAMES) or (
        isinstance(node, ast.Attribute) and node.attr in WORLD_NAMES)


def violations(source: str) -> list[str]:
    """Where a module reaches into MuJoCo: ``line: what``."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import) and any(a.name.split(".")[0] == "mujoco" for a in node.names):
            out.append(f"{node.lineno}: import mujoco")
        elif isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "mujoco" and not node.level:
            out.append(f"{node.lineno}: from {node.module} import")
        elif isinstance(node, ast.Attribute):
            if node.attr in ("model", "data") and _is_world(node.value):
                out.append(f"{node.lineno}: world.{node.attr}")
            elif node.attr in MUJOCO_FIELDS:
                out.append(f"{node.lineno}: .{node.attr}")
    return out


def _modules_above_sim() -> list[Path]:
    found = [p for p in PACKAGE.rglob("*.py")
             if p.relative_to(PACKAGE).parts[0] not in ("sim", "prompts", "mjcf")]
    return sorted(found + list((ROOT / "task_plugins").rglob("*.py")))


def test_the_checker_sees_each_way_in() -> None:
    src = ("import mujoco\nfrom mujoco import mj_step\n"
           "def f(world, ctx, self):\n"
           "    a = world.model.nbody\n    b = ctx.world.data.xpos[3]\n    c = self._world.data\n"
           "    d = world.state().poses  # fine\n    e = cfg.model  # an LLM model name: fine\n")
    assert sorted(violations(src)) == ["1: import mujoco", "2: from mujoco import", "4: .nbody", "4: world.model",
                                       "5: .xpos", "5: world.data", "6: world.data"]


@pytest.mark.parametrize("path", _modules_above_sim(), ids=lambda p: str(p.relative_to(ROOT)))
def test_nothing_above_sim_touches_mjmodel_or_mjdata(path: Path) -> None:
    rel = str(path.relative_to(PACKAGE)) if path.is_relative_to(PACKAGE) else str(path.relative_to(ROOT))
    found = violations(path.read_text(encoding="utf-8"))
    if rel in EXCEPTIONS:
        assert found, f"{rel} no longer reaches into MuJoCo: take it off EXCEPTIONS"
        return
    assert not found, f"{rel} reaches into MjModel/MjData (use World's read API): {found}"
