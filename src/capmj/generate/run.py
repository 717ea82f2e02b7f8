"""A whole generator run: N candidates (in parallel threads), deduplication, the package.

Candidates are independent conversations; each one's code runs in its own jail, and the checks
(MuJoCo physics, which releases the GIL while it steps) run in the candidate's thread.  Records are ordered by candidate index whatever
order they finish in, so two runs over the same LLM answers write the same files.
"""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from capmj.confine import jail
from capmj.generate.candidate import CandidateRecord, Context, run_candidate
from capmj.generate.config import GenerateConfig
from capmj.generate.library import load_library
from capmj.generate.package import JOURNAL, write_package
from capmj.llm import LLMClient, LLMConfig
from capmj.llm.cache import env_cache_dir


@dataclass(frozen=True)
class RunResult:
    """Every candidate's record (by index) and the tasks written into the package."""

    records: tuple[CandidateRecord, ...]
    accepted: tuple[str, ...]
    out: Path


def _client(cfg: GenerateConfig) -> LLMClient:
    cache = cfg.cache_dir or env_cache_dir()
    return LLMClient(LLMConfig(model=cfg.model, api_base=cfg.api_base, temperature=cfg.temperature,
                               max_tokens=cfg.max_tokens, timeout_s=cfg.timeout_s, cache_dir=cache))


def _dedupe(records: list[CandidateRecord]) -> None:
    """A name accepted twice goes into the package once: the lowest candidate index keeps it."""
    owner: dict[str, int] = {}
    for r in records:
        if r.accepted and r.name:
            if r.name in owner:
                r.accepted, r.stage = False, "package"
                r.reason = f"candidate {owner[r.name]} already provides {r.name!r}; this alternative stays in {r.code_path}"
            else:
                owner[r.name] = r.index


def generate(cfg: GenerateConfig, *, on_done: Callable[[CandidateRecord], None] | None = None) -> RunResult:
    """Run the generator described by ``cfg``; write the package, README and generation.jsonl.

    Each candidate's line is appended to ``generation.jsonl`` as soon as it finishes, so a run
    killed after hours with a slow model keeps what it learnt; the end of the run rewrites the
    file in candidate order, deduplicated.

    Raises :class:`~capmj.errors.ConfinementError` before anything else when this machine cannot
    jail generated code (no candidate is written, none is checked unconfined).
    """
    jail.require()
    cfg.out.mkdir(parents=True, exist_ok=True)
    ctx = Context(cfg, _client(cfg), load_library(), cfg.out)
    records: list[CandidateRecord] = []
    progress = cfg.out / JOURNAL
    with ThreadPoolExecutor(max_workers=cfg.workers) as pool:
        futures = [pool.submit(run_candidate, ctx, i) for i in range(cfg.n)]
        for fut in as_completed(futures):
            rec = fut.result()
            records.append(rec)
            with open(progress, "a", encoding="utf-8") as f:
                f.write(json.dumps(rec.to_dict()) + "\n")
            if on_done:
                on_done(rec)
    records.sort(key=lambda r: r.index)
    _dedupe(records)
    acc = write_package(cfg, records)
    return RunResult(tuple(records), tuple(r.name or "" for r in acc), cfg.out)


__all__ = ["RunResult", "generate"]
