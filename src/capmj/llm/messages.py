"""Chat message content in the OpenAI format every litellm provider takes: text and inline
images, the parts a vision reporter mixes in one message."""

from __future__ import annotations

import base64
from collections.abc import Mapping
from typing import Any

from capmj.errors import ConfigError

Message = Mapping[str, Any]
"""One chat message: ``{"role": ..., "content": ...}``."""


def image_part(png_bytes: bytes, *, mime: str = "image/png") -> dict[str, Any]:
    """An OpenAI-format image content part carrying ``png_bytes`` inline as a data URL."""
    if not isinstance(png_bytes, (bytes, bytearray)) or not png_bytes:
        raise ConfigError("image_part needs non-empty image bytes")
    encoded = base64.b64encode(bytes(png_bytes)).decode("ascii")
    return {"type": "image_url", "image_url": {"url": f"data:{mime};base64,{encoded}"}}


def text_part(text: str) -> dict[str, Any]:
    """An OpenAI-format text content part (to mix with :func:`image_part` in one message)."""
    return {"type": "text", "text": text}
