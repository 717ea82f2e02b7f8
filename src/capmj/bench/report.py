"""Summary tables and plots of benchmark results, for one run folder or several side by side.

``summary.md`` is shaped like the CapRavens thesis's Table 5.2: tasks as rows, one column per
configuration (agent, model — plus the LLM options that differ, when several folders are
compared), cells ``"96 % [87–99]"`` = success rate and its 95 % Wilson interval.  When the run
holds generated tasks 1–10, they get a second table shaped like the thesis's Table 5.4 (the
generated tasks as rows, in the spec's order), and each table ends with the pooled rate of its own
rows, so the benchmark figure is not diluted by the generated tasks or the other way round.
``summary.png`` draws the same numbers as bars with the intervals as error bars (matplotlib, Agg
backend).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

from capmj.atomic import atomic_write
from capmj.bench.config import effective_args
from capmj.bench.manifest import differences
from capmj.bench.results import (
    CONFIG,
    EPISODES,
    SUMMARY_JSON,
    SUMMARY_MD,
    SUMMARY_PNG,
    config_of,
    default_label,
    load_json,
    read_records,
    summarize,
    wilson,
    write_result_json,
)
from capmj.bench.options import LABEL_OPTIONS
from capmj.bench.anomalies import DEFAULT_THRESHOLD, headline
from capmj.bench.sections import (
    anomaly_section,
    comparison_section,
    cost_section,
    failure_section,
    perception_section,
    profile_section,
    stamp_lines,
    warnings_section,
)
from capmj.errors import ConfigError
from capmj.records import EpisodeRecord
from capmj.tasks.builtin import GENERATED_NUMBERS, TASK_LETTERS


def task_order(task: str) -> tuple[int, str]:
    """The sort key of a task in every table: benchmark tasks A–J, then others by name, then generated 1–10."""
    letter = TASK_LETTERS.get(task)
    if letter:
        return (0, letter)
    if task in GENERATED_NUMBERS:
        return (2, f"{GENERATED_NUMBERS[task]:02d}")
    return (1, task)


def task_label(task: str) -> str:
    letter = TASK_LETTERS.get(task) or GENERATED_NUMBERS.get(task)
    return f"{letter} {task}" if letter else task


def pooled(summary: Mapping[str, Any], tasks: Sequence[str], label: str) -> dict[str, Any] | None:
    """Success count, rate and Wilson interval of one configuration pooled over ``tasks``."""
    cells = [summary["tasks"][t][label] for t in tasks if label in summary["tasks"][t]]
    n = sum(c["n"] for c in cells)
    if not n:
        return None
    k = sum(c["successes"] for c in cells)
    return {"n": n, "successes": k, "success_rate": k / n, "ci95": list(wilson(k, n))}


def _success_table(summary: Mapping[str, Any], tasks: Sequence[str], labels: Sequence[str], first: str,
                   total: str | None) -> list[str]:
    """Tasks as rows, one column per configuration; ``total`` names a pooled last row (None: the
    run's overall row)."""
    ns = {lab: {summary["tasks"][t][lab]["n"] for t in tasks if lab in summary["tasks"][t]} for lab in labels}
    head = [f"{lab} (n={next(iter(ns[lab]))})" if len(ns[lab]) == 1 else lab for lab in labels]
    out = [f"| {first} | " + " | ".join(head) + " |", "|---|" + "---:|" * len(labels)]
    for t in tasks:
        cells = [pct_cell(summary["tasks"][t].get(lab), show_n=True) for lab in labels]  # n in every cell
        out.append(f"| {task_label(t)} | " + " | ".join(cells) + " |")
    if total is None:
        foot = [summary["overall"][lab] for lab in labels]
        total = "Overall"
    else:
        foot = [pooled(summary, tasks, lab) for lab in labels]
    out.append(f"| **{total}** | " + " | ".join(f"**{pct_cell(st, show_n=True)}**" for st in foot) + " |")
    return out


def pct_cell(st: Mapping[str, Any] | None, show_n: bool = False) -> str:
    """``"96 % [87–99]"`` (success rate and 95 % Wilson interval, rounded to whole percent)."""
    if not st or not st.get("n"):
        return "—" if not st or not st.get("anomalies") or not show_n else f"— (n=0, {st['anomalies']} anomalies excluded)"
    lo, hi = st["ci95"]
    cell = f"{round(100 * st['success_rate'])} % [{round(100 * lo)}–{round(100 * hi)}]"
    if not show_n:
        return cell
    excluded = st.get("anomalies") or 0
    return cell + f" (n={st['n']}" + (f", {excluded} anomal{'ies' if excluded != 1 else 'y'} excluded" if excluded else "") + ")"


def _fmt(v: Any, nd: int = 2) -> str:
    return "—" if v is None else f"{v:.{nd}f}"


def markdown(summary: Mapping[str, Any], title: str = "capmj benchmark results",
             sources: Sequence[str] = ()) -> str:
    """The Markdown report: the Table-5.2-shaped success table (plus the Table-5.4-shaped one of
    the generated tasks when there are any), then per-cell details."""
    labels = list(summary["overall"])
    tasks = sorted(summary["tasks"], key=task_order)
    generated = [t for t in tasks if t in GENERATED_NUMBERS]
    others = [t for t in tasks if t not in GENERATED_NUMBERS]
    warning = headline(summary.get("anomalies") or {})
    out = ([warning, ""] if warning else []) + [f"# {title}", ""]
    if sources:
        out += ["Sources: " + ", ".join(f"`{s}`" for s in sources), ""]
    out += stamp_lines(summary.get("stamp"))
    out += ["Success rate per task with its 95 % Wilson interval; n = episodes (seeds) per cell.", ""]
    seen = {lab: (c or {}).get("perception") for lab, c in (summary.get("configs") or {}).items()}
    if any(seen.values()):  # what the planner API read: the simulator (state) or the cameras (docs/perception.md)
        out += ["Perception: " + ", ".join(f"{lab} = {seen[lab] or 'state'}" for lab in labels if lab in seen), ""]
    if not generated:
        out += _success_table(summary, tasks, labels, "Task", None)
    else:
        if others:
            out += ["## Benchmark tasks (thesis Table 5.2)", ""]
            out += _success_table(summary, others, labels, "Task", "All benchmark tasks") + [""]
        out += ["## Generated tasks (thesis Table 5.4)", ""]
        out += _success_table(summary, generated, labels, "Generated task", "All generated tasks")
        if others:
            out += ["", f"Overall, all {len(tasks)} tasks: "
                    + ", ".join(f"{lab} {pct_cell(summary['overall'][lab])}" for lab in labels)]
    out += profile_section(summary.get("profile"))
    out += ["", "## Details", "",
            "| Task | Configuration | n | successes | success | 95 % CI | mean progress | mean primitives "
            "| errors | wall total (s) | wall mean (s) |",
            "|---|---|---:|---:|---:|---|---:|---:|---:|---:|---:|"]
    rows = [(t, summary["tasks"][t]) for t in tasks] + [("**Overall**", summary["overall"])]
    for t, per in rows:
        for lab in labels:
            st = per.get(lab)
            if not st:
                continue
            lo, hi = st["ci95"]
            name = t if t.startswith("**") else task_label(t)
            rate, ci = ((f"{100 * st['success_rate']:.1f} %", f"{100 * lo:.1f}–{100 * hi:.1f} %")
                        if st["n"] else ("—", "—"))
            out.append(f"| {name} | {lab} | {st['n']} | {st['successes']} | {rate} | {ci} | "
                       f"{_fmt(st['mean_progress'])} | {_fmt(st['mean_primitives'])} | {st['errors']} | {_fmt(st['wall_s_total'], 1)} | {_fmt(st['wall_s_mean'])} |")
    out += _loop_table(rows, labels)
    out += _turns_table(rows, labels)
    out += _tools_table(rows, labels)
    out += failure_section(summary, task_label, task_order) + perception_section(summary, task_label, task_order)
    out += cost_section(summary, task_label, task_order)
    out += comparison_section(summary.get("comparisons") or [], task_label, task_order)
    out += anomaly_section(summary.get("anomalies"), task_label)
    out += warnings_section(summary.get("warnings") or [])
    return "\n".join(out) + "\n"


def _count_cell(k: int, n: int) -> str:
    return "—" if not n else f"{k}/{n} ({round(100 * k / n)} %)"


def _loop_table(rows: Sequence[tuple[str, Mapping[str, Any]]], labels: Sequence[str]) -> list[str]:
    """The closed-loop table of LLM configurations (empty when no cell has ``loop`` statistics)."""
    if not any((per.get(lab) or {}).get("loop") for _, per in rows for lab in labels):
        return []
    out = ["", "## Closed loop (LLM agent)", "",
           "Per attempt: *verdict* = the reporter reached True/False (of the attempts it judged; a plan that "
           "raised is not judged); *agreement* = verdicts equal to the task predicate on the same state, with "
           "false positives (said achieved, was not) and false negatives; *identical re-plans* = attempts 2+ "
           "whose plan still equals an earlier one after the retries (*not re-run*: of these, not run again); "
           "*extra requests* = planner requests made because an answer repeated an earlier plan. "
           "See docs/llm.md.", "",
           "| Task | Configuration | success | attempts/ep | verdict | sources code/repair/direct/unknown "
           "| agreement | FP | FN | identical re-plans | not re-run | extra requests | tokens/ep |",
           "|---|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    for t, per in rows:
        for lab in labels:
            st = per.get(lab) or {}
            lp = st.get("loop")
            if not lp:
                continue
            name = t if t.startswith("**") else task_label(t)
            src = lp["verdict_sources"]
            out.append(f"| {name} | {lab} | {_count_cell(st['successes'], st['n'])} | {lp['mean_attempts']:.2f} | "
                       f"{_count_cell(lp['verdicts'], lp['reporter_runs'])} | "
                       f"{src['code']}/{src['repair']}/{src['direct']}/{src['unknown']} | "
                       f"{_count_cell(lp['agree'], lp['compared'])} | {lp['false_positives']} | "
                       f"{lp['false_negatives']} | {_count_cell(lp['identical_replans'], lp['replans'])} | "
                       f"{lp['not_rerun']} | {lp['extra_requests']} | {lp['mean_tokens']:.0f} |")
    return out


def _loop_cells(rows: Sequence[tuple[str, Mapping[str, Any]]], labels: Sequence[str], key: str
                ) -> list[tuple[str, str, Mapping[str, Any], Mapping[str, Any]]]:
    """(task, configuration, the cell's ``loop[key]``, the cell) of the cells that have ``loop[key]``."""
    cells = []
    for t, per in rows:
        for lab in labels:
            st = per.get(lab) or {}
            tp = (st.get("loop") or {}).get(key)
            if tp:
                cells.append((t, lab, tp, st))
    return cells


def _turns_table(rows: Sequence[tuple[str, Mapping[str, Any]]], labels: Sequence[str]) -> list[str]:
    """The multi-turn table (``--interaction multi`` cells only; empty without any)."""
    cells = _loop_cells(rows, labels, "turns")
    if not cells:
        return []
    out = ["", "## Multi-turn (LLM agent, --interaction multi)", "",
           "*FINISH agreement* = episodes the model ended with FINISH in which the task predicate held "
           "(its self-assessment, as reporter agreement above), *FINISH, not achieved* = the others; "
           "*no FINISH* = episodes that used all their turns (failure no_finish). See docs/llm.md.", "",
           "| Task | Configuration | success | turns/ep | FINISH agreement | FINISH, not achieved | no FINISH |",
           "|---|---|---:|---:|---:|---:|---:|"]
    for t, lab, tp, st in cells:
        name = t if t.startswith("**") else task_label(t)
        out.append(f"| {name} | {lab} | {_count_cell(st['successes'], st['n'])} | {tp['mean_turns']:.2f} | "
                   f"{_count_cell(tp['finish_agree'], tp['finished'])} | {tp['finish_false_positives']} | "
                   f"{tp['no_finish']} |")
    return out


def _tools_table(rows: Sequence[tuple[str, Mapping[str, Any]]], labels: Sequence[str]) -> list[str]:
    """The tool-calling table (``--policy tools`` cells only, ``loop.tools``; empty without any)."""
    cells = _loop_cells(rows, labels, "tools")
    if not cells:
        return []
    out = ["", "## Tool calling (LLM agent, --policy tools)", "",
           "*calls as JSON* = function calls the model wrote as JSON in its text instead of tool_calls (read and "
           "labelled content_json); *ended, goal met* = episodes the model ended (no call or FINISH) in which the "
           "task predicate held; *no FINISH* = episodes that used all their turns (failure no_finish). "
           "See docs/llm.md.", "",
           "| Task | Configuration | success | turns/ep | calls | calls as JSON | ended, goal met | no FINISH |",
           "|---|---|---:|---:|---:|---:|---:|---:|"]
    for t, lab, tp, st in cells:
        name = t if t.startswith("**") else task_label(t)
        out.append(f"| {name} | {lab} | {_count_cell(st['successes'], st['n'])} | {tp['mean_turns']:.2f} | "
                   f"{tp['calls']} | {_count_cell(tp['content_json_calls'], tp['calls'])} | "
                   f"{_count_cell(tp['finish_agree'], tp['ended_by_model'])} | {tp['no_finish']} |")
    return out


def plot(summary: Mapping[str, Any], path: str | Path, title: str = "capmj benchmark") -> Path:
    """Grouped horizontal bars of the success rate per task and configuration, Wilson error bars."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    import numpy as np

    labels = list(summary["overall"])
    tasks = sorted(summary["tasks"], key=task_order)
    rows = [(task_label(t), summary["tasks"][t]) for t in tasks] + [("Overall", summary["overall"])]
    k = max(1, len(labels))
    height = 0.8 / k
    fig, ax = plt.subplots(figsize=(9, 1.2 + 0.45 * len(rows) * max(1, k * 0.6)))
    y0 = np.arange(len(rows))[::-1]
    for j, lab in enumerate(labels):
        ys: list[float] = []
        vals: list[float] = []
        err: list[list[float]] = [[], []]
        for (name, per), y in zip(rows, y0):
            st = per.get(lab)
            if not st or not st["n"]:
                continue
            rate = 100 * st["success_rate"]
            lo, hi = (100 * v for v in st["ci95"])
            ys.append(y + (k - 1 - j - (k - 1) / 2) * height)
            vals.append(rate)
            err[0].append(max(0.0, rate - lo))
            err[1].append(max(0.0, hi - rate))
        ax.barh(ys, vals, height=height * 0.95, xerr=err, capsize=2, label=lab, error_kw={"elinewidth": 0.8})
    ax.set_yticks(y0)
    ax.set_yticklabels([name for name, _ in rows], fontsize=8)
    ax.set_xlim(0, 100)
    ax.set_xlabel("success rate (%) with 95 % Wilson interval")
    ax.set_title(title, fontsize=10)
    ax.grid(axis="x", alpha=0.3)
    if labels:
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_summary(out_dir: str | Path, summary: Mapping[str, Any], *, title: str = "capmj benchmark results",
                  sources: Sequence[str] = (), png: bool = True) -> dict[str, Path]:
    """Write ``summary.json``, ``summary.md`` and (``png``) ``summary.png`` into ``out_dir``."""
    out = Path(out_dir)
    paths = {"json": out / SUMMARY_JSON, "md": out / SUMMARY_MD}
    write_result_json(paths["json"], summary)
    with atomic_write(paths["md"], encoding="utf-8") as f:
        f.write(markdown(summary, title=title, sources=sources))
    if png and summary.get("overall"):
        paths["png"] = plot(summary, out / SUMMARY_PNG, title=title)
    return paths


def summarize_dir(run_dir: str | Path) -> dict[str, Any]:
    """The summary of one result folder's ``episodes.jsonl``."""
    records, _ = read_records(Path(run_dir) / EPISODES)
    return summarize(records)


def _options_suffix(cfg: Mapping[str, Any] | None) -> str:
    """The label suffix of a folder's ``config.json``: the set options of :data:`LABEL_OPTIONS` the
    latest part of the run ran with (``config.json`` keeps them under ``args.agent_options``, with
    each resume's changes in ``resumes``: :func:`~capmj.bench.config.effective_args` applies them)."""
    opts = effective_args(cfg or {}).get("agent_options") or {}
    parts = [f"{k}={opts[k]}" for k in LABEL_OPTIONS if opts.get(k) is not None]
    return f" ({', '.join(parts)})" if parts else ""


def _column(r: EpisodeRecord) -> tuple[str, str | None] | str:
    """What makes a column within one folder: the record's configuration name, else (agent, model)."""
    return r.config if r.config is not None else config_of(r)


def stored_stamp(cfg: Mapping[str, Any] | None) -> dict[str, Any] | None:
    """The task stamp a folder's ``config.json`` holds: that of its latest part (a resume under a
    changed task set records its own), None for a run from before stamps."""
    if not cfg:
        return None
    stamp = cfg.get("stamp")
    for r in cfg.get("resumes") or []:
        stamp = r.get("stamp") or stamp
    return stamp


def combined_stamp(stamps: Mapping[str, Mapping[str, Any] | None], tasks: Sequence[str],
                   allow_mismatch: bool) -> tuple[dict[str, Any] | None, list[str]]:
    """The stamp of the tasks several runs report together (each task's from the first run that
    has it) and the mismatches of the tasks they share.  Mismatches are a ``ConfigError`` unless
    ``allow_mismatch``; then they are returned to be printed."""
    from capmj.bench.stamp import SCHEMA, mismatches, overall

    problems = mismatches(stamps, tasks)
    if problems and not allow_mismatch:
        raise ConfigError("the runs are not comparable: " + "; ".join(problems)
                          + " (add --allow-version-mismatch to compare them anyway)")
    have = [s for s in stamps.values() if s]
    if not have:
        return None, problems
    per: dict[str, Any] = {}
    for s in have:
        for task, entry in (s.get("tasks") or {}).items():
            if task in tasks:
                per.setdefault(task, entry)
    first = have[0]
    prompts = next((s.get("prompts") for s in have if s.get("prompts")), None)
    return {"schema": SCHEMA, "overall": overall(per, prompts), "capmj": first.get("capmj"), "mjcf": first.get("mjcf"),
            "prompts": prompts, "tasks": per}, problems


def load_folders(dirs: Sequence[str | Path]) -> tuple[list[EpisodeRecord], dict[int, str], list[str]]:
    """Records of several result folders with a column label per record (by ``id``).

    A column is one (agent, model) configuration of one folder, labelled ``agent model`` plus the
    LLM options of that folder's ``config.json`` that are set (reporter, attempts, temperature); if
    two folders still give the same label, the folder name is appended.  Raises ``ConfigError``
    for a folder without ``episodes.jsonl``.
    """
    per_folder: list[tuple[Path, list[EpisodeRecord], str]] = []
    for d in dirs:
        d = Path(d)
        f = d / EPISODES
        if not f.is_file():
            raise ConfigError(f"{d} is not a result folder (no {EPISODES})")
        records, _ = read_records(f)
        cfg = load_json(d / CONFIG)
        rank = {c.get("name"): i for i, c in enumerate(effective_args(cfg or {}).get("configs") or [])}
        records.sort(key=lambda r: rank.get(r.config, len(rank)))  # a --configs run's order: its first is the baseline
        per_folder.append((d, records, _options_suffix(cfg)))
    base: dict[tuple[int, tuple[str, str | None] | str], str] = {}
    for i, (d, records, suffix) in enumerate(per_folder):
        for r in records:
            base.setdefault((i, _column(r)), r.config if r.config is not None else default_label(*config_of(r)) + suffix)
    counts: dict[str, int] = {}
    for lab in base.values():
        counts[lab] = counts.get(lab, 0) + 1
    final = {key: (f"{lab} [{per_folder[key[0]][0].name}]" if counts[lab] > 1 else lab) for key, lab in base.items()}
    out: list[EpisodeRecord] = []
    labels: dict[int, str] = {}
    for i, (d, records, _) in enumerate(per_folder):
        for r in records:
            labels[id(r)] = final[(i, _column(r))]
            out.append(r)
    return out, labels, [str(d) for d, _, _ in per_folder]


def report(dirs: Sequence[str | Path], out_dir: str | Path | None = None, *, allow_version_mismatch: bool = False,
           anomaly_threshold: float | None = None) -> tuple[dict[str, Any], str]:
    """Summary and Markdown over one or several result folders; written to ``out_dir`` when given.

    Several folders are compared only when the task stamps of the tasks they share match
    (:mod:`capmj.bench.stamp`; ``ConfigError`` otherwise, unless ``allow_version_mismatch``, when
    the mismatches go to ``stamp_mismatches``).  ``summary["stamp"]`` is the reported tasks' stamp,
    ``summary["stamps"]`` each folder's overall stamp.  The anomaly threshold is the given one,
    else the first folder's summary's, else the default."""
    records, labels, sources = load_folders(dirs)
    configs = {str(d): load_json(Path(d) / CONFIG) for d in dirs}
    stamps = {src: stored_stamp(cfg) for src, cfg in configs.items()}
    tasks = sorted({r.task for r in records})
    stamp, problems = (combined_stamp(stamps, tasks, allow_version_mismatch) if len(dirs) > 1
                       else (stamps[str(dirs[0])], []))
    if anomaly_threshold is None:
        previous = load_json(Path(dirs[0]) / SUMMARY_JSON) or {}
        anomaly_threshold = (previous.get("anomalies") or {}).get("threshold", DEFAULT_THRESHOLD)
    summary = summarize(records, label_of=lambda r: labels[id(r)], anomaly_threshold=float(anomaly_threshold))
    summary["sources"] = sources
    summary["stamp"] = stamp
    summary["stamps"] = {src: (s or {}).get("overall") for src, s in stamps.items()}
    if problems:
        summary["stamp_mismatches"] = problems
    for cfg in configs.values():
        for member in (cfg or {}).get("configurations") or []:
            if member.get("name") in summary["configs"]:
                summary["configs"][member["name"]].setdefault("options", member.get("options") or {})
    if len(dirs) > 1:
        names = [str(d) for d in dirs]
        summary["warnings"] = problems + differences({n: (load_json(Path(d) / CONFIG) or {}).get("manifest")
                                                      for n, d in zip(names, dirs)})
    if out_dir is not None and len(dirs) == 1 and Path(out_dir).resolve() == Path(dirs[0]).resolve():
        previous = load_json(Path(out_dir) / SUMMARY_JSON) or {}
        if "run" in previous:  # keep the timing facts of the run that produced the folder
            summary["run"] = previous["run"]
    md = markdown(summary, sources=sources)
    if out_dir is not None:
        Path(out_dir).mkdir(parents=True, exist_ok=True)
        write_summary(out_dir, summary, sources=sources)
    return summary, md


__all__ = ["GENERATED_NUMBERS", "TASK_LETTERS", "load_folders", "markdown", "pct_cell", "plot", "pooled", "report",
           "summarize_dir", "task_label", "task_order", "write_summary"]
