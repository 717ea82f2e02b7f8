"""Typed, versioned records of what an episode did: frozen dataclasses with ``to_dict()`` and
``from_dict(strict=True)``.

:mod:`~capmj.records.episode` (the runner's :class:`EpisodeResult`, the run folder's
:class:`EpisodeRecord`), :mod:`~capmj.records.notes` (the LLM agent's :class:`LLMNotes`,
:class:`Spend`), :mod:`~capmj.records.perception` (:class:`PerceptionNotes` of an rgbd
episode), :mod:`~capmj.records.attempt` (:class:`AttemptRecord`); :mod:`~capmj.records.codec`
turns them into JSON data and back.  They sit below every layer (like :mod:`capmj.errors`): agents
and the runner write them, the benchmark and replay read them.
"""

from capmj.records.attempt import ATTEMPT_FIELDS, CALL_FORMS, LOOP_RULES, ApiError, AttemptRecord, ToolCallRecord
from capmj.records.episode import SCHEMA, Drift, Episode, EpisodeRecord, EpisodeResult, Key
from capmj.records.notes import LLMNotes, Spend, SpendLimits
from capmj.records.perception import PerceptionCall, PerceptionNotes

__all__ = ["ATTEMPT_FIELDS", "CALL_FORMS", "LOOP_RULES", "SCHEMA", "ApiError", "AttemptRecord", "Drift", "Episode", "EpisodeRecord",
           "EpisodeResult", "Key", "LLMNotes", "PerceptionCall", "PerceptionNotes", "Spend", "SpendLimits",
           "ToolCallRecord"]
