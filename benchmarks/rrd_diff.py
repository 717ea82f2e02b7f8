"""Compare what two run folders' episode logs hold, for behaviour-preserving changes to logging.

Reads every ``.rrd`` under ``A`` and the file at the same relative path under ``B`` back with
``rerun.chunk.RrdReader`` and compares them entity by entity: the same entities, and per entity
the same rows (static and temporal) in logging order — every component and time column, equal
values, equal row counts.  Row ids (they hold the wall-clock time of logging), the recording's
start time and the summary's wall time and ``written_at`` stamp are left out: they differ from run
to run; the summary's ``rrd`` path is compared within its run folder.  ``episodes.jsonl`` is compared too (without ``wall_s``), when both folders have one.

    python -m capmj.bench --agent oracle --tasks all --seeds 0:3 --out runs/a   # before
    python -m capmj.bench --agent oracle --tasks all --seeds 0:3 --out runs/b   # after
    python benchmarks/rrd_diff.py runs/a runs/b

Prints one line per differing file and a total; exits 1 if anything differs.
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path
from typing import Any

from capmj.bench.results import EPISODES, read_records
from capmj.records import Key
from capmj.replay.reader import iter_chunks

ROW_ID = "rerun.controls.RowId"
VOLATILE_SUMMARY_KEYS = ("written_at", "wall_s")
_WALL = re.compile(r"wall \d+\.\d+ s")


def _mask_text(entity: str, text: str) -> str:
    if entity == "/summary_json":
        s = json.loads(text)
        for k in VOLATILE_SUMMARY_KEYS:
            s.pop(k, None)
        if s.get("rrd"):  # the file's own path: compare it within the run folder
            s["rrd"] = "/".join(Path(s["rrd"]).parts[-3:])
        return json.dumps(s, sort_keys=True)
    if entity == "/summary":
        return _WALL.sub("wall - s", text)
    return text


def _values(col: Any) -> list[Any]:
    """A column as Python values; durations as integer nanoseconds (exact)."""
    import pyarrow as pa

    if str(col.type).startswith("duration"):
        col = col.cast(pa.int64())
    return col.to_pylist()


def _rows(path: Path) -> dict[str, list[tuple[Any, ...]]]:
    """Entity path -> its rows, each a tuple of (column, value) without the row id, ordered by
    row id (the order they were logged in)."""
    out: dict[str, list[tuple[Any, tuple[Any, ...]]]] = {}
    for c in iter_chunks(path):
        ent = c.entity_path
        rb = c.to_record_batch()
        cols = {n: _values(rb.column(n)) for n in rb.schema.names
                if n != ROW_ID and not (ent == "/__properties" and n == "RecordingInfo:start_time")}
        if "TextDocument:text" in cols:
            cols["TextDocument:text"] = [None if v is None else [_mask_text(ent, x) for x in v]
                                         for v in cols["TextDocument:text"]]
        row_ids = rb.column(ROW_ID).to_pylist()
        for i in range(rb.num_rows):
            row = tuple((n, str(v[i])) for n, v in sorted(cols.items()))
            out.setdefault(ent, []).append((row_ids[i], (c.is_static, row)))
    return {e: [r for _, r in sorted(rows, key=lambda x: x[0])] for e, rows in out.items()}


def diff_rows(ra: dict[str, list[Any]], rb: dict[str, list[Any]]) -> list[str]:
    """What differs between two episode logs read by :func:`_rows` (empty: they hold the same)."""
    msgs = [f"entity only in {side}: {e}" for side, x, y in (("A", ra, rb), ("B", rb, ra)) for e in sorted(set(x) - set(y))]
    for e in sorted(set(ra) & set(rb)):
        if len(ra[e]) != len(rb[e]):
            msgs.append(f"{e}: {len(ra[e])} rows vs {len(rb[e])}")
        elif ra[e] != rb[e]:
            k = next(i for i, (x, y) in enumerate(zip(ra[e], rb[e])) if x != y)
            msgs.append(f"{e}: row {k} differs")
    return msgs


def _results(folder: Path) -> dict[Key, str] | None:
    p = folder / EPISODES
    if not p.is_file():
        return None
    records, corrupt = read_records(p)
    out = {r.key: json.dumps({k: v for k, v in r.to_dict().items() if k != "wall_s"}, sort_keys=True)
           for r in records}
    if corrupt:  # unreadable lines count as a difference unless both folders have the same number
        out[("<corrupt lines>", corrupt, "", None)] = ""
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("a", type=Path)
    ap.add_argument("b", type=Path)
    args = ap.parse_args(argv)
    files = sorted(p.relative_to(args.a) for p in args.a.rglob("*.rrd"))
    bad = 0
    entities = rows = 0
    for rel in files:
        if not (args.b / rel).is_file():
            print(f"{rel}: missing in {args.b}")
            bad += 1
            continue
        ra, rb = _rows(args.a / rel), _rows(args.b / rel)
        msgs = diff_rows(ra, rb)
        entities += len(ra)
        rows += sum(map(len, ra.values()))
        if msgs:
            bad += 1
            print(f"{rel}: " + "; ".join(msgs[:5]) + (f" (+{len(msgs) - 5} more)" if len(msgs) > 5 else ""))
    extra = sorted(p.relative_to(args.b) for p in args.b.rglob("*.rrd") if not (args.a / p.relative_to(args.b)).is_file())
    for rel in extra:
        print(f"{rel}: missing in {args.a}")
    res_a, res_b = _results(args.a), _results(args.b)
    results_equal = res_a == res_b
    print(f"{len(files)} file(s), {entities} entities, {rows} rows compared: {bad + len(extra)} differ"
          + ("" if res_a is None or res_b is None else f"; episodes.jsonl {'equal' if results_equal else 'DIFFER'}"))
    return 1 if bad or extra or not results_equal else 0


if __name__ == "__main__":
    raise SystemExit(main())
