"""The public task checker: does a task object follow the protocol and does physics prove it sound?

Why it lives here and not in ``capmj.tasks``: two of its checks run real episodes with the
oracle through :func:`capmj.runner.run_episode`, and the layers only depend downward
(sim <- tasks <- agents <- runner/bench).  ``python -m capmj.tasks check`` is a thin, lazy entry
into this module; the task generator runs the very same :func:`check_task` on a jailed
:class:`~capmj.confine.proxy.ConfinedTask`, so plugin authors and the generator judge tasks by one
definition.

Checks, in order (a check runs only when every check before it passed; the rest are skipped):

``protocol``
    :func:`capmj.tasks.registry.validate_task` (attributes, methods, the three-part docstring),
    the entry-point name if given, and any tags the caller requires.  A task that still names its
    scene method ``generate`` passes with a note, unless the caller refuses deprecated names
    (the generator does: what it writes today must not be born deprecated).
``scenes``
    the same seed gives the same scene twice; different seeds do not all give one scene;
    ``scene.info`` is JSON; ``oracle_goals`` returns :class:`OracleGoal` steps whose targets lie
    above the workspace.
``goal_text``
    every colour, ``<colour> <kind>``, kind, size and warm/cool word of the goal text names
    something present in the scene (a text naming an absent colour cannot be solved or judged).
``not_solved_at_reset``
    the predicate rejects the spawn state, and the Ravens matching reward there is below 1.
``do_nothing_fails``
    an episode whose agent does nothing (real physics, settled; first seed) is judged a failure.
``oracle_solves``
    the oracle succeeds on at least ``accept_rate`` of the distinct seeds (the rate is reported).
``reward_agrees``
    on every oracle episode the Ravens matching reward of the final state is 1 exactly when the
    predicate says success (the two definitions of "done" must not disagree).
"""

from __future__ import annotations

import json
import re
import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

from capmj.errors import ConfigError
from capmj.sim.bounds import WORKSPACE
from capmj.sim.objects import BLOCK_SIZES, KINDS
from capmj.sim.palette import COLOR_NAMES, COOL, WARM
from capmj.sim.state import SceneState
from capmj.taskcheck.report import CHECKS, CheckResult, Report
from capmj.tasks.predicates import ravens_reward
from capmj.tasks.protocol import OracleGoal, Scene, Task, make_scene
from capmj.tasks.registry import validate_task
from capmj.tasks.scene_method import DEPRECATED_SCENE_METHOD, SCENE_METHOD, uses_deprecated_name

DEFAULT_SEEDS = 5
DEFAULT_ACCEPT_RATE = 0.8
REWARD_ONE = 1.0 - 1e-6
SIZE_WORDS: dict[str, str] = {"big": "big", "bigger": "big", "biggest": "big",
                              "small": "small", "smaller": "small", "smallest": "small", "tiny": "tiny"}
"""Goal-text words that claim a block of a size exists."""
_TARGET_MARGIN = 0.01


@dataclass(frozen=True)
class CheckConfig:
    """How hard to check: ``seeds`` distinct scene seeds, the oracle's minimum success share,
    the entry-point ``name`` the task must carry (None: any), tags it must have, and whether a
    protocol name kept only for old plugins (``generate`` for ``sample_scene``) is accepted."""

    seeds: tuple[int, ...] = tuple(range(DEFAULT_SEEDS))
    accept_rate: float = DEFAULT_ACCEPT_RATE
    name: str | None = None
    required_tags: frozenset[str] = frozenset()
    allow_deprecated: bool = True

    def __post_init__(self) -> None:
        if not self.seeds or len(set(self.seeds)) != len(self.seeds):
            raise ConfigError(f"seeds must be distinct and non-empty, got {self.seeds}")
        if not 0.0 < self.accept_rate <= 1.0:
            raise ConfigError(f"accept_rate must be in (0, 1], got {self.accept_rate}")

    @classmethod
    def first(cls, k: int, **kw: Any) -> "CheckConfig":
        """Seeds 0 … k-1."""
        if k < 1:
            raise ConfigError(f"the number of seeds must be >= 1, got {k}")
        return cls(seeds=tuple(range(k)), **kw)


class IdleAgent:
    """An agent that does nothing: the do-nothing episode."""

    name = "idle"
    model = None

    def act(self, ctx: Any) -> None:
        return None


def _word(word: str, text: str) -> bool:
    return re.search(rf"\b{re.escape(word)}s?\b", text) is not None


def goal_text_problems(scene: Scene) -> list[str]:
    """What the goal text names that the scene lacks (empty when everything it names exists)."""
    text = scene.goal.lower()
    objs = scene.objects
    out: list[str] = []
    colours = {o.color for o in objs}
    for c in COLOR_NAMES:
        if _word(c, text) and c not in colours:
            out.append(f"names the colour {c!r} but no object is {c}")
    kinds = "|".join(KINDS)
    for c, kind in re.findall(rf"\b([a-z]+) ({kinds})s?\b", text):
        if c in COLOR_NAMES and c in colours and not any(o.color == c and o.kind == kind for o in objs):
            out.append(f"names a {c} {kind} but there is none")
    for kind in KINDS:
        if _word(kind, text) and not any(o.kind == kind for o in objs):
            out.append(f"names a {kind} but the scene has none")
    sizes = {o.size for o in objs if o.kind == "block"}
    for w, size in SIZE_WORDS.items():
        if size in BLOCK_SIZES and re.search(rf"\b{w}\b", text) and size not in sizes:
            out.append(f"says {w!r} but there is no {size} block")
    blocks = {o.color for o in objs if o.kind == "block"}
    for w, group in (("warm", WARM), ("cool", COOL)):
        if re.search(rf"\b{w}\b", text) and not blocks & group:
            out.append(f"says {w!r} but no block has a {w} colour")
    return out


def _scenes(task: Task, cfg: CheckConfig) -> tuple[str, dict[str, Any], list[str]]:
    problems: list[str] = []
    scenes = {}
    for s in cfg.seeds:
        a, b = make_scene(task, s), make_scene(task, s)
        if not isinstance(a, Scene):
            return "", {}, [f"{SCENE_METHOD} returned {type(a).__name__}, not a Scene"]
        if a != b:
            problems.append(f"seed {s} gave two different scenes")
        scenes[s] = a
        try:
            json.dumps(dict(a.info))
        except (TypeError, ValueError) as e:
            problems.append(f"seed {s}: scene.info is not JSON-serialisable ({e})")
        goals = task.oracle_goals(a)
        if not goals or not all(isinstance(g, OracleGoal) for g in goals):
            problems.append(f"seed {s}: oracle_goals must return a non-empty list of OracleGoal")
            continue
        for g in goals:
            for t in g.targets:
                x, y, z = t.pos
                inside = bool(WORKSPACE.contains(x, y, _TARGET_MARGIN)) and WORKSPACE.zmin < z <= WORKSPACE.zmax
                if not inside:
                    problems.append(f"seed {s}: oracle target {tuple(round(v, 3) for v in t.pos)} is outside the workspace")
    layouts = {tuple((o.kind, o.color, o.pos) for o in sc.objects) for sc in scenes.values()}
    if len(cfg.seeds) > 1 and len(layouts) == 1:
        problems.append(f"all {len(cfg.seeds)} seeds gave the same scene ({SCENE_METHOD} ignores its rng)")
    goal_texts = sorted({sc.goal for sc in scenes.values()})
    return f"{len(cfg.seeds)} seeds, {len(layouts)} distinct layouts", {"goals": goal_texts[:5]}, problems


def _goal_text(task: Task, cfg: CheckConfig) -> tuple[str, dict[str, Any], list[str]]:
    problems = []
    for s in cfg.seeds:
        scene = make_scene(task, s)
        problems += [f"seed {s}: goal {scene.goal!r} {p}" for p in goal_text_problems(scene)]
    return "every colour/size/kind word names an object of the scene", {}, problems


def _not_solved_at_reset(task: Task, cfg: CheckConfig) -> tuple[str, dict[str, Any], list[str]]:
    problems = []
    for s in cfg.seeds:
        scene = make_scene(task, s)
        start = SceneState.from_specs(scene.objects)
        if task.evaluate(scene, start).success:
            problems.append(f"seed {s}: the spawn state is already a success")
        reward = ravens_reward(task.oracle_goals(scene), start)
        if reward >= REWARD_ONE:
            problems.append(f"seed {s}: the oracle goals are already met at reset (Ravens reward {reward:.2f})")
    return "the spawn state is judged unsolved", {}, problems


def _do_nothing_fails(task: Task, cfg: CheckConfig) -> tuple[str, dict[str, Any], list[str]]:
    from capmj.runner import run_episode  # the runner (agents, physics) only when this check runs

    s = cfg.seeds[0]  # one episode: the spawn state of every seed is already judged statically
    r = run_episode(task, s, IdleAgent())
    problems = [f"seed {s}: {r.error}"] if r.error else []
    if r.success:
        problems.append(f"seed {s}: doing nothing is judged a success")
    return f"a do-nothing episode (seed {s}, settled physics) fails", {"progress": r.progress}, problems


def _oracle_runs(task: Task, cfg: CheckConfig, cache: dict[str, Any]) -> list[dict[str, Any]]:
    if "oracle" not in cache:
        from capmj.agents.oracle import OracleAgent
        from capmj.runner import run_episode

        agent = OracleAgent()
        cache["oracle"] = [
            {"seed": r.seed, "success": r.success, "reward": r.reward, "progress": r.progress,
             "primitives": r.primitives, "error": r.error, "diagnostics": list(r.diagnostics[:3])}
            for r in (run_episode(task, s, agent) for s in cfg.seeds)]
    return cache["oracle"]


def _oracle_solves(task: Task, cfg: CheckConfig, cache: dict[str, Any]) -> tuple[str, dict[str, Any], list[str]]:
    runs = _oracle_runs(task, cfg, cache)
    wins = sum(r["success"] for r in runs)
    rate = wins / len(runs)
    detail = f"oracle solved {wins}/{len(runs)} seeds (rate {rate:.2f}, need >= {cfg.accept_rate:.2f})"
    problems = []
    if rate + 1e-12 < cfg.accept_rate:
        why = "; ".join(f"seed {r['seed']}: {r['error'] or ', '.join(r['diagnostics']) or 'failed'}"
                        for r in runs if not r["success"])[:600]
        problems.append(f"{detail}: {why}")
    return detail, {"rate": rate, "solved": wins, "seeds": len(runs), "episodes": runs}, problems


def _reward_agrees(task: Task, cfg: CheckConfig, cache: dict[str, Any]) -> tuple[str, dict[str, Any], list[str]]:
    runs = _oracle_runs(task, cfg, cache)
    problems = [f"seed {r['seed']}: predicate says {'success' if r['success'] else 'failure'} but the Ravens "
                f"reward is {r['reward']:.3f}" for r in runs if r["success"] != (r["reward"] >= REWARD_ONE)]
    return f"reward and predicate agree on {len(runs) - len(problems)}/{len(runs)} oracle episodes", {}, problems


def _protocol(task: Task, cfg: CheckConfig) -> tuple[str, dict[str, Any], list[str]]:
    problems = validate_task(task, cfg.name)
    tags: Any = getattr(task, "tags", frozenset())  # a plugin's attribute: any type; validate_task reports a bad one
    missing = sorted(cfg.required_tags - set(tags)) if isinstance(tags, (set, frozenset)) else []
    if missing:
        problems.append(f"its tags lack {', '.join(map(repr, missing))}")
    detail = "attributes, methods and the three-part docstring"
    if uses_deprecated_name(task):
        rename = f"'{DEPRECATED_SCENE_METHOD}' is the old name of '{SCENE_METHOD}': rename it to '{SCENE_METHOD}'"
        if cfg.allow_deprecated:
            detail += f" (deprecated: {rename})"
        else:
            problems.append(f"it defines '{DEPRECATED_SCENE_METHOD}(self, rng)' but no '{SCENE_METHOD}(self, rng)'; {rename}")
    return detail, {"name": getattr(task, "name", None), "tags": sorted(map(str, tags or ()))}, problems


_RUNNERS: dict[str, Callable[..., tuple[str, dict[str, Any], list[str]]]] = {
    "protocol": _protocol, "scenes": _scenes, "goal_text": _goal_text, "not_solved_at_reset": _not_solved_at_reset,
    "do_nothing_fails": _do_nothing_fails, "oracle_solves": _oracle_solves, "reward_agrees": _reward_agrees,
}
"""One runner per check of :data:`CHECKS`, in its order (``tests/test_taskcheck.py`` holds them equal)."""


def _one_line(e: BaseException) -> str:
    return " ".join(f"{type(e).__name__}: {e}".split())[:500]


def check_task(task: Task, config: CheckConfig = CheckConfig(), *,
               on_start: Callable[[str], None] | None = None,
               on_result: Callable[[CheckResult], None] | None = None,
               checks: Sequence[str] = CHECKS) -> Report:
    """Run ``checks`` (default: all, in :data:`CHECKS` order) on ``task``; never raises for the
    task's own faults: an exception inside a check is that check's ``error`` outcome.

    ``on_start``/``on_result`` are told about each check as it begins and ends (the generator
    records which check a refused event belongs to).
    """
    unknown = [c for c in checks if c not in _RUNNERS]
    if unknown:
        raise ConfigError(f"unknown check(s) {', '.join(unknown)}; valid checks: {', '.join(CHECKS)}")
    cache: dict[str, Any] = {}
    results: list[CheckResult] = []
    name = str(getattr(task, "name", task))
    failed: str | None = None
    for check in checks:
        if failed:
            res = CheckResult(check, "skip", f"not run: {failed} did not pass")
        else:
            if on_start:
                on_start(check)
            t0 = time.perf_counter()
            run = _RUNNERS[check]
            try:
                args = (task, config, cache) if check in ("oracle_solves", "reward_agrees") else (task, config)
                detail, data, problems = run(*args)
            except Exception as e:  # noqa: BLE001 - the task's own code failed: that is the finding
                res = CheckResult(check, "error", _one_line(e), time.perf_counter() - t0)
            else:
                wall = time.perf_counter() - t0
                if problems:
                    more = f" (+{len(problems) - 3} more)" if len(problems) > 3 else ""
                    res = CheckResult(check, "fail", "; ".join(problems[:3]) + more, wall, data)
                else:
                    res = CheckResult(check, "pass", detail, wall, data)
        results.append(res)
        failed = failed or (check if res.outcome in ("fail", "error") else None)
        if on_result:
            on_result(res)
    return Report(name, tuple(results))


__all__ = ["CheckConfig", "DEFAULT_ACCEPT_RATE", "DEFAULT_SEEDS", "IdleAgent", "check_task", "goal_text_problems"]
