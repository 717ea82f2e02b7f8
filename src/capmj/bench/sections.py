"""Markdown sections of ``summary.md`` beyond the success table: why episodes failed, what the LLM
cost, paired comparisons between configurations, and warnings about runs that differ.

Every cell says its n.  Data come from ``summary.json`` (see :mod:`capmj.bench.results`,
:mod:`capmj.bench.failures`, :mod:`capmj.bench.spend`, :mod:`capmj.bench.stats`).
"""

from __future__ import annotations

from typing import Any, Callable, Mapping

from capmj.bench.failures import LABELS
from capmj.bench.spend import fmt_cost

__all__ = ["anomaly_section", "profile_section", "stamp_lines", "comparison_section", "cost_section", "failure_section", "perception_section", "warnings_section"]


def _rows(summary: Mapping[str, Any], task_label: Callable[[str], str],
          order: Callable[[str], Any]) -> list[tuple[str, Mapping[str, Any]]]:
    tasks = sorted(summary["tasks"], key=order)
    return [(task_label(t), summary["tasks"][t]) for t in tasks] + [("**Overall**", summary["overall"])]


def failure_section(summary: Mapping[str, Any], task_label: Callable[[str], str],
                    order: Callable[[str], Any]) -> list[str]:
    """Failed episodes per label (docs/failures.md says how each label is decided)."""
    present = [lab for lab in LABELS if any(lab in (st.get("failures") or {})
                                            for per in [summary["overall"]] for st in per.values())]
    present += sorted({lab for st in summary["overall"].values() for lab in (st.get("failures") or {})} - set(present))
    if not present:
        return []
    apart = any(st.get("anomalies") for st in summary["overall"].values())
    out = ["", "## Failures", "",
           "Failed episodes by cause, as counts of n (the cell's episodes); see docs/failures.md for the rules."
           + (" Anomalies (harness failures) are not in n: they are counted in the last column." if apart else ""),
           "", "| Task | Configuration | n | failed | " + " | ".join(present) + (" | anomalies |" if apart else " |"),
           "|---|---|---:|---:|" + "---:|" * (len(present) + apart)]
    for name, per in _rows(summary, task_label, order):
        for lab, st in per.items():
            f = st.get("failures") or {}
            out.append(f"| {name} | {lab} | {st['n']} | {st['n'] - st['successes']} | "
                       + " | ".join(str(f.get(x, 0)) for x in present)
                       + (f" | {st.get('anomalies') or 0} |" if apart else " |"))
    return out


def perception_section(summary: Mapping[str, Any], task_label: Callable[[str], str],
                       order: Callable[[str], Any]) -> list[str]:
    """What perception got wrong, beside success (rgbd configurations only; see docs/perception.md)."""
    if not any(st.get("perception") for st in summary["overall"].values()):
        return []
    out = ["", "## Perception (rgbd)", "",
           "The planner API's objects scored against the truth after every view: *at reset* the episode's "
           "first view, *after moves* every view after a pick-and-place. missed / false = objects not "
           "perceived / perceived but not there, of all objects in those views; position error = median of "
           "the views' medians / largest (mm); *erred* = episodes whose last attempt acted on a wrong view "
           "or picked off target (see docs/failures.md, label `perception`).", "",
           "| Task | Configuration | success | erred | pick misses | reset: missed / false of objects "
           "| reset: pos mm med / max | after moves: missed / false of objects | after moves: pos mm med / max |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for name, per in _rows(summary, task_label, order):
        for lab, st in per.items():
            p = st.get("perception")
            if not p:
                continue
            r, a = p["reset"], p["after_moves"]
            out.append(f"| {name} | {lab} | {st['successes']}/{st['n']} | {p['erred']}/{p['episodes']} | "
                       f"{p['pick_misses']} | {r['missed']} / {r['false']} of {r['objects']} | "
                       f"{_mm(r['median_pos_mm'])} / {_mm(r['max_pos_mm'])} | "
                       f"{a['missed']} / {a['false']} of {a['objects']} | "
                       f"{_mm(a['median_pos_mm'])} / {_mm(a['max_pos_mm'])} |")
    return out


def _mm(v: float | None) -> str:
    return "—" if v is None else f"{v:.1f}"


def cost_section(summary: Mapping[str, Any], task_label: Callable[[str], str],
                 order: Callable[[str], Any]) -> list[str]:
    """LLM calls, tokens and cost (nominal: cache hits at their stored cost; 'unknown' = no price)."""
    if not any((st.get("llm_usage") or {}).get("llm_episodes") for st in summary["overall"].values()):
        return []
    out = ["", "## LLM usage and cost", "",
           "Nominal usage (cache hits counted at their recorded tokens and price); cost 'unknown' when a "
           "model has no known or declared price.", "",
           "| Task | Configuration | n | LLM calls | tokens | tokens / episode | cost (USD) | cost / episode (USD) |",
           "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, per in _rows(summary, task_label, order):
        for lab, st in per.items():
            u = st.get("llm_usage") or {}
            if not u.get("llm_episodes"):
                continue
            mean = u.get("tokens_mean")
            out.append(f"| {name} | {lab} | {u['llm_episodes']} | {u['calls']} | {u['tokens']} | "
                       f"{'—' if mean is None else f'{mean:.0f}'} | {fmt_cost(u.get('cost_usd'))} | "
                       f"{fmt_cost(u.get('cost_usd_mean'))} |")
    return out


def _pct(v: float | None) -> str:
    return "—" if v is None else f"{100 * v:+.0f} pp"


def comparison_section(comparisons: list[Mapping[str, Any]], task_label: Callable[[str], str],
                       order: Callable[[str], Any]) -> list[str]:
    """Paired (task, seed) comparisons with the exact McNemar test."""
    out: list[str] = []
    for cmp in comparisons:
        a, b = cmp["a"], cmp["b"]
        out += ["", f"## Paired comparison: {a} vs {b}", "",
                f"Same (task, seed) pairs only (n = pairs; {cmp['unpaired']} unpaired episode(s) left out). "
                f"Difference = success rate of {a} minus {b}; exact two-sided McNemar test on the discordant pairs; "
                f"p ≥ {cmp['alpha']} is flagged *not significant*.", "",
                f"| Task | n | {a} | {b} | difference | only {a} | only {b} | McNemar p | |",
                "|---|---:|---:|---:|---:|---:|---:|---:|---|"]
        rows = [(task_label(t), cmp["tasks"][t]) for t in sorted(cmp["tasks"], key=order)]
        rows.append(("**Overall**", cmp["overall"]))
        for name, c in rows:
            flag = "significant" if c["significant"] else "not significant"
            out.append(f"| {name} | {c['n']} | {c['successes_a']}/{c['n']} | {c['successes_b']}/{c['n']} | "
                       f"{_pct(c['difference'])} | {c['only_a']} | {c['only_b']} | {c['p_value']:.4g} | {flag} |")
    return out


def warnings_section(warnings: list[str]) -> list[str]:
    if not warnings:
        return []
    return ["", "## Warnings: the combined runs differ", "",
            "These runs were not made under the same conditions (run manifests in config.json):", ""] + \
           [f"- {w}" for w in warnings]


def stamp_lines(stamp: Mapping[str, Any] | None) -> list[str]:
    """The task-set stamp line(s) under the title (:mod:`capmj.bench.stamp`); a ``report`` over
    several runs lists each run's overall stamp."""
    from capmj.bench.stamp import short

    if not stamp:
        return []
    if "overall" in stamp:
        return [f"Task stamp: `{short(stamp['overall'])}` ({len(stamp.get('tasks') or {})} tasks, capmj "
                f"{stamp.get('capmj')}, MJCF `{short(stamp.get('mjcf'))}`, prompts `{short(stamp.get('prompts'))}`)", ""]
    return ["Task stamps: " + ", ".join(f"{src} `{short((s or {}).get('overall'))}`" for src, s in stamp.items()), ""]


def profile_section(prof: Mapping[str, Any] | None) -> list[str]:
    """The capability profile's efficiency table (the configuration × task success table is the
    success table above; the paired comparisons follow)."""
    from capmj.bench.profile import efficiency_rows

    if not prof or not prof.get("configs"):
        return []
    base = prof["baseline"]
    paired = {p["b"]: p["overall"] for p in prof.get("paired") or []}
    rows = ["", "## Capability profile", "",
            f"Each configuration over all tasks (the agent's episodes; anomalies excluded), paired against the first, "
            f"{base}, on the (task, seed) episodes both ran: *only {base}* / *only this* = pairs one of them solved "
            "(exact McNemar p).", "",
            f"| Configuration | success | 95 % CI | episodes | only {base} | only this | McNemar p |",
            "|---|---:|---|---|---:|---:|---:|"]
    for c in prof["configs"]:
        cell = prof["overall"][c]
        lo, hi = cell["ci95"]
        rate = "—" if cell["success_rate"] is None else f"{100 * cell['success_rate']:.0f} %"
        pair = paired.get(c)
        vs = (f"{pair['only_a']} | {pair['only_b']} | {pair['p_value']:.3g}" if pair else "— | — | —")
        rows.append(f"| {c} | {rate} | {100 * lo:.0f}–{100 * hi:.0f} % | {cell['denominator']} | {vs} |")
    return rows + ["", "## Capability profile: efficiency", "",
            "Over the agent's episodes (anomalies excluded); *per solved* = the configuration's total over its "
            "episodes divided by the episodes it solved (— when it solved none); $ is unknown (—) when any "
            "episode's price is. Turns = attempt records (multi-turn turns, else plan attempts).", ""] + \
        efficiency_rows(prof)


def anomaly_section(anomalies: Mapping[str, Any] | None, task_label: Callable[[str], str]) -> list[str]:
    """Every anomaly (harness failure, not the agent's; :mod:`capmj.bench.anomalies`), listed."""
    if not anomalies:
        return []
    head = ["", "## Anomalies (harness failures, excluded from every rate)", "",
            f"{anomalies['count']} of {anomalies['episodes']} episodes ({100 * anomalies['share']:.0f} %; "
            f"threshold {100 * anomalies['threshold']:.0f} %)"
            + (": " + ", ".join(f"{k} {v}" for k, v in anomalies["labels"].items()) if anomalies["labels"] else "")
            + "."]
    if not anomalies["list"]:
        return head
    rows = ["", "| Configuration | Task | Seed | Label | Error |", "|---|---|---:|---|---|"]
    for a in anomalies["list"]:
        err = " ".join(str(a.get("error") or "").split()).replace("|", "\\|")
        rows.append(f"| {a['config']} | {task_label(a['task'])} | {a['seed']} | {a['label']} | {err[:160]} |")
    return head + rows
