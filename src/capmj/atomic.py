"""Atomic file writes: a reader (or a run killed half-way) sees the old file or the whole new one.

Every file capmj writes in place (result configs and summaries, transcripts, demo episodes) goes
through :func:`atomic_write`: the content goes to a hidden temporary file next to the target, is
flushed and ``fsync``-ed, then ``os.replace`` swaps it in.  The temporary name carries the process
and thread id, so parallel writers never share one, and it is removed when writing fails.  Like
``errors.py`` and ``record.py`` this module sits below every layer.
"""

from __future__ import annotations

import contextlib
import json
import os
import threading
from pathlib import Path
from typing import IO, Any, Iterator


@contextlib.contextmanager
def atomic_write(path: str | Path, mode: str = "w", encoding: str | None = None) -> Iterator[IO[Any]]:
    """Open a temporary file for writing (``mode`` "w" or "wb"); on a clean exit it replaces ``path``.

    The file is created with ``open`` (the umask's permissions, as a plain write would).  On an
    exception the temporary file is deleted and ``path`` is left as it was.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}-{threading.get_ident()}")
    try:
        with open(tmp, mode, encoding=encoding) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def write_json_atomic(path: str | Path, data: Any, **dump_kwargs: Any) -> None:
    """``json.dump(data, **dump_kwargs)`` plus a final newline, written atomically (UTF-8)."""
    with atomic_write(path, "w", encoding="utf-8") as f:
        json.dump(data, f, **dump_kwargs)
        f.write("\n")


__all__ = ["atomic_write", "write_json_atomic"]
