"""One episode's outcome: :class:`EpisodeResult` (what the runner returns) and :class:`EpisodeRecord`
(one line of a run folder's ``episodes.jsonl``).

Why two types over one base: the runner knows what happened in the episode; only the benchmark
knows the failure label it attributes and where it moved the LLM calls (``transcripts/``).  Both
share :class:`Episode`, which every reader (failure attribution, statistics, spend, export, replay)
takes.  A record line carries ``schema`` (:data:`SCHEMA`), so a reader can tell today's lines from
older ones: those are migrated in one place, :mod:`capmj.bench.migrate`.

The JSON keys are those written before the records were typed; new fields are only ever added.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

from capmj.errors import RecordError
from capmj.records.codec import from_plain, to_plain
from capmj.records.notes import LLMNotes
from capmj.records.perception import PerceptionNotes

__all__ = ["SCHEMA", "Drift", "Episode", "EpisodeRecord", "EpisodeResult", "Key"]

SCHEMA = "capmj.episode/3"
"""The ``schema`` of every ``episodes.jsonl`` line this version writes.  Lines without one were
written before records were typed; ``capmj.episode/1`` lines lack ``error_type``/``error_status``,
``capmj.episode/2`` lines ``perception`` (see :mod:`capmj.bench.migrate`)."""

Key = tuple[str, int, str, "str | None"]
"""The identity of an episode in a grid: (task, seed, agent, model)."""


@dataclass(frozen=True)
class Drift:
    """How far each object the last attempt placed ended from where its pick-and-place put it
    (:func:`capmj.agents.attribution.placement_drift`): the largest drift and one per object."""

    max_m: float
    objects: dict[str, float]

    def to_dict(self) -> dict[str, Any]:
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "Drift":
        return from_plain(cls, data, strict=strict)


@dataclass(frozen=True)
class Episode:
    """The facts of one episode that every reader needs.

    ``llm`` is None for agents without an LLM (written ``{}``), ``drift`` None when it could not be
    measured (written ``{}``); ``final_poses`` maps object name -> ``[x, y, z, qw, qx, qy, qz]``;
    ``calls`` are the episode's LLM calls (messages and answer, :mod:`capmj.agents.lmp.meter`).
    ``error_type`` is the class of what failed (:func:`capmj.errors.error_facts`), None without
    an error; ``error_status`` the failed primitive's status for a ``MotionFailed``.
    ``perception`` is the perception error of an episode whose planner API read the cameras
    (:class:`~capmj.records.perception.PerceptionNotes`); None (and not written) in state mode.
    """

    task: str
    seed: int
    agent: str
    model: str | None
    success: bool
    progress: float
    reward: float
    primitives: int
    attempts: int
    sim_s: float
    wall_s: float
    error: str | None
    goal: str = ""
    diagnostics: tuple[str, ...] = ()
    llm: LLMNotes | None = None
    rrd: str | None = None
    final_poses: dict[str, tuple[float, ...]] = dataclasses.field(default_factory=dict)
    drift: Drift | None = None
    error_type: str | None = None
    error_status: str | None = None
    calls: tuple[dict[str, Any], ...] = ()
    perception: PerceptionNotes | None = None

    EMPTY_IF_NONE: ClassVar[frozenset[str]] = frozenset({"llm", "drift"})
    OMIT_IF_NONE: ClassVar[frozenset[str]] = frozenset({"perception"})

    @property
    def key(self) -> Key:
        return (self.task, self.seed, self.agent, self.model)

    @property
    def llm_attempts(self) -> tuple[Any, ...]:
        """The LLM agent's attempt records (empty for other agents)."""
        return self.llm.attempts if self.llm is not None else ()


@dataclass(frozen=True)
class EpisodeResult(Episode):
    """What :func:`capmj.runner.run_episode` returns; ``to_dict`` has every field, ``calls`` included."""

    def to_dict(self) -> dict[str, Any]:
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "EpisodeResult":
        return from_plain(cls, data, strict=strict)


@dataclass(frozen=True)
class EpisodeRecord(Episode):
    """One line of ``episodes.jsonl``: the result plus its failure label (None: it succeeded) and
    the transcript file its LLM calls were moved to (:mod:`capmj.bench.transcripts`).
    ``config`` names the configuration of a ``--configs`` grid the episode ran in
    (:mod:`capmj.bench.configs`); None (and not written) in a run of one unnamed configuration.

    ``calls`` is written only while not empty: the grid moves them to ``transcripts/`` first; lines
    written before transcripts existed hold them inline.
    """

    failure: str | None = None
    transcript: str | None = None
    config: str | None = None

    OMIT_IF_NONE: ClassVar[frozenset[str]] = frozenset({"transcript", "perception", "config"})

    @property
    def grid_key(self) -> tuple[str | None, str, int, str, str | None]:
        """The identity of an episode in a run folder: its configuration, then :attr:`key`."""
        return (self.config, *self.key)

    @classmethod
    def of(cls, result: Episode, *, failure: str | None, transcript: str | None = None,
           config: str | None = None) -> "EpisodeRecord":
        shared = {f.name: getattr(result, f.name) for f in dataclasses.fields(Episode)}
        return cls(**shared, failure=failure, transcript=transcript, config=config)

    def to_dict(self) -> dict[str, Any]:
        out = to_plain(self)
        if not self.calls:
            del out["calls"]
        out["schema"] = SCHEMA
        return out

    @classmethod
    def from_dict(cls, data: Any, *, strict: bool = True) -> "EpisodeRecord":
        """A record from a line of today's schema (older lines: :func:`capmj.bench.migrate.load_record`)."""
        schema = data.get("schema") if isinstance(data, dict) else None
        if schema != SCHEMA:
            raise RecordError(f"EpisodeRecord: schema {schema!r}, expected {SCHEMA!r}")
        if "calls" not in data:
            data = {**data, "calls": []}
        return from_plain(cls, data, strict=strict, skip=frozenset({"schema"}))
