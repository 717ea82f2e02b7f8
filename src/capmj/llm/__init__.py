"""LLM access for capmj: a retrying, caching, accounting client over litellm.

Importing this package is cheap: litellm (seconds to import) is loaded on the first real call.
"""

from capmj.llm.cache import CompletionCache, cache_key
from capmj.llm.client import LLMClient
from capmj.llm.config import LLMConfig
from capmj.llm.messages import image_part, text_part
from capmj.llm.records import CallRecord, Completion, ToolCall, Usage

__all__ = [
    "CallRecord",
    "Completion",
    "CompletionCache",
    "LLMClient",
    "LLMConfig",
    "ToolCall",
    "Usage",
    "cache_key",
    "image_part",
    "text_part",
]
