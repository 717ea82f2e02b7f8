"""Named configurations of the agent, a grid axis: ``--configs S1,S2,M1``.

A :class:`Configuration` is a name and a set of the agent's options (the keyword arguments the
command line's agent flags give, :data:`capmj.bench.options.AGENT_OPTIONS`: perception, api,
examples, interaction, feedback, policy, reporter, reporter_prompt, loop_policy, attempts ...).
The shipped tiers are one table, :data:`TIERS`, named in the field's vocabulary (docs/bench.md);
a user adds their own in a TOML file (``--configs-file``, :func:`load_file`), each a table under
``configs``, optionally ``extends`` another configuration by name.

A configuration may name an option the bench has no flag for yet (another issue adds it): such a
configuration is refused with an error naming the option (:func:`check`), unless its value is the
one the agent has without the option (:data:`IMPLICIT`), in which case it is simply not passed.
Which options exist is read from the flag table, so a tier lights up when its flag lands.
"""

from __future__ import annotations

import argparse
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

from capmj.errors import ConfigError

SCHEMA = "capmj.bench-configs/1"


@dataclass(frozen=True)
class Configuration:
    """A named set of agent options; ``about`` says what it is (for ``--list-configs`` and docs)."""

    name: str
    options: Mapping[str, Any] = field(default_factory=dict)
    about: str = ""
    implied: Mapping[str, Any] = field(default_factory=dict)
    """Options asked for at the value the agent has without them (:data:`IMPLICIT`), left out of
    ``options`` by :func:`check` but still compared with the command line's (:func:`merged`)."""

    def __post_init__(self) -> None:
        if not self.name or any(c in self.name for c in ",/\\ \t\n") or self.name.startswith("."):
            raise ConfigError(f"configuration name {self.name!r} must be non-empty, without commas, slashes or "
                              "spaces, and not start with a dot")
        object.__setattr__(self, "options", dict(self.options))
        object.__setattr__(self, "implied", dict(self.implied))

    def as_dict(self) -> dict[str, Any]:
        out = {"name": self.name, "options": dict(self.options), "about": self.about}
        return out | ({"implied": dict(self.implied)} if self.implied else {})

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Configuration":
        return cls(str(data["name"]), dict(data.get("options") or {}), str(data.get("about") or ""),
                   dict(data.get("implied") or {}))


TIERS: tuple[Configuration, ...] = (
    Configuration("S1", {"api": "high", "perception": "state"}, "single-turn code, high-level API, the simulator's state"),
    Configuration("S2", {"api": "high", "perception": "rgbd"}, "single-turn code, high-level API, perceived from RGB-D"),
    Configuration("S3", {"api": "low", "perception": "state"}, "single-turn code, low-level API, the simulator's state"),
    Configuration("S4", {"api": "low", "examples": "none", "perception": "state"},
                  "as S3 without the prompt's examples"),
    Configuration("M1", {"interaction": "multi", "feedback": "text"}, "multi-turn code with text execution feedback"),
    Configuration("M2", {"interaction": "multi", "feedback": "image"}, "M1 plus the cameras' views after each turn"),
    Configuration("M3", {"interaction": "multi", "feedback": "describe"},
                  "M1 plus a model's description of what changed"),
    Configuration("T1", {"policy": "tools"}, "tool calls instead of code"),
    Configuration("R1", {"reporter": "text", "loop_policy": "careful", "reporter_prompt": "relations"},
                  "S1 with the text reporter in the loop measured never to hurt (careful loop, relations prompt)"),
    Configuration("thesis", {"reporter": "text", "loop_policy": "thesis", "reporter_prompt": "thesis"},
                  "the thesis's closed loop: text reporter, reset and re-plan after any failure, its prompt"),
)
"""The shipped tiers (docs/bench.md has the same table)."""

IMPLICIT: dict[str, str] = {"api": "high", "examples": "full", "policy": "code", "perception": "state",
                            "interaction": "single"}
"""What the agent does without an option: a configuration asking for exactly this is run without
passing the option (so ``S1`` runs before ``--api`` exists, and with agents that do not take it)."""


def _flags() -> dict[str, Any]:
    """The bench's agent flags by ``dest`` (the shared LLM client options have no Flag: ``None``)."""
    from capmj.bench.options import AGENT_FLAGS, AGENT_OPTIONS, PERCEPTION

    table: dict[str, Any] = {name: None for name in AGENT_OPTIONS}
    table.update({f.dest: f for f in AGENT_FLAGS + (PERCEPTION,)})
    return table


def available_options() -> tuple[str, ...]:
    """The option names a configuration may set today: the flag table's."""
    return tuple(_flags())


def check(config: Configuration) -> Configuration:
    """``config`` with each option checked against the flag table: a missing option is refused
    (unless asked for at its :data:`IMPLICIT` value, which is then left out), a value outside the
    flag's choices or of the wrong type is refused; options at their implicit value are left out."""
    flags = _flags()
    out: dict[str, Any] = {}
    implied: dict[str, Any] = dict(config.implied)
    for key, value in config.options.items():
        if IMPLICIT.get(key) == value:
            implied[key] = value
            continue
        if key not in flags:
            raise ConfigError(f"configuration {config.name!r} needs option {key!r} ({key}={value}), which this "
                              f"capmj does not have yet (--{key.replace('_', '-')}); options there are: "
                              f"{', '.join(sorted(flags))}")
        out[key] = _value(config.name, key, value, flags[key])
    return replace(config, options=out, implied=implied)


def _value(name: str, key: str, value: Any, flag: Any) -> Any:
    if flag is None:
        return value
    if flag.type is not None and isinstance(value, str):
        try:
            value = flag.type(value)
        except (ValueError, TypeError, argparse.ArgumentTypeError) as exc:
            raise ConfigError(f"configuration {name!r}: {key}={value!r}: {exc}") from None
    if flag.choices is not None and value not in flag.choices:
        raise ConfigError(f"configuration {name!r}: {key}={value!r} is not one of {', '.join(flag.choices)}")
    return value


def load_file(path: str | Path) -> tuple[Configuration, ...]:
    """The configurations of a TOML file: ``[configs.NAME]`` tables of options, with optional
    ``about`` and ``extends = "OTHER"`` (a tier or a configuration earlier in the file)."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConfigError(f"--configs-file {str(path)!r}: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"--configs-file {str(path)!r} is not valid TOML: {exc}") from None
    tables = data.get("configs")
    if not isinstance(tables, dict) or not tables:
        raise ConfigError(f"--configs-file {str(path)!r} defines no configuration; write [configs.NAME] tables "
                          "of agent options, e.g. [configs.mine] then perception = \"rgbd\"")
    known = {c.name: c for c in TIERS}
    out: list[Configuration] = []
    for name, table in tables.items():
        if not isinstance(table, dict):
            raise ConfigError(f"--configs-file {str(path)!r}: configs.{name} must be a table of options")
        options = {k: v for k, v in table.items() if k not in ("about", "extends")}
        base = table.get("extends")
        if base is not None:
            if base not in known:
                raise ConfigError(f"configuration {name!r} extends unknown {base!r}; known: {', '.join(known)}")
            options = {**known[base].options, **options}
        config = Configuration(str(name), options, str(table.get("about") or (f"{base} with changes" if base else "")))
        known[config.name] = config
        out.append(config)
    return tuple(out)


def resolve(names: str, files: Sequence[Configuration] = ()) -> tuple[Configuration, ...]:
    """The configurations ``--configs`` names (comma-separated, in order; a file's override a tier
    of the same name), each :func:`check`-ed.  Unknown or repeated names are a ``ConfigError``
    naming the valid ones."""
    table = {c.name: c for c in TIERS} | {c.name: c for c in files}
    wanted = [n.strip() for n in names.split(",") if n.strip()]
    if not wanted:
        raise ConfigError(f"--configs names no configuration; valid: {', '.join(table)}")
    unknown = [n for n in wanted if n not in table]
    if unknown:
        raise ConfigError(f"unknown configuration(s) {', '.join(unknown)}; valid: {', '.join(table)}"
                          + ("" if files else " (add your own with --configs-file FILE.toml)"))
    repeated = sorted({n for n in wanted if wanted.count(n) > 1})
    if repeated:
        raise ConfigError(f"configuration(s) named twice in --configs: {', '.join(repeated)}")
    return tuple(check(table[n]) for n in wanted)


def merged(config: Configuration, shared: Mapping[str, Any]) -> dict[str, Any]:
    """The agent options of one configuration of a grid: the command line's ``shared`` options,
    then the configuration's.  An option both set, to different values, is a ``ConfigError``."""
    asked = {**config.implied, **config.options}
    clash = sorted(k for k, v in asked.items() if k in shared and shared[k] != v)
    if clash:
        raise ConfigError(f"configuration {config.name!r} sets {', '.join(f'{k}={asked[k]!r}' for k in clash)}"
                          f" but the command line gives {', '.join(f'{k}={shared[k]!r}' for k in clash)}; leave the "
                          "option off the command line or use another configuration")
    return {**shared, **config.options}


MEASURED_REPORTER_DEFAULTS: dict[str, str] = {"loop_policy": "careful", "reporter_prompt": "relations"}
"""What ``--reporter text`` runs with unless told otherwise: the loop policy and reporter prompt
measured never to make an episode worse (docs/llm.md); the thesis's are the ``thesis`` tier."""


def with_measured_defaults(options: Mapping[str, Any]) -> dict[str, Any]:
    """``options`` with :data:`MEASURED_REPORTER_DEFAULTS` filled in where ``--reporter text`` is
    asked for and the option is not set; other options unchanged."""
    out = dict(options)
    if out.get("reporter") == "text":
        for key, value in MEASURED_REPORTER_DEFAULTS.items():
            out.setdefault(key, value)
    return out


def listing(configs: Iterable[Configuration]) -> list[str]:
    """One line per configuration: name, options, what it is, and whether it can run here."""
    lines = []
    for c in configs:
        try:
            check(c)
            state = ""
        except ConfigError as exc:
            state = f"  [not available: {exc}]"
        opts = ", ".join(f"{k}={v}" for k, v in c.options.items()) or "(defaults)"
        lines.append(f"  {c.name:<8} {opts:<62} {c.about}{state}")
    return lines


__all__ = ["Configuration", "IMPLICIT", "MEASURED_REPORTER_DEFAULTS", "SCHEMA", "TIERS", "available_options", "check", "listing", "load_file",
           "merged", "resolve", "with_measured_defaults"]
