"""Do CapRavens' few-shot examples run as written in capmj?  Counts and a class per example.

Reads the original prompt files from a local clone or ``fetch`` mirror of ``Flakeeeet/capravens``
at run time (nothing of their text is stored in capmj, and the JSON holds only ids, classes and
capmj's own error messages), splits them into examples and runs each example's code unchanged in
capmj's sandbox against a real MuJoCo scene:

* planner (``prompt_tabletop_ui.txt``) and fgen examples with the whole plan environment
  (``LMPSession.plan_env``); parse_obj_name / parse_position examples with the helper environment
  (``LMPSession.helper_env``, ``objects`` bound); parse_completion examples with the text
  reporter's environment (``reporter_env``: ``object_positions`` ...).  A fgen ``define function``
  example is then called with arguments named as in its signature.
* The scene is built from the example's ``objects = [...]`` (or ``object_positions``) names: one
  capmj object per name of a kind capmj has, colour, size, ``2x scaled`` and ``obj_id`` as
  written (ids ≥ 1), placed collision-free from ``--seed``.  Examples that name no objects get
  the scene of the capmj task ``put-block-into-matching-bowl`` (blocks and bowls).
* Helper LMP calls the code makes are answered by :class:`Answers`, a scripted keyword resolver
  over the scene: fixtures so the example's own code can run without an LLM, never results.
  They are bound only under the names capmj's environment provides.  A plan's own
  ``parse_completion`` check (bound by capmj as the session's ``check``, the text reporter in a
  real episode) answers False the first time and True after, so a check-and-retry example runs
  its retry branch too (``reset()`` and the second try, on the real world).

Classes, decided in this order:

* ``invalid_in_original``: not valid Python; calls a function that neither the original's API
  (``setup_LMP`` in its ``cliport/cap.py``), its fgen examples nor the example defines (only a
  function-writing LLM could supply it); names placeholder objects ('object1') with no scene; uses
  a variable nothing defines; names an object its own objects line does not list; or fails the
  same way (same error class, same line) once the original's return conventions are emulated.
* ``fails``: uses objects of a kind capmj lacks (cylinders, lines), calls an API function of the
  original capmj does not provide, or any other error in capmj (quoted, no code).
* ``mapping``: fails with an error naming a documented difference (a
  :class:`~capmj.errors.PortingDifference`, or a name capmj refuses where the original bound it:
  ``NameError: X() cannot be called``); runs once the original's conventions are emulated (one-element
  position lists, ``get_bbox`` sizes); or runs but reads ``get_bbox`` as CapRavens' sizes, which
  capmj's bounds are not (it runs, with other numbers).
* ``unchanged``: runs as written and sets its return variable.

The thesis's appendix plan and check exist in the repository only inside ``paper.pdf`` and are
not read.  Examples are split at blank lines and at ``objects =`` / ``object_positions =`` lines
(a multi-line dict stays one context); ids are ``<set>#<n>`` in file order.

    python benchmarks/capravens_examples.py --repo /work/.mirror/Flakeeeet+capravens/repo \\
        --out benchmarks/results/capravens_examples.json
"""

from __future__ import annotations

import argparse
import ast
import inspect
import json
import re
import subprocess
import sys
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
from shapely.geometry import LineString

from capmj.agents.api.planner_api import PlannerAPI
from capmj.agents.base import EpisodeContext
from capmj.agents.lmp.codeprep import RESERVED, strip_benign_imports, undefined_calls
from capmj.agents.lmp.session import LMPSession
from capmj.agents.prompt_files import object_names
from capmj.agents.report.text_env import reporter_env
from capmj.agents.sandbox import PROVIDED_NAMES, SandboxBudget, run_code
from capmj.errors import PlanError, PortingDifference, UnknownObjectError, error_name
from capmj.runner import start_episode
from capmj.sim.objects import KINDS, ObjectSpec, resting_z
from capmj.sim.palette import COLOR_NAMES
from capmj.tasks.protocol import Scene
from capmj.tasks.registry import get_task
from capmj.tasks.spawn import Resample, Spawner

FILES = {  # the core example sets, in the order the issue lists them
    "planner": "prompts/capravens/prompt_tabletop_ui.txt",
    "parse_obj_name": "prompts/capravens/prompt_parse_obj_name.txt",
    "parse_position": "prompts/capravens/prompt_parse_position.txt",
    "parse_completion": "prompts/capravens/prompt_parse_completion.txt",
    "fgen": "prompts/capravens/prompt_fgen.txt",
}
RETURNS = {"parse_obj_name": "ret_val", "parse_position": "ret_val", "parse_completion": "judge"}
LMP_NAMES = ("parse_obj_name", "parse_position", "parse_question", "transform_shape_pts", "parse_completion")
ORIGINAL_ENV = frozenset((  # what the original's setup_LMP bound for every LMP (cliport/cap.py)
    "get_bbox", "get_obj_pos", "get_color", "is_obj_visible", "denormalize_xy", "put_first_on_second",
    "get_obj_names", "get_obj_rot", "get_obj_positions_np", "get_corner_name", "get_side_name",
    "get_obj_rotations_np", "goto_pos", "is_target_occupied", "get_random_free_pos",
    "stack_objects_in_order", "get_obj_pos_dict", "denormalize_bbox", "reset", "say", "np", "utils",
    "itertools") + LMP_NAMES)
DEFAULT_TASK = "put-block-into-matching-bowl"
NUMBERS = {"two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8, "nine": 9, "ten": 10}
NAME_ARGS = frozenset(("put_first_on_second", "get_obj_pos", "get_obj_rot", "get_bbox", "is_target_occupied",
                       "stack_objects_in_order"))
ARGUMENTS: dict[str, Any] = {  # fgen signatures' parameters, by name
    "xs": [1.0, 2.0, 3.0], "x": 0.5, "slope": 2.0, "y_intercept": 0.1, "pt": np.array([0.5, 0.0]),
    "dist": 0.1, "length": 0.2, "t": 0.5}  # and "line": a 0.2 m LineString


@dataclass(frozen=True)
class Example:
    id: str
    lmp: str
    context: str | None  # the objects = / object_positions = line
    query: str
    code: str


# ------------------------------------------------------------------------------------------ reading
def read_original(repo: Path, path: str) -> str:
    """A file of the original, from a work tree or a bare git directory (its HEAD)."""
    if (repo / path).is_file():
        return (repo / path).read_text()
    return subprocess.run(["git", f"--git-dir={repo}", "show", f"HEAD:{path}"], check=True,
                          capture_output=True, text=True).stdout


def _parses(code: str) -> bool:
    try:
        ast.parse(code)
    except SyntaxError:
        return False
    return True


def split_examples(lmp: str, text: str) -> list[Example]:
    """The examples of one prompt file: a blank line or a context line starts one; each is an
    optional ``objects =`` / ``object_positions =`` line, the query comment and the code."""
    lines = text.splitlines()
    start = next((i + 2 for i, ln in enumerate(lines) if ln.startswith("# Task Examples")), 0)
    end = next((i - 1 for i, ln in enumerate(lines) if ln.startswith("# Question")), len(lines))
    blocks: list[list[str]] = []
    current: list[str] = []
    for ln in lines[start:end]:
        opens = ln.startswith(("objects = ", "object_positions = ")) or (
            lmp == "fgen" and ln.startswith(("# define function", "# example:")))
        if not ln.strip() or ln.startswith("# ----") or opens:
            if current:
                blocks.append(current)
            current = [ln] if opens else []
            continue
        if not current and ln.startswith(("import ", "from ")):
            continue
        current.append(ln)
    if current:
        blocks.append(current)
    out: list[Example] = []
    for block in blocks:
        context, rest = None, block
        if block[0].startswith(("objects = ", "object_positions = ")):
            n = next((k for k in range(1, len(block) + 1) if _parses("\n".join(block[:k]))), 1)
            context, rest = "\n".join(block[:n]), block[n:]  # a dict may span several lines
        if not rest or not rest[0].startswith("#"):
            if out and context is None:  # a blank line inside an example's code
                prev = out.pop()
                out.append(Example(prev.id, lmp, prev.context, prev.query, prev.code + "\n" + "\n".join(block)))
            continue
        out.append(Example(f"{lmp}#{len(out) + 1}", lmp, context, rest[0], "\n".join(rest[1:]) + "\n"))
    return out


# ------------------------------------------------------------------------------------------ scenes
def context_names(ex: Example) -> list[str]:
    if ex.context is None:
        return []
    if ex.context.startswith("objects = "):
        return object_names(ex.context) or []
    try:
        return list(ast.literal_eval(ex.context.partition("=")[2].strip()))
    except (ValueError, SyntaxError):
        return re.findall(r"'([^']+)':", ex.context)


def spec_for(name: str, obj_id: int) -> ObjectSpec | None:
    """The capmj object a name describes (None for a kind capmj does not have)."""
    words = re.findall(r"[a-z]+|\d+(?:\.\d+)?x?", name.lower())
    kind = next((w for w in words if w in KINDS), None)
    if kind is None:
        return None
    color = next((w for w in words if w in COLOR_NAMES), "gray")
    size = ("big" if {"big", "large"} & set(words) else "tiny" if "tiny" in words else "small") if kind == "block" else None
    scale = next((float(w[:-1]) for w in words if w.endswith("x") and w[:-1].replace(".", "").isdigit()), 1.0)
    return ObjectSpec(obj_id, kind, color, (0.0, 0.0, resting_z(kind, size, scale)), size=size,  # type: ignore[arg-type]
                      scale=scale if kind == "zone" else 1.0)


def build_scene(names: list[str], seed: int) -> tuple[ObjectSpec, ...]:
    """One object per name of a capmj kind, with the obj_id written in the name (≥ 1) where it is
    free, placed collision-free at random yaws."""
    ids = [int(m.group(1)) if (m := re.search(r"obj_id (\d+)", n)) else None for n in names]
    taken = {i for i in ids if i}
    free = (i for i in range(1, 1000) if i not in taken)
    rng = np.random.default_rng(seed)
    for _ in range(20):
        spawner, specs, used = Spawner(rng), [], set()
        try:
            for name, oid in zip(names, ids):
                oid = oid if oid and oid not in used else next(free)
                probe = spec_for(name, oid)
                if probe is None:
                    continue
                used.add(oid)
                x, y = spawner.sample_xy(probe.footprint_radius)
                spec = probe.moved((x, y, probe.pos[2]), float(rng.uniform(0, 2 * np.pi)))
                spawner.reserve((x, y), spec.footprint_radius)
                specs.append(spec)
            return tuple(specs)
        except Resample:
            free = (i for i in range(1, 1000) if i not in taken)
    raise RuntimeError(f"no collision-free layout for {names}")


def missing_kinds(ex: Example) -> list[str]:
    """The kinds of object the example's names have that capmj has not (cylinder, line ...)."""
    out = []
    for name in context_names(ex):
        words = re.findall(r"[a-z]+", name.lower().split(" with obj_id")[0])
        if words and not set(words) & set(KINDS) and words[-1] not in out:
            out.append(words[-1])
    return out


class _PlainTask:
    name, tags = "capravens-example", frozenset()

    def evaluate(self, scene, state):  # noqa: ANN001, ANN201 - examples are not judged
        raise AssertionError("examples are not judged")


def context_for(ex: Example, seed: int) -> EpisodeContext:
    names = context_names(ex)
    if not names:
        return start_episode(get_task(DEFAULT_TASK), seed)
    scene = Scene(build_scene(names, seed), ex.query[1:].strip())
    return start_episode(_PlainTask(), seed, scene=scene)  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------ answers
class Answers:
    """Scripted helper-LMP answers over the scene (fixtures standing in for the LLM): names by
    kind / colour / mobility words of the description, areas by top/bottom/left/right, N points
    as free table positions."""

    def __init__(self, fns: dict[str, Callable[..., Any]]) -> None:
        self.fns = fns
        self.checks = 0

    def _scope(self, context: Any) -> list[str]:
        quoted = re.findall(r"'([^']+)'|\"([^\"]+)\"", context) if isinstance(context, str) else []
        names = [a or b for a, b in quoted]
        return names or self.fns["get_obj_names"]()

    def parse_obj_name(self, query: Any, context: Any = None) -> Any:
        q = str(query).lower()
        words = set(re.findall(r"[a-z]+", q))
        names = self._scope(context)
        kinds = [k for k in KINDS if k in words or f"{k}s" in words]
        colors = [c for c in COLOR_NAMES if c in words]
        pick = [n for n in names if (not kinds or any(k in n for k in kinds))
                and (not colors or any(c in n.split() for c in colors))]
        if "movable" in words:
            pick = [n for n in pick if "fixed" not in n]
        if "largest quantity" in q and pick:
            counts = Counter(next((c for c in COLOR_NAMES if c in n.split()), "") for n in pick)
            top = counts.most_common(1)[0][0]
            pick = [n for n in pick if top in n.split()]
        if q.split(",")[0].strip().endswith(("color", "colors")):  # "zone colors, ..." asks for colours
            pick = list(dict.fromkeys(next((c for c in COLOR_NAMES if c in n.split()), "gray") for n in pick))
        if "list" in q:
            return pick
        first = next((w for w in re.findall(r"[a-z]+", q) if w.rstrip("s") in KINDS), "")
        if "str" in q or first in KINDS:  # "one str", or a singular "the bowl that ..."
            return pick[0] if pick else ""
        return pick

    def parse_position(self, query: Any, context: Any = None) -> Any:
        q = str(query).lower()
        if "bounding box" in q or "area" in q:
            u = (0.5, 1.0) if "right" in q else (0.0, 0.5) if "left" in q else (0.0, 1.0)
            v = (0.5, 1.0) if "top" in q else (0.0, 0.5) if "bottom" in q else (0.0, 1.0)
            return self.fns["denormalize_bbox"]((u[0], v[0], u[1], v[1]))
        for word, n in NUMBERS.items():
            q = re.sub(rf"\b{word}\b", str(n), q)
        m = (re.search(r"(\d+)\s+(?:evenly distributed\s+)?(?:points|corners)", q)
             or re.search(r"with (\d+) points", q))
        if m:
            pts: list[Any] = []
            for _ in range(int(m.group(1))):
                pts.append(self.fns["get_random_free_pos"](targ=list(pts) or None))
            return [(p, [0.0, 0.0, 0.0, 1.0]) for p in pts] if ("rot" in q or "pose" in q) else pts
        return self.fns["get_random_free_pos"]()

    def parse_question(self, query: Any, context: Any = None) -> Any:
        q = str(query).lower()
        if q.startswith("how many"):
            return len(self.parse_obj_name(q, context))
        if q.startswith("what"):
            return self.parse_obj_name(q, context)
        return False

    def parse_completion(self, query: Any, context: Any = None) -> bool:
        """False on the first check, True after: a plan's retry branch runs once."""
        self.checks += 1
        return self.checks > 1

    def transform_shape_pts(self, query: Any, context: Any = None) -> Any:
        return self.parse_position("3 points")


# ------------------------------------------------------------------------------------------ running
class _NoLLM(Exception):
    """The harness has no LLM: raised where capmj would ask one (parse_function)."""


def _no_llm(messages: Any, purpose: str = "", **_: Any) -> Any:
    raise _NoLLM(purpose)


def _original_conventions(env: dict[str, Any]) -> dict[str, Any]:
    """The env with get_obj_pos / get_obj_rot / get_bbox returning as the original did: a
    one-element list of arrays, and (size_x, size_y, size_z) of the first object of a list."""
    pos, rot, bbox = env["get_obj_pos"], env["get_obj_rot"], env["get_bbox"]

    def get_obj_pos(obj: Any, count: int = 1) -> list[Any]:
        objs = obj if isinstance(obj, (list, tuple)) else [obj]
        return [np.array(pos(o), float) for o in objs]

    def get_obj_rot(obj: Any, count: int = 1) -> list[Any]:
        objs = obj if isinstance(obj, (list, tuple)) else [obj]
        return [np.array(rot(o), float) for o in objs]

    def get_bbox(obj: Any) -> tuple[float, ...]:
        b = bbox(obj[0] if isinstance(obj, (list, tuple, np.ndarray)) else obj)
        return tuple(float(b[i + 3] - b[i]) for i in range(3))

    return {**env, "get_obj_pos": get_obj_pos, "get_obj_rot": get_obj_rot, "get_bbox": get_bbox}


def _cause(exc: BaseException) -> BaseException:
    """The innermost error an API function raised (the sandbox re-raises as PlanError from it)."""
    while exc.__cause__ is not None:
        exc = exc.__cause__
    return exc


def _reason(exc: BaseException) -> str:
    inner = _cause(exc)
    text = getattr(inner, "detail", None) or str(inner)
    text = re.sub(r"`[^`]*`", "`…`", str(text))  # no quoted lines of the original's code
    return f"{error_name(inner)}: {' '.join(text.split())[:300]}"


def _environment(ex: Example, ctx: EpisodeContext, original: bool) -> tuple[dict[str, Any], LMPSession]:
    api = PlannerAPI(ctx)
    fns = api.functions()
    answers = Answers(fns)
    session = LMPSession(complete=_no_llm, api=fns, objects_text=api.objects_text,
                         rng=np.random.default_rng(ctx.seed), check=answers.parse_completion)
    if ex.lmp in ("planner", "fgen"):
        env = session.plan_env()
        env["objects"] = api.object_names()
        env["goal"] = ex.query[1:].strip()
    else:
        env = session.helper_env(ex.context or api.objects_text())
        if ex.lmp == "parse_completion":
            env.update(reporter_env(fns, ctx.world.objects, ex.query[1:].strip()))
    for name in LMP_NAMES:
        if name in env:
            env[name] = getattr(answers, name)
    return (_original_conventions(env) if original else env), session


class _Missing(Exception):
    """The example calls functions of the original's API that capmj's environment lacks."""


def _run(ex: Example, seed: int, original: bool, library: dict[str, Any]) -> None:
    """Run the example's code; raises what it raises.  ``library``: functions earlier fgen
    examples defined (the fgen prompt builds each on the previous ones)."""
    ctx = context_for(ex, seed)
    env, session = _environment(ex, ctx, original)
    env.update(library)
    stripped, _ = strip_benign_imports(ex.code, set(env))
    lacking = [n for n, _, _ in undefined_calls(stripped, set(env)) if n in ORIGINAL_ENV and n not in RESERVED]
    if lacking:
        raise _Missing(", ".join(dict.fromkeys(lacking)))
    code = session.prepare(ex.code, env, program=f"the {ex.lmp} example")
    ns = run_code(code, env, budget=SandboxBudget(wall_s=120, max_api_calls=5000), program=f"the {ex.lmp} example",
                  rng=np.random.default_rng(seed))
    if ex.lmp in RETURNS and RETURNS[ex.lmp] not in ns:
        raise PlanError(f"NameError: the code did not set {RETURNS[ex.lmp]!r}")
    for name, fn in ns.items():
        if ex.lmp == "fgen" and callable(fn) and ex.query.startswith("# define"):
            library[name] = fn
            arguments = {**ARGUMENTS, "line": LineString([[0.0, 0.0], [0.2, 0.0]])}
            fn(**{p: arguments[p] for p in inspect.signature(fn).parameters if p in arguments})


def _calls_mention(tree: ast.AST, word: str) -> bool:
    """Whether a call of the original's API or LMPs passes a string naming ``word`` (e.g. a
    parse_obj_name query for cylinders)."""
    pattern = re.compile(rf"\b{re.escape(word)}s?\b")
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ORIGINAL_ENV:
            for arg in ast.walk(node):
                if isinstance(arg, ast.Constant) and isinstance(arg.value, str) and pattern.search(arg.value):
                    return True
    return False


def _placeholders(tree: ast.AST) -> list[str]:
    """Object-name literals of API calls that name no kind of object at all ('object1')."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in NAME_ARGS:
            for arg in node.args:
                if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                    if not set(re.findall(r"[a-z]+", arg.value.lower())) & set(KINDS):
                        out.append(arg.value)
    return out


def classify(ex: Example, seed: int, library: dict[str, Any]) -> tuple[str, str]:
    """(class, reason) of one example (see the module docstring)."""
    try:
        tree = ast.parse(ex.code)
    except SyntaxError as exc:
        return "invalid_in_original", f"not valid Python: SyntaxError: {exc.msg} (line {exc.lineno})"
    code, _ = strip_benign_imports(ex.code, set(ORIGINAL_ENV))
    known = (set(ORIGINAL_ENV) | set(PROVIDED_NAMES) | set(ARGUMENTS) | set(library)
             | {"objects", "object_positions", "ret_val"})
    for name, line, _site in undefined_calls(code, known):
        return "invalid_in_original", (f"calls {name}() (line {line}), which neither the original's API, its fgen "
                                       "examples nor the example defines (only a function-writing LLM could supply it)")
    lacking = [k for k in missing_kinds(ex) if _calls_mention(tree, k)]
    if lacking:
        return "fails", f"uses {', '.join(lacking)} objects, a kind capmj does not have"
    placeholders = _placeholders(tree)
    if placeholders and not context_names(ex):
        return "invalid_in_original", f"names placeholder objects ({', '.join(map(repr, placeholders))}) no scene has"
    try:
        _run(ex, seed, False, library)
    except _Missing as exc:
        return "fails", f"calls {exc} of the original's API, which capmj does not provide"
    except _NoLLM:
        return "fails", "needs parse_function (an LLM) for a call capmj's code preparation found undefined"
    except PlanError as exc:
        inner = _cause(exc)
        if isinstance(inner, PortingDifference):
            return "mapping", _reason(exc)
        m = re.search(r"NameError: (\w+)\(\) cannot be called", str(exc))
        if m and m.group(1) in ORIGINAL_ENV:
            return "mapping", _reason(exc)
        failure = exc
    else:
        if any(isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "get_bbox"
               for n in ast.walk(tree)):
            return "mapping", ("runs, but reads get_bbox as CapRavens' sizes (size_x, size_y, size_z) of the first "
                               "object; capmj's get_bbox gives the world bounds (xmin, ymin, zmin, xmax, ymax, zmax) "
                               "the thesis states, so its numbers differ")
        return "unchanged", ""
    inner = _cause(failure)
    m = re.search(r"NameError: name '(\w+)' is not defined", str(failure))
    if m:
        if m.group(1) in ORIGINAL_ENV:
            return "fails", f"capmj provides no {m.group(1)!r}, which the original had"
        return "invalid_in_original", f"uses {m.group(1)!r}, which nothing in the original defines"
    if isinstance(inner, KeyError) and inner.args and inner.args[0] in context_names(ex):
        return "fails", f"{_reason(failure)} (a name of its objects line; capmj's names differ)"
    if isinstance(inner, UnknownObjectError) and isinstance(inner.name, str) and context_names(ex):
        if inner.name not in context_names(ex):
            return "invalid_in_original", f"names {inner.name!r}, which its own objects line does not list"
        return "fails", _reason(failure)
    try:
        _run(ex, seed, True, {})
    except (PlanError, _Missing, _NoLLM) as again:
        if isinstance(_cause(again), PortingDifference):
            return "mapping", f"{_reason(failure)}; under the original's return conventions: {_reason(again)}"
        if type(_cause(again)) is type(inner) and getattr(again, "line", 0) == getattr(failure, "line", 1):
            return "invalid_in_original", f"fails the same way under the original's return conventions: {_reason(failure)}"
        return "fails", _reason(failure)
    return "mapping", ("runs under the original's return conventions (one-element position lists, bbox sizes); "
                       f"in capmj: {_reason(failure)}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repo", required=True, type=Path, help="the original's git directory or work tree")
    ap.add_argument("--seed", type=int, default=10001)
    ap.add_argument("--only", default="", help="comma-separated example ids")
    ap.add_argument("--out", type=Path, help="also write the JSON here")
    args = ap.parse_args(argv)
    examples = [ex for lmp, path in FILES.items() for ex in split_examples(lmp, read_original(args.repo, path))]
    if args.only:
        examples = [ex for ex in examples if ex.id in args.only.split(",")]
    rows, library = [], {}  # type: ignore[var-annotated]
    for ex in examples:
        cls, reason = classify(ex, args.seed, library)
        rows.append({"id": ex.id, "class": cls, "reason": reason})
        print(f"{ex.id:22s} {cls:20s} {reason[:150]}", file=sys.stderr, flush=True)
    counts = Counter(r["class"] for r in rows)
    valid = len(rows) - counts["invalid_in_original"]
    by_set: dict[str, Counter[str]] = {}
    for r in rows:
        by_set.setdefault(r["id"].split("#")[0], Counter())[r["class"]] += 1
    result = {"source": "Flakeeeet/capravens prompts/capravens (core example sets; the thesis appendix is not in "
                        "the repository as text)", "seed": args.seed,
              "helper_answers": "scripted keyword stand-ins for the helper LMPs (no LLM), see Answers",
              "examples": len(rows), "by_set": {k: dict(v) for k, v in by_set.items()},
              "counts": {k: counts[k] for k in ("unchanged", "mapping", "invalid_in_original", "fails")},
              "valid": valid, "unchanged_of_valid": f"{counts['unchanged']} of {valid}", "per_example": rows}
    text = json.dumps(result, indent=1)
    print(text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
