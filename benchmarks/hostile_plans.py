"""Which layer stops each hostile plan of ``tests/hostile_plans.py``, and at what peak memory.

Every fixture runs as one real ``--agent llm`` episode (the agent's loop, the LMP session, the
sandbox, the planner API, MuJoCo physics, the episode record and its failure label); only the LLM
is scripted: a :class:`ScriptedClient` answers each LMP with the fixture's code for it, and
records the key it would hand litellm.  Each fixture runs in a fresh process (``--one NAME``), so
``peak_mb`` is that episode's process peak (``ru_maxrss``; the interpreter with capmj, numpy and
MuJoCo imported is most of it, about 120 MB, and litellm, imported to find a provider's key, adds
about 140 MB to the secret fixtures).  The secret fixtures plant ``OPENAI_API_KEY`` in the process's
environment first and take it out as the bench does (:func:`capmj.llm.keys.take_secrets`); their
row says whether the key stayed out of the environment while plan code ran, reached every LLM
request, and appears nowhere in the episode's record.

    python benchmarks/hostile_plans.py [--out benchmarks/results/hostile_plans.json]

Prints a JSON list, one row per fixture: ``fixture``, ``stopped_by`` (the layer, see
``tests/hostile_plans.py``), ``error`` (the episode's ``error_type``: message), ``peak_mb``, plus
``expected`` (the layer and class the fixture must end with), ``failure`` (the episode's failure
label) and, for a secret fixture, ``key``.  :func:`run_hostile_plans` returns the same rows.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from hostile_plans import HOSTILE_PLANS, PLANTED_KEY, HostilePlan, layer_of  # noqa: E402

TASK = "stack-all-blocks-on-a-zone"
SEED = 10001


def _scripted_client(config: Any, answers: Mapping[str, str], log: dict[str, list[Any]]) -> Any:
    """An :class:`~capmj.llm.LLMClient` whose answers are ``answers[lmp]`` (fenced code), recorded
    as the real client records its calls, without HTTP.  ``log["keys"]`` gets the key each request
    would carry, ``log["env"]`` whether any secret was in ``os.environ`` at that moment."""
    from capmj.llm import LLMClient
    from capmj.llm.keys import is_secret_name
    from capmj.llm.records import Completion

    class ScriptedClient(LLMClient):
        def complete(self, messages: Sequence[Mapping[str, Any]], *, purpose: str = "", **kwargs: Any) -> Completion:
            lmp = purpose.split("#", 1)[0]
            log["keys"].append(self.config.resolved_api_key)
            log["env"].append(any(is_secret_name(k) for k in os.environ))
            log["prompts"].append(" ".join(str(m.get("content", "")) for m in messages))
            code = answers.get(lmp, "ret_val = None\n")
            done = Completion(text=f"```python\n{code}```", model=self.config.model, prompt_tokens=1,
                              completion_tokens=1, cost_usd=0.0, latency_s=0.0, cached=False, attempts=1,
                              purpose=purpose)
            self._record(done, purpose=purpose, latency=0.0, attempts=1)
            return done

    return ScriptedClient(config)


def run_one(fixture: HostilePlan) -> dict[str, Any]:
    """Run one fixture as an LLM episode in this process; its report row (see the module docstring)."""
    if fixture.secret:
        os.environ["OPENAI_API_KEY"] = PLANTED_KEY
        os.environ["OPENAI_BASE_URL"] = "http://127.0.0.1:9/v1"  # never asked: the client is scripted
    from capmj.agents.llm_agent.agent import LLMAgent
    from capmj.agents.llm_agent.options import LLMAgentOptions
    from capmj.agents.sandbox import check_code
    from capmj.bench.failures import classify
    from capmj.bench.migrate import as_record
    from capmj.bench.results import sanitize
    from capmj.errors import PlanError
    from capmj.llm import LLMConfig
    from capmj.llm.keys import take_secrets
    from capmj.records import EpisodeResult
    from capmj.runner import run_episode
    from capmj.tasks.registry import get_task

    take_secrets()  # as the bench does when it starts
    log: dict[str, list[Any]] = {"keys": [], "env": [], "prompts": []}
    answers = {"planner": fixture.code, **fixture.helpers}
    config = LLMConfig("gpt-4o-mini" if fixture.secret else "openai/scripted",
                       api_base=None if fixture.secret else "http://127.0.0.1:9/v1")
    agent = LLMAgent(config, LLMAgentOptions(price="0,0", **fixture.options))  # type: ignore[arg-type]
    agent._client = lambda: _scripted_client(agent.config, answers, log)  # type: ignore[method-assign]
    result = run_episode(get_task(TASK), SEED, agent)
    record = as_record(EpisodeResult.from_dict(sanitize(result.to_dict())))
    try:
        check_code(fixture.code)
        static = False
    except PlanError:
        static = True
    error = " ".join((result.error or "").split())
    head, sep, detail = error.partition(": ")  # the recorded text starts with the class it is shown as
    detail = detail if sep and head.isidentifier() else error
    row: dict[str, Any] = {
        "fixture": fixture.name,
        "stopped_by": layer_of(result.error_type, error, static=static),
        "error": f"{result.error_type}: {detail[:300]}" if result.error_type else None,
        "peak_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        "expected": f"{fixture.layer}: {fixture.expected}",
        "failure": classify(record),
        "llm_requests": len(log["keys"]),
    }
    if fixture.secret:
        text = json.dumps(record.to_dict() if hasattr(record, "to_dict") else result.to_dict(), default=str)
        row["key"] = {"in_environment_while_plan_ran": any(log["env"]),
                      "carried_by_every_request": bool(log["keys"]) and all(k == PLANTED_KEY for k in log["keys"]),
                      "in_episode_record": PLANTED_KEY in text,
                      "in_any_prompt": any(PLANTED_KEY in p for p in log["prompts"])}
    return row


def run_hostile_plans(names: Sequence[str] | None = None, *, isolated: bool = True) -> list[dict[str, Any]]:
    """Run every fixture (or those ``names``), each in a fresh process when ``isolated`` (its peak
    memory is then its own); one row each, in the order of ``HOSTILE_PLANS``."""
    rows = []
    for fixture in HOSTILE_PLANS:
        if names is not None and fixture.name not in names:
            continue
        if not isolated:
            rows.append(run_one(fixture))
            continue
        env = {k: v for k, v in os.environ.items() if k != "OPENAI_API_KEY"}
        done = subprocess.run([sys.executable, __file__, "--one", fixture.name], capture_output=True, text=True,
                              env=env, timeout=600)
        try:
            rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
        except (IndexError, json.JSONDecodeError):
            rows.append({"fixture": fixture.name, "stopped_by": "crashed", "peak_mb": None,
                         "error": f"exit code {done.returncode}: {done.stderr.strip()[-300:]}",
                         "expected": f"{fixture.layer}: {fixture.expected}"})
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--one", metavar="NAME", help="run one fixture in this process and print its row")
    p.add_argument("--out", type=Path, default=None, help="also write the JSON list here")
    args = p.parse_args(argv)
    if args.one:
        fixture = next((f for f in HOSTILE_PLANS if f.name == args.one), None)
        if fixture is None:
            p.error(f"no fixture {args.one!r}")
        print(json.dumps(run_one(fixture)))
        return 0
    rows = run_hostile_plans()
    text = json.dumps(rows, indent=1)
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    expected = all(r.get("stopped_by") == r["expected"].split(":")[0] and r.get("error", "")
                   and r["error"].startswith(r["expected"].split(": ")[1] + ":") for r in rows)
    return 0 if expected else 1


if __name__ == "__main__":
    sys.exit(main())
