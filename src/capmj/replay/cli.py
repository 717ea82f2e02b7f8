"""``python -m capmj.replay FILE.rrd | RUN_DIR``: why episodes failed, from the files alone.

With a run folder (``python -m capmj.bench --out RUN_DIR``) it lists the failed episodes with their
first diagnostic and the command that opens each log.  With an episode ``.rrd`` it prints the
summary :class:`capmj.log.RerunRecorder` stored at ``/summary_json`` (task, seed, agent, verdict,
diagnostics, error, primitives, LLM usage); when the summary is missing (an episode killed before
it ended) it falls back to the goal/verdict texts and the primitive log.  ``--texts`` adds every
text (the per-attempt documents first), ``--frames DIR`` writes the camera images as PNG (depth as
16-bit millimetres plus a colour preview), ``--open`` starts the viewer in a new window (or says
how to use the web viewer when there is no display), ``--web`` serves the web viewer.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Sequence

from capmj.replay.frames import export_frames
from capmj.replay.reader import EpisodeLog, ReplayError, read_episode
from capmj.replay.run_dir import failed_episodes, format_failed
from capmj.replay.viewer import open_viewer, serve_web


def _fmt_summary(log: EpisodeLog) -> str:
    s = log.summary
    lines = [f"capmj episode log: {log.path}"]
    if s is None:
        lines.append("(no episode summary in the file: the episode was probably interrupted; showing what was logged)")
        for key in ("goal", "verdict"):
            if key in log.texts:
                lines.append(f"{key}: " + log.texts[key][-1].replace("\n", "\n  "))
        lines.append(f"primitives logged: {len(log.primitive_lines)}")
        lines += [f"  {x}" for x in log.primitive_lines]
        return "\n".join(lines)
    verdict = "SUCCESS" if s.get("success") else "FAILURE"
    model = f" (model {s['model']})" if s.get("model") else ""
    lines += [
        f"task:        {s.get('task')}",
        f"seed:        {s.get('seed')}",
        f"agent:       {s.get('agent')}{model}",
        f"verdict:     {verdict} (progress {float(s.get('progress') or 0):.2f}, reward {float(s.get('reward') or 0):.2f})",
        f"goal:        {s.get('goal') or '-'}",
    ]
    diags = s.get("diagnostics") or []
    lines.append(f"diagnostics: {len(diags)}")
    lines += [f"  - {d}" for d in diags]
    if s.get("error"):
        lines.append(f"error:       {s['error']}")
    lines.append(f"primitives:  {s.get('primitives')} (attempts {s.get('attempts')}, "
                 f"simulated {float(s.get('sim_s') or 0):.2f} s, wall {float(s.get('wall_s') or 0):.2f} s)")
    lines += [f"  {x}" for x in log.primitive_lines]
    llm = {k: v for k, v in (s.get("llm") or {}).items() if k != "attempts"}
    if llm:
        lines.append("LLM usage:")
        lines += ["  " + ln for ln in json.dumps(llm, indent=2, sort_keys=True).splitlines()]
    if log.attempts:
        lines.append("attempt documents: " + ", ".join(sorted(log.attempts)) + " (--texts prints them)")
    if s.get("perception_views"):
        lines.append(f"perception views: {s['perception_views']} (/world/perception/detections, /text/perception)")
    if s.get("images_logged"):
        lines.append(f"camera images: {s['images_logged']}")
    if s.get("image_error"):
        lines.append(f"camera images failed: {s['image_error']}")
    return "\n".join(lines)


def _print_texts(log: EpisodeLog) -> None:
    for k, doc in sorted(log.attempts.items()):
        print(f"\n----- /attempts/{k} -----")
        print(doc)
    for key, docs in sorted({**log.texts, **log.logs}.items()):
        for i, body in enumerate(docs):
            print(f"\n----- /text/{key}" + (f" [{i + 1}]" if len(docs) > 1 else "") + " -----")
            print(body)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m capmj.replay",
        description="Why did episodes fail?  List a run's failed episodes, or print, export or open one episode log.",
        epilog="examples:\n"
               "  python -m capmj.replay runs/x                    # failed episodes of a run + how to open each\n"
               "  python -m capmj.replay runs/x/rrd/put-block-into-matching-bowl/10001-oracle.rrd\n"
               "  python -m capmj.replay EP.rrd --json            # the summary as JSON\n"
               "  python -m capmj.replay EP.rrd --texts           # + plan, verdict, API calls, prompts per attempt\n"
               "  python -m capmj.replay EP.rrd --frames frames/  # camera images as PNG (+ depth previews)\n"
               "  python -m capmj.replay EP.rrd --open            # rerun viewer in a new window\n"
               "  python -m capmj.replay EP.rrd --web             # web viewer on :9090 (for SSH port forwarding)",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("path", type=Path, metavar="FILE.rrd|RUN_DIR",
                   help="an episode .rrd written by capmj, or a run folder of python -m capmj.bench")
    p.add_argument("--json", action="store_true", help="print the summary JSON instead of the text report")
    p.add_argument("--texts", action="store_true", help="also print the attempt documents and every text")
    p.add_argument("--frames", type=Path, metavar="DIR", help="export the logged camera images to DIR as PNG")
    p.add_argument("--open", action="store_true", help="open the file in a new rerun viewer window")
    p.add_argument("--web", action="store_true", help="serve the file in the web viewer (ports 9090 and 9876)")
    return p


def _run_dir(args: Any) -> int:
    if args.json or args.texts or args.frames or args.open or args.web:
        print(f"capmj-replay: error: {args.path} is a run folder; --json/--texts/--frames/--open/--web take one "
              "episode .rrd (listed below)", file=sys.stderr)
    failed, total = failed_episodes(args.path)
    print(format_failed(args.path, failed, total))
    return 0 if not (args.json or args.texts or args.frames or args.open or args.web) else 2


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        if args.path.is_dir():
            return _run_dir(args)
        log = read_episode(args.path)
        print(json.dumps(log.summary, indent=2, sort_keys=True) if args.json else _fmt_summary(log))
        if args.texts:
            _print_texts(log)
        if args.frames is not None:
            written = export_frames(args.path, args.frames)
            if written:
                print(f"wrote {len(written)} PNG files to {args.frames} (depth: 16-bit mm + *_preview.png colour maps)")
            else:
                print(f"no camera images in {args.path} (record with python -m capmj.bench --log-images)")
    except ReplayError as exc:
        print(f"capmj-replay: error: {exc}", file=sys.stderr)
        return 2
    if args.web:
        return serve_web(args.path)
    if args.open:
        return open_viewer(args.path)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
