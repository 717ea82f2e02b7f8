"""The report page's HTML: sections in a fixed order, every number a reader compares tagged with
``data-*`` attributes that hold the summary's unrounded value (``repr`` of the float).

Sections: header (sources, configurations, the version stamp), capability profile (heat map and
the table of success with Wilson intervals), success per task (bars), paired comparisons
(McNemar), efficiency (per episode and per solved episode), failures by label, anomalies,
the failure gallery, and how to reproduce each run.  No script; a Content-Security-Policy that
allows only inline style and ``data:`` images, so the page loads nothing.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
from pathlib import Path
from typing import Any, Mapping, Sequence

from capmj.atomic import atomic_write
from capmj.bench.page.gallery import FailedEpisode, failed_episodes, replay_command
from capmj.bench.page.plots import bars_svg, heatmap_svg
from capmj.bench.page.view import METRICS, ProfileView, profile_view
from capmj.bench.report import task_label, task_order
from capmj.bench.results import CONFIG, load_json
from capmj.bench.config import reproduce_commands

__all__ = ["GALLERY_MAX", "REPORT_HTML", "headline", "render_page", "write_page"]

REPORT_HTML = "report.html"
"""The page's file name in a result folder (``report RUN --html`` with no path)."""
GALLERY_MAX = 400
"""At most this many failed episodes are shown (the page says how many were left out)."""

CSP = "default-src 'none'; img-src data:; style-src 'unsafe-inline'"

STYLE = """
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:0 auto;max-width:1200px;padding:0 1.2em 3em;
color:#222;line-height:1.4}
h1{margin:.8em 0 .2em}h2{border-bottom:2px solid #ddd;padding-bottom:.2em;margin-top:1.8em}
nav a{margin-right:1em}table{border-collapse:collapse;margin:.6em 0;font-size:.88em}
th,td{border:1px solid #ccc;padding:.25em .5em;text-align:right;vertical-align:top}
th:first-child,td:first-child{text-align:left}th{background:#f3f3f3}
td.rate{white-space:nowrap}.muted{color:#777}.warn{color:#a40}
img.figure{max-width:100%;height:auto;display:block;margin:.5em 0}
dl.stamp{display:grid;grid-template-columns:max-content auto;gap:.1em 1em;font-size:.88em}
dl.stamp dt{font-weight:600}dl.stamp dd{margin:0;font-family:ui-monospace,monospace;word-break:break-all}
.gallery{display:grid;grid-template-columns:repeat(auto-fill,minmax(360px,1fr));gap:1em}
article.failed-episode{border:1px solid #ccc;border-radius:6px;padding:.6em;background:#fafafa;overflow:hidden}
article.failed-episode h3{margin:.1em 0 .4em;font-size:1em}
article.failed-episode img{width:320px;max-width:100%;height:auto;image-rendering:pixelated;border:1px solid #bbb}
.label{display:inline-block;background:#a40;color:#fff;border-radius:3px;padding:0 .4em;font-size:.85em}
.label.anomaly{background:#666}article.failed-episode.anomaly{background:#f0f0f0;border-style:dashed}
td.text{text-align:left}
pre{background:#f0f0f0;padding:.5em;overflow-x:auto;font-size:.8em;max-height:24em}
pre.error{white-space:pre-wrap;word-break:break-word;background:#fbeeee}
code.cmd{display:block;background:#222;color:#eee;padding:.4em;font-size:.8em;word-break:break-all}
details summary{cursor:pointer}
"""


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _num(value: Any) -> str:
    """A ``data-*`` value: the number exactly as the summary holds it ("" for None)."""
    return "" if value is None else repr(value)


def _attrs(**values: Any) -> str:
    return "".join(f' data-{k.replace("_", "-")}="{_e(_num(v) if not isinstance(v, str) else v)}"'
                   for k, v in values.items())


def _pct(value: float | None) -> str:
    return "—" if value is None else f"{round(100 * value)} %"


def _fig(svg: bytes, alt: str, ident: str) -> str:
    data = base64.b64encode(svg).decode("ascii")
    return f'<img class="figure" id="{ident}" alt="{_e(alt)}" src="data:image/svg+xml;base64,{data}">'


def _fmt(value: float | None, digits: int) -> str:
    if value is None:
        return "—"
    return f"{value:,.{digits}f}"


# ---------------------------------------------------------------------- sections
def _header(summary: Mapping[str, Any], sources: Sequence[str], labels: Sequence[str], title: str) -> str:
    """Title, the anomaly warning (when the share is above its threshold), sources, configurations."""
    configs = summary.get("configs") or {}
    rows = "".join(
        f"<tr data-config=\"{_e(lab)}\"><td>{_e(lab)}</td><td>{_e((configs.get(lab) or {}).get('agent', '—'))}</td>"
        f"<td>{_e((configs.get(lab) or {}).get('model') or '—')}</td>"
        f"<td>{_e((configs.get(lab) or {}).get('perception') or 'state')}</td></tr>" for lab in labels)
    warning = headline(summary.get("anomalies"))
    first = f'<p class="warn" id="headline">{_e(warning)}</p>' if warning else ""
    return (f"<header><h1>{_e(title)}</h1>{first}"
            f"<p>Sources: {', '.join(f'<code>{_e(s)}</code>' for s in sources)}</p>"
            "<table id=\"configs\"><tr><th>configuration</th><th>agent</th><th>model</th><th>perception</th></tr>"
            f"{rows}</table>"
            "<nav><a href=\"#profile\">profile</a><a href=\"#bars\">per task</a><a href=\"#comparisons\">paired</a>"
            "<a href=\"#efficiency\">efficiency</a><a href=\"#failures\">failures</a><a href=\"#anomalies\">anomalies</a>"
            "<a href=\"#gallery\">gallery</a><a href=\"#stamp\">version stamp</a><a href=\"#reproduce\">reproduce</a></nav>"
            "</header>")


def _rate_cell(st: Mapping[str, Any] | None, task: str, label: str) -> str:
    excluded = (st or {}).get("anomalies") or 0
    note = f", {excluded} anomal{'ies' if excluded != 1 else 'y'} excluded" if excluded else ""
    if not st or not st.get("n"):
        return f'<td class="rate muted"{_attrs(task=task, config=label, n=0, anomalies=excluded)}>—{_e(note)}</td>'
    lo, hi = st["ci95"]
    attrs = _attrs(task=task, config=label, n=st["n"], successes=st["successes"], rate=st["success_rate"], lo=lo,
                   hi=hi, anomalies=excluded)
    return (f'<td class="rate"{attrs}>'
            f"{round(100 * st['success_rate'])} % [{round(100 * lo)}–{round(100 * hi)}] "
            f"<span class=\"muted\">({st['successes']}/{st['n']}{_e(note)})</span></td>")


def _profile(view: ProfileView) -> str:
    if not view.configs:
        return '<section id="profile"><h2>Capability profile</h2><p>No episode in these folders.</p></section>'
    head = "".join(f"<th>{_e(lab)}</th>" for lab in view.configs)
    body = ""
    for t in sorted(view.tasks, key=task_order):
        body += (f'<tr data-task="{_e(t)}"><td>{_e(task_label(t))}</td>'
                 + "".join(_rate_cell(view.cells.get(c, {}).get(t), t, c) for c in view.configs) + "</tr>")
    body += ('<tr data-task="" class="overall"><td><b>Overall</b></td>'
             + "".join(_rate_cell(view.overall.get(c), "", c) for c in view.configs) + "</tr>")
    return (f'<section id="profile" data-source="{view.source}"><h2>Capability profile</h2>'
            "<p>Success rate per task and configuration (colour; episodes solved of n in each cell); below, "
            "the same with 95 % Wilson intervals. n counts the agent's episodes: anomalies (harness failures) "
            "are excluded and counted beside the rate.</p>"
            + _fig(heatmap_svg(view, task_order), "heat map of the success rate, tasks × configurations", "heatmap")
            + f'<table id="profile-table"><tr><th>task</th>{head}</tr>{body}</table></section>')


def _bars(view: ProfileView) -> str:
    if not view.configs:
        return ""
    return ('<section id="bars"><h2>Success per task</h2>'
            + _fig(bars_svg(view), "success rate per task with 95 % Wilson intervals", "bars-figure")
            + "</section>")


def _comparisons(view: ProfileView) -> str:
    if not view.paired:
        return ('<section id="comparisons"><h2>Paired comparisons</h2><p class="muted">One configuration: '
                "nothing to pair.</p></section>")
    out = ['<section id="comparisons"><h2>Paired comparisons</h2>'
           f"<p>Each configuration against the first ({_e(view.configs[0])}) on the same (task, seed) pairs; "
           "exact two-sided McNemar test on the discordant pairs (only one of the two solved it).</p>"]
    for c in view.paired:
        a, b = c["a"], c["b"]
        rows = [(t, c["tasks"][t]) for t in sorted(c["tasks"], key=task_order)] + [("", c["overall"])]
        out.append(f'<h3>{_e(a)} vs {_e(b)}</h3><table class="comparison"{_attrs(a=a, b=b)}>'
                   f"<tr><th>task</th><th>pairs</th><th>{_e(a)}</th><th>{_e(b)}</th><th>only {_e(a)}</th>"
                   f"<th>only {_e(b)}</th><th>McNemar p</th><th></th></tr>")
        for t, cell in rows:
            name = _e(task_label(t)) if t else "<b>Overall</b>"
            flag = "significant" if cell["significant"] else "not significant"
            out.append(f"<tr{_attrs(task=t, n=cell['n'], only_a=cell['only_a'], only_b=cell['only_b'], p=cell['p_value'])}>"
                       f"<td>{name}</td><td>{cell['n']}</td><td>{cell['successes_a']}</td>"
                       f"<td>{cell['successes_b']}</td><td>{cell['only_a']}</td><td>{cell['only_b']}</td>"
                       f"<td>{cell['p_value']:.4g}</td><td>{flag}</td></tr>")
        out.append(f"</table><p class=\"muted\">{c.get('unpaired', 0)} unpaired episode(s) left out.</p>")
    return "".join(out) + "</section>"


def _efficiency(view: ProfileView) -> str:
    digits = {"tokens": 0, "cost_usd": 4, "llm_calls": 2, "turns": 2, "wall_s": 2}
    head = ("<tr><th rowspan=\"2\">configuration</th><th rowspan=\"2\">episodes</th><th rowspan=\"2\">solved</th>"
            f"<th colspan=\"{len(METRICS)}\">per episode</th><th colspan=\"{len(METRICS)}\">per solved episode</th></tr>"
            "<tr>" + "".join(f"<th>{_e(h)}</th>" for _, h in METRICS) * 2 + "</tr>")
    rows = ""
    for lab in view.configs:
        eff = view.efficiency.get(lab) or {}
        cells = ""
        for per in ("per_episode", "per_solved"):
            for k, _ in METRICS:
                v = (eff.get(per) or {}).get(k)
                cells += f'<td{_attrs(metric=k, per=per, value=v)}>{_fmt(v, digits[k])}</td>'
        rows += (f'<tr{_attrs(config=lab, episodes=eff.get("episodes"), solved=eff.get("solved"))}><td>{_e(lab)}</td>'
                 f"<td>{eff.get('episodes')}</td><td>{eff.get('solved')}</td>{cells}</tr>")
    return ('<section id="efficiency"><h2>Efficiency</h2>'
            "<p>LLM tokens, cost (USD), LLM calls, turns (a multi-turn episode's turns, else its plan attempts) "
            "and wall seconds, per episode and per solved episode (the configuration's total divided by the "
            "episodes it solved). — : not measured (no LLM, an unknown price) or nothing solved.</p>"
            f'<table id="efficiency-table">{head}{rows}</table></section>')


def _failures(summary: Mapping[str, Any], labels: Sequence[str]) -> str:
    cells = {lab: summary["overall"].get(lab) or {} for lab in labels}
    present = sorted({f for st in cells.values() for f in (st.get("failures") or {})})
    if not present:
        return '<section id="failures"><h2>Failures by cause</h2><p>No failed episode.</p></section>'
    head = "".join(f"<th>{_e(f)}</th>" for f in present)
    rows = ""
    for lab, st in cells.items():
        fails = st.get("failures") or {}
        rows += (f'<tr{_attrs(config=lab)}><td>{_e(lab)}</td><td>{sum(fails.values())}</td>'
                 + "".join(f'<td{_attrs(failure=f, count=fails.get(f, 0))}>{fails.get(f, 0)}</td>' for f in present)
                 + "</tr>")
    return ('<section id="failures"><h2>Failures by cause</h2>'
            "<p>Failed episodes per failure label (docs/failures.md says how each is decided). A summary that "
            "counts anomalies apart lists only the agent's failures here, the anomalies below.</p>"
            f'<table id="failures-table"><tr><th>configuration</th><th>failed</th>{head}</tr>{rows}</table></section>')


def _generic(value: Any) -> str:
    """A JSON value of a summary field this page does not know in detail, as nested lists."""
    if isinstance(value, Mapping):
        return "<dl class=\"stamp\">" + "".join(f"<dt>{_e(k)}</dt><dd>{_generic(v)}</dd>"
                                                for k, v in value.items()) + "</dl>"
    if isinstance(value, (list, tuple)):
        return "<ul>" + "".join(f"<li>{_generic(v)}</li>" for v in value) + "</ul>"
    return _e(value)


def headline(anomalies: Mapping[str, Any] | None) -> str | None:
    """The warning a page opens with when a run's anomaly share exceeds its threshold (None otherwise)."""
    if not anomalies or not anomalies.get("exceeded"):
        return None
    return (f"{anomalies['count']} of {anomalies['episodes']} episodes ({_pct(anomalies['share'])}) are anomalies, "
            f"above the {_pct(anomalies['threshold'])} threshold: harness failures, not the agent's, excluded "
            "from every rate on this page.")


def _anomalies(summary: Mapping[str, Any]) -> str:
    found = summary.get("anomalies")
    if found is None:
        body = ('<p class="muted">This summary has no anomaly accounting (a run made before harness failures '
                "were counted apart): provider errors, if any, are among the failures above.</p>")
    elif not found.get("count"):
        body = (f'<p id="anomaly-none"{_attrs(count=0, episodes=found.get("episodes"))}>No anomaly: every one '
                f"of the {found.get('episodes')} episodes is the agent's result.</p>")
    else:
        labels = "".join(f"<tr{_attrs(label=k, count=v)}><td>{_e(k)}</td><td>{v}</td></tr>"
                         for k, v in (found.get("labels") or {}).items())
        listed = "".join(f"<tr{_attrs(config=str(a.get('config')), task=str(a.get('task')), seed=a.get('seed'))}>"
                         f"<td>{_e(a.get('config'))}</td><td class=\"text\">{_e(task_label(str(a.get('task'))))}</td>"
                         f"<td>{_e(a.get('seed'))}</td><td class=\"text\">{_e(a.get('label'))}</td>"
                         f"<td class=\"text\">{_e(a.get('error') or '')}</td></tr>" for a in found.get("list") or [])
        body = (f'<p id="anomaly-count"{_attrs(count=found["count"], episodes=found.get("episodes"), share=found.get("share"))}>'
                f"{found['count']} of {found.get('episodes')} episodes ({_pct(found.get('share'))}) are anomalies "
                f"(threshold {_pct(found.get('threshold'))}).</p>"
                f'<table id="anomaly-labels"><tr><th>label</th><th>episodes</th></tr>{labels}</table>'
                '<table id="anomaly-list"><tr><th>configuration</th><th>task</th><th>seed</th><th>label</th>'
                f"<th>error</th></tr>{listed}</table>")
    return f'<section id="anomalies"><h2>Anomalies (harness failures, not the agent\'s)</h2>{body}</section>'


def _short(value: Any) -> str:
    """The first 12 hex digits of a stamp (the text summaries show; the data-* attribute holds all)."""
    return "—" if not value else str(value)[:12]


def _stamp(summary: Mapping[str, Any], configs: Mapping[str, Mapping[str, Any] | None]) -> str:
    out = ['<section id="stamp"><h2>Version stamp</h2>']
    stamp = summary.get("stamp")
    if isinstance(stamp, Mapping) and isinstance(stamp.get("tasks"), Mapping):
        rows = "".join(f'<tr{_attrs(task=t, stamp=str((v or {}).get("stamp", "")))}><td>{_e(task_label(t))}</td>'
                       f'<td><code>{_e(_short((v or {}).get("stamp")))}</code></td><td>{_e((v or {}).get("kind", ""))}</td>'
                       "</tr>" for t, v in sorted(stamp["tasks"].items(), key=lambda kv: task_order(kv[0])))
        out.append(f'<p id="task-stamp"{_attrs(stamp=str(stamp.get("overall", "")))}>Task set stamp '
                   f'<code>{_e(_short(stamp.get("overall")))}</code> (capmj {_e(stamp.get("capmj", "?"))}, MJCF '
                   f'<code>{_e(_short(stamp.get("mjcf")))}</code>, prompts <code>{_e(_short(stamp.get("prompts")))}</code>); '
                   "two runs are comparable on the tasks whose stamps match.</p>"
                   f'<table id="task-stamps"><tr><th>task</th><th>stamp</th><th>kind</th></tr>{rows}</table>')
    elif stamp is not None:
        out.append(f'<div id="task-stamp">{_generic(stamp)}</div>')
    else:
        out.append('<p class="muted">No task stamp in this summary (a run made before stamps were recorded).</p>')
    for line in summary.get("stamp_mismatches") or []:
        out.append(f'<p class="warn stamp-mismatch">{_e(line)}</p>')
    for src, cfg in configs.items():
        manifest = (cfg or {}).get("manifest") or {}
        git = manifest.get("git") or {}
        packages = manifest.get("packages") or (cfg or {}).get("versions") or {}
        facts = {"git revision": (git.get("revision") or "unknown") + (" (uncommitted changes)" if git.get("dirty") else ""),
                 **{k: v for k, v in packages.items() if k in ("capmj", "python", "mujoco", "litellm", "platform")},
                 "model": manifest.get("model") or "—", "perception": manifest.get("perception") or "state",
                 "started": (cfg or {}).get("started_at") or "—"}
        out.append(f"<h3><code>{_e(src)}</code></h3>" + _generic(facts))
    return "".join(out) + "</section>"


def _card(ep: FailedEpisode, anomaly: bool) -> str:
    thumb = (f'<img alt="final top-down view" src="data:image/png;base64,{base64.b64encode(ep.thumbnail).decode()}">'
             if ep.thumbnail else '<p class="muted no-thumb">no thumbnail (a run made before thumbnails, or '
             "rendering was unavailable)</p>")
    kind = "anomaly" if anomaly else "agent"
    label = f"anomaly: {ep.failure}" if anomaly else (ep.failure or "failed")
    parts = [f'<article class="failed-episode {kind}"'
             f'{_attrs(config=ep.config, task=ep.task, seed=ep.seed, failure=ep.failure or "", side=kind)}>',
             f"<h3>{_e(task_label(ep.task))} · seed {ep.seed} · {_e(ep.config)}</h3>",
             f'<p><span class="label {kind}">{_e(label)}</span> progress {ep.progress:.2f}</p>', thumb]
    if ep.goal:
        parts.append(f"<p><b>Goal:</b> {_e(ep.goal)}</p>")
    if ep.error:
        parts.append(f'<pre class="error">{_e(ep.error)}</pre>')
    if ep.diagnostics:
        parts.append("<ul class=\"diagnostics\">" + "".join(f"<li>{_e(d)}</li>" for d in ep.diagnostics) + "</ul>")
    word = "Turn" if ep.turns else "Attempt"
    for a in ep.attempts:
        if not a.code and not a.feedback:
            continue  # no plan came back (the error above says why)
        extra = []
        if a.error:
            extra.append(f'<pre class="error">{_e(a.error)}</pre>')
        if a.feedback:
            extra.append(f"<p><b>Feedback</b></p><pre>{_e(a.feedback)}</pre>")
        verdict = "" if a.verdict is None else f" · reporter: {'achieved' if a.verdict else 'not achieved'}"
        finish = "" if a.finish is None else f" · {'FINISH' if a.finish else 'no FINISH'}"
        lines = len((a.code or "").splitlines())
        parts.append(f"<details class=\"attempt\"><summary>{word} {a.number}: plan ({lines} lines){verdict}{finish}"
                     f"</summary><pre class=\"code\">{_e(a.code or '(no code)')}</pre>{''.join(extra)}</details>")
    if ep.rrd is not None:
        parts.append(f'<p>Open its log:</p><code class="cmd">{_e(replay_command(ep.rrd))}</code>')
    else:
        parts.append('<p class="muted">No .rrd log (run with --no-log).</p>')
    if ep.transcript is not None:
        parts.append(f"<p class=\"muted\">LLM calls: <code>{_e(ep.transcript)}</code></p>")
    return "".join(parts) + "</article>"


def _gallery(episodes: Sequence[FailedEpisode], summary: Mapping[str, Any]) -> str:
    """The failed episodes, the agent's first, then the anomalies (each group by configuration, task, seed)."""
    listed = (summary.get("anomalies") or {}).get("list") or []
    anomalous = {(str(a.get("config")), str(a.get("task")), a.get("seed")) for a in listed}
    configs = {c: i for i, c in enumerate(dict.fromkeys(e.config for e in episodes))}
    flagged = [(e, (e.config, e.task, e.seed) in anomalous) for e in episodes]
    flagged.sort(key=lambda ea: (ea[1], configs[ea[0].config], task_order(ea[0].task), ea[0].seed))
    if not episodes:
        return '<section id="gallery"><h2>Failure gallery</h2><p>No failed episode.</p></section>'
    shown = flagged[:GALLERY_MAX]
    more = (f"<p class=\"warn\">{len(episodes) - len(shown)} more failed episode(s) not shown.</p>"
            if len(episodes) > len(shown) else "")
    return (f'<section id="gallery"><h2>Failure gallery</h2><p>{len(episodes)} failed episode(s): the final '
            "top-down view (objects where the episode left them, arm left out), the failure label and message, "
            "the plan of each attempt, and the command that opens the episode's log.</p>"
            f'{more}<div class="gallery">{"".join(_card(e, a) for e, a in shown)}</div></section>')


def _reproduce(configs: Mapping[str, Mapping[str, Any] | None]) -> str:
    out = ['<section id="reproduce"><h2>Reproduce</h2>']
    for src, cfg in configs.items():
        for cmd in reproduce_commands(cfg or {}):
            out.append(f"<p><code>{_e(src)}</code>:</p><code class=\"cmd\">{_e(cmd)}</code>")
    return "".join(out) + "</section>"


# ---------------------------------------------------------------------- the page
def render_page(summary: Mapping[str, Any], dirs: Sequence[str | Path], *,
                title: str = "capmj benchmark report") -> str:
    """The page of ``summary`` (the report of ``dirs``, :func:`capmj.bench.report.report`) as HTML."""
    from capmj import __version__

    view = profile_view(summary)
    sources = [str(s) for s in summary.get("sources") or dirs]
    configs = {str(d): load_json(Path(d) / CONFIG) for d in dirs}
    when = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    body = [_header(summary, sources, view.configs, title), _profile(view), _bars(view),
            _comparisons(view), _efficiency(view), _failures(summary, view.configs), _anomalies(summary),
            _gallery(failed_episodes(dirs), summary), _stamp(summary, configs), _reproduce(configs)]
    warnings = summary.get("warnings") or []
    if warnings:
        body.insert(1, '<section id="warnings"><details><summary class="warn">'
                    f"{len(warnings)} warning(s): the combined runs were not made under the same conditions "
                    "(their manifests differ)</summary><ul>"
                    + "".join(f"<li>{_e(w)}</li>" for w in warnings) + "</ul></details></section>")
    return ("<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f'<meta http-equiv="Content-Security-Policy" content="{CSP}">'
            '<meta name="viewport" content="width=device-width, initial-scale=1">'
            f'<link rel="icon" href="data:,"><title>{_e(title)}</title><style>{STYLE}</style></head>\n<body>'
            + "\n".join(body)
            + f'\n<footer class="muted"><p>capmj {_e(__version__)}, page written {when} by '
              "<code>python -m capmj.bench report --html</code>.</p></footer></body></html>\n")


def write_page(path: str | Path, summary: Mapping[str, Any], dirs: Sequence[str | Path], *,
               title: str = "capmj benchmark report") -> Path:
    """Write :func:`render_page` to ``path`` (atomically); returns ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = render_page(summary, dirs, title=title)
    with atomic_write(path, encoding="utf-8") as f:
        f.write(text)
    return path
