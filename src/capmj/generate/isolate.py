"""Run the checks of a generated task with its code in the jail and every check computed here.

The candidate's exact text goes to a :class:`~capmj.confine.proxy.ConfinedTask`: it is loaded
only inside the jail (:mod:`capmj.confine.jail`), under CPU, memory and wall limits, and answers
the task protocol as validated data.  The checks themselves — :func:`capmj.taskcheck.check_task`,
the same code plugin authors run — run in this process: the physics, the oracle episodes, the
Ravens reward from the goals the task returned, the do-nothing episode.  Nothing the jailed
process *says about a check* exists to be believed; it only answers ``sample_scene``,
``oracle_goals`` and ``evaluate``, and each episode gets a fresh process.

A check that fails because the jail ended the process names the limit (CPU, memory, wall time);
one the runtime guard refused is recorded as a ``violation`` (hostile or careless: rejected
without a repair round).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from capmj.confine import jail
from capmj.confine.jail import Limits
from capmj.confine.proxy import ConfinedTask, ModuleSource
from capmj.errors import ConfinedTaskError, ConfinementError
from capmj.taskcheck import CHECKS, CheckConfig, CheckResult, check_task

LOAD = "load"
"""The pseudo-check of loading the module in the jail and finding ``TASK``."""
ORDER = (LOAD, *CHECKS)


@dataclass(frozen=True)
class IsolatedRun:
    """The results in :data:`ORDER`, how the run ended, and its wall time.

    ``violation`` is the event the runtime guard refused (``{"event", "detail", "check"}``);
    ``jail`` says how the code was confined (and how many jailed processes ran it).
    """

    results: tuple[CheckResult, ...]
    ended: str
    wall_s: float
    violation: dict[str, str] | None = None
    jail: dict[str, Any] | None = None
    facts: dict[str, Any] | None = None


def _load_result(e: BaseException) -> CheckResult:
    notes = "\n".join(getattr(e, "__notes__", ()))
    return CheckResult(LOAD, "error", f"{type(e).__name__}: {e}"[:500] if not isinstance(e, ConfinedTaskError)
                       else str(e)[:500], data={"traceback": notes} if notes else {})


def run_isolated(source: ModuleSource, *, name: str, seeds: tuple[int, ...], accept_rate: float,
                 tags: tuple[str, ...], limits: Limits, guarded: bool = True) -> IsolatedRun:
    """Check the generated module ``source`` (its text runs only in the jail).

    ``guarded=False`` leaves the audit hook out; only the tests and ``benchmarks/confinement.py``
    do, to show what the jail stops on its own.

    Raises :class:`~capmj.errors.ConfinementError` when this machine cannot jail: then nothing runs.
    """
    jail.require()
    task = ConfinedTask(source, limits, guard=guarded)
    t0 = time.perf_counter()
    running = [LOAD]
    violation: dict[str, str] | None = None
    results: list[CheckResult] = []
    try:
        task.load()
        results.append(CheckResult(LOAD, "pass", "module loaded in the jail, TASK found"))
        cfg = CheckConfig(seeds, accept_rate, name, frozenset(tags), allow_deprecated=False)
        check_task(task, cfg, on_start=running.append, on_result=results.append)
    except (ConfinementError, ConfinedTaskError) as e:  # the load itself failed
        results.append(_load_result(e))
    finally:
        task.close()
    if task.refusals:
        violation = {**task.refusals[0], "check": running[-1]}  # the checks stop at the refused one
        results = [r for r in results if r.name != violation["check"]]
        results.append(CheckResult(violation["check"], "error",
                                   f"refused by the runtime guard: {violation['detail']}"[:600]))
    done = {r.name for r in results}
    results += [CheckResult(c, "skip", "not run") for c in ORDER if c not in done]
    ended = "completed" if violation is None else f"refused by the runtime guard: {violation['detail']}"
    info = {"jail": "bwrap", "seccomp": True, "guard": guarded, "processes": task.started, "jails": task.jails}
    facts = task.expected.to_dict() if task.expected is not None else None
    return IsolatedRun(tuple(sorted(results, key=lambda r: ORDER.index(r.name))), ended,
                       time.perf_counter() - t0, violation, info, facts)


__all__ = ["IsolatedRun", "LOAD", "ORDER", "run_isolated"]
