"""python -m capmj.generate (capmj-generate): write new tasks with an LLM, keep those physics accepts."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path
from typing import NoReturn

from capmj.errors import CapmjError
from capmj.generate.config import GenerateConfig, Limits, MODES, default_package
from capmj.generate.run import generate
from capmj.llm.options import add_llm_options, llm_values
from capmj.taskcheck import DEFAULT_ACCEPT_RATE, DEFAULT_SEEDS

EPILOG = """examples:
  python -m capmj.generate --mode bottom-up --n 5 --model gpt-4o-mini --out gen/run1
  python -m capmj.generate --mode top-down --name put-blocks-in-a-row --description "Put the blocks in a row." \\
      --n 3 --model openai/qwen --api-base http://127.0.0.1:8000/v1 --seeds 10 --accept-rate 0.9 --out gen/row
  pip install -e gen/run1 && python -m capmj.bench --tasks generated-by-llm --seeds 10001:10011:2

results: DIR/pyproject.toml + DIR/<package>/*.py (installable plugin), DIR/README.md, DIR/generation.jsonl
         (one line per candidate: stage reached, every check, tokens, cost, conversation log path),
         DIR/conversations/*.json, DIR/candidates/*.py.  See docs/generate.md."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, exit 2
        print(f"error: {message} (see --help)", file=sys.stderr)
        raise SystemExit(2)


def parser() -> argparse.ArgumentParser:
    ap = _Parser(prog="python -m capmj.generate", description=__doc__, epilog=EPILOG,
                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mode", required=True, choices=MODES, help="bottom-up: the LLM proposes; top-down: you name the task")
    ap.add_argument("--n", type=int, default=1, help="number of candidates (default 1)")
    ap.add_argument("--name", help="top-down: the task name (kebab-case)")
    ap.add_argument("--description", help="top-down: the task's goal text")
    llm = ap.add_argument_group("LLM options (the same flags as python -m capmj.bench)")
    add_llm_options(llm, {f.name: f.default for f in dataclasses.fields(GenerateConfig)
                          if f.name in ("temperature", "timeout_s", "max_tokens")}, model_required=True)
    ap.add_argument("--out", type=Path, required=True, metavar="DIR", help="new folder for the plugin package")
    ap.add_argument("--package", default=None, help=f"distribution name (default {default_package()})")
    ap.add_argument("--seeds", type=int, default=DEFAULT_SEEDS, metavar="K",
                    help=f"distinct seeds of the runtime checks (default {DEFAULT_SEEDS})")
    ap.add_argument("--accept-rate", type=float, default=DEFAULT_ACCEPT_RATE, metavar="R",
                    help=f"minimum oracle success share over the seeds (default {DEFAULT_ACCEPT_RATE})")
    ap.add_argument("--workers", type=int, default=1, help="candidates generated in parallel (default 1)")
    ap.add_argument("--cpu-limit", type=int, default=300, metavar="S", help="CPU seconds of one jailed process (one episode; default 300)")
    ap.add_argument("--memory-limit", type=int, default=4096, metavar="MB", help="address space of one jailed process (default 4096)")
    ap.add_argument("--wall-limit", type=float, default=600.0, metavar="S", help="wall seconds one call into the jail may take (default 600)")
    ap.add_argument("--no-progress", action="store_true", help="no progress bar")
    return ap


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        cfg = GenerateConfig(
            mode=args.mode, model=args.model, out=args.out, n=args.n, name=args.name, description=args.description,
            **{k: v for k, v in llm_values(args).items() if k not in ("model", "cache_dir")},
            package=args.package or default_package(), seeds=args.seeds, accept_rate=args.accept_rate,
            workers=args.workers, cache_dir=Path(args.cache_dir) if args.cache_dir else None,
            limits=Limits(args.cpu_limit, args.memory_limit, args.wall_limit))
    except CapmjError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    from tqdm import tqdm

    bar = tqdm(total=cfg.n, desc="candidates", unit="task", disable=args.no_progress, file=sys.stderr)

    def done(rec) -> None:  # noqa: ANN001
        bar.update(1)
        bar.set_postfix_str(f"{rec.name}: {'accepted' if rec.accepted else 'rejected at ' + rec.stage}")

    try:
        result = generate(cfg, on_done=done)
    except CapmjError as e:
        bar.close()
        print(f"error: {e}", file=sys.stderr)
        return 2
    bar.close()
    for r in result.records:
        verdict = "ACCEPTED" if r.accepted else f"rejected at {r.stage}"
        print(f"{r.index:3d} {r.name or '-':40} {verdict}: {r.reason}")
    print(f"{len(result.accepted)} of {len(result.records)} accepted; package in {cfg.out}"
          + (f" (pip install -e {cfg.out})" if result.accepted else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
