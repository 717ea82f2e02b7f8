"""``python -m capmj.tasks check NAME...``: a thin, lazy entry into :mod:`capmj.taskcheck`.

The checker runs the oracle, which lives above this layer (sim <- tasks <- agents); it is
imported only when this entry runs, so nothing in ``capmj.tasks`` depends on it.
"""

from __future__ import annotations

import sys

USAGE = "usage: python -m capmj.tasks check NAME... [--seeds K] [--accept-rate R] [--json]"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("-h", "--help"):
        print(USAGE + "\n\ncommands:\n  check   run the public task checker (python -m capmj.tasks check --help)")
        return 0 if argv else 2
    if argv[0] != "check":
        print(f"error: unknown command {argv[0]!r}; valid commands: check\n{USAGE}", file=sys.stderr)
        return 2
    from capmj.taskcheck.cli import main as check_main  # lazy: the checker sits above this layer

    return check_main(argv[1:])


if __name__ == "__main__":
    raise SystemExit(main())
