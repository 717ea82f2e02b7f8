"""Kinds of error are classes, and the text each shows is the one its message prefix showed before.

The texts are what the LLM is shown on a re-plan and what cached completions were asked with: a
class that replaces a ``PlanError("NameError: …")`` must render exactly the same characters, both
alone (:func:`describe`) and quoted inside another error (:func:`inner_text`).
"""

from __future__ import annotations

import pytest

from capmj.agents.lmp.codeprep import function_defs
from capmj.errors import FunctionNotWritten, PlanError, ReturnNotSet, describe, inner_text


def test_a_function_parse_function_did_not_write_shows_the_old_text():
    with pytest.raises(FunctionNotWritten) as info:
        function_defs("def other(x):\n    return x\n", "wanted")
    exc = info.value
    assert describe(exc) == "PlanError: NameError: parse_function did not define 'wanted' (defined: ['other'])"
    assert inner_text(exc) == "NameError: parse_function did not define 'wanted' (defined: ['other'])"
    assert isinstance(exc, PlanError) and not isinstance(exc, NameError)


def test_a_helper_that_set_no_return_value_shows_the_old_text():
    exc = ReturnNotSet("parse_obj_name code did not set 'ret_val'")
    assert describe(exc) == describe(PlanError("NameError: parse_obj_name code did not set 'ret_val'"))


def test_inner_text_is_the_message_for_errors_shown_as_their_own_class():
    assert inner_text(PlanError("NameError: x")) == "NameError: x"
    assert inner_text(ValueError("bad")) == "bad"
