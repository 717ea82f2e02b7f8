"""Seed lists of a grid as the command line writes them: ``"1,3,5"``, ``"10001:10101:2"``.

Its own module because every command that runs a grid reads seeds (the bench, the judge, the
replay check), and none of them should import another command's CLI to do it.
"""

from __future__ import annotations

from typing import Sequence

from capmj.errors import ConfigError

TEST_SEEDS = "10001:10101:2"
"""The test split: the 50 odd seeds from 10001 (CLIPort convention)."""


def parse_seeds(text: str) -> list[int]:
    """``"1,3,5"``, ``"10001:10101:2"`` or a mix ``"1,10:20"``; order kept, repeats dropped."""
    out: list[int] = []
    parts = [p.strip() for p in str(text).split(",")]
    if not any(parts):
        raise ConfigError(f"empty seed list {text!r}; give e.g. 1,3,5 or {TEST_SEEDS}")
    for part in parts:
        if not part:
            raise ConfigError(f"bad seed list {text!r}: empty item; give e.g. 1,3,5 or {TEST_SEEDS}")
        if ":" in part:
            bits = part.split(":")
            if len(bits) not in (2, 3):
                raise ConfigError(f"bad seed range {part!r}: use start:stop[:step], e.g. {TEST_SEEDS}")
            try:
                start, stop = int(bits[0]), int(bits[1])
                step = int(bits[2]) if len(bits) == 3 else 1
            except ValueError:
                raise ConfigError(f"bad seed range {part!r}: start, stop and step must be integers, e.g. {TEST_SEEDS}") from None
            if step <= 0:
                raise ConfigError(f"bad seed range {part!r}: step must be positive")
            if start >= stop:
                raise ConfigError(f"bad seed range {part!r}: it is empty (stop is excluded and must exceed start)")
            if start < 0:
                raise ConfigError(f"bad seed range {part!r}: seeds must be >= 0")
            vals: Sequence[int] = range(start, stop, step)
        else:
            try:
                vals = [int(part)]
            except ValueError:
                raise ConfigError(f"bad seed {part!r}: seeds are integers; give e.g. 1,3,5 or {TEST_SEEDS}") from None
            if vals[0] < 0:
                raise ConfigError(f"bad seed {part!r}: seeds must be >= 0")
        for v in vals:
            if v not in out:
                out.append(v)
    return out


__all__ = ["TEST_SEEDS", "parse_seeds"]
