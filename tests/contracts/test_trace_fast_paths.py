"""The trace rules' fast paths for the common field (a float in range, a list of floats) take
and refuse exactly what the full checks do, with the same values and the same messages.

The writer checks every line it writes by the reader's rules (runtime/trace/__init__.py), so
these checks run for every sample of every run: ``_Fields.number`` and ``_Fields.numbers``
answer the common case before the field's path is spelt out. A fast path that let through a
bool, a NaN, an infinity, an int too large for a float or a value out of its bounds, or that
handed back another value or type, would write a trace the reader refuses or reads otherwise.
"""

from __future__ import annotations

import math
import sys
from typing import Any

from hypothesis import example, given, settings
from hypothesis import strategies as st

from rei.runtime.trace import TraceError
from rei.runtime.trace.rules import _Fields, _number, _numbers

WHERE, PREFIX, KEY = "trace.jsonl:7", "belief", "odom"

_scalars = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-1.0, max_value=1.0),
    st.integers(min_value=-5, max_value=5),
    st.just(10 ** 400), st.just(-(10 ** 400)), st.just(int(sys.float_info.max)),
    st.booleans(), st.none(), st.text(max_size=3),
    st.just(0.0), st.just(-0.0), st.just(1.5),
)
_numeric = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.booleans(),
                     st.integers(min_value=-5, max_value=5), st.just(10 ** 400))
_values = st.one_of(_scalars, st.lists(_scalars, max_size=4), st.tuples(_scalars, _scalars),
                    st.lists(_numeric, min_size=1, max_size=4))
"""Anything a line may hold, and many lists of number-like values (the fast path's case)."""
_bounds = st.fixed_dictionaries({}, optional={
    "low": st.sampled_from([0.0, -1.0, 1.5]),
    "low_open": st.booleans(),
})


def _outcome(call: Any) -> tuple[str, Any]:
    try:
        value = call()
    except TraceError as exc:
        return ("refused", str(exc))
    return ("taken", (type(value), value if not isinstance(value, tuple)
                      else tuple((type(v), v) for v in value)))


def _same(a: tuple[str, Any], b: tuple[str, Any]) -> bool:
    """Equal outcomes; NaN never gets through, so plain equality after -0.0 vs 0.0 by sign."""
    if a[0] != b[0]:
        return False
    if a[0] == "refused":
        return bool(a[1] == b[1])
    return repr(a[1]) == repr(b[1])


@settings(max_examples=400, deadline=None, derandomize=True)  # no wall-clock limit
@given(value=_values, n=st.integers(min_value=1, max_value=4), bounds=_bounds)
@example(value=[0.0, math.nan, 1.0], n=3, bounds={})
@example(value=[0.0, -math.inf], n=2, bounds={})
@example(value=[True, 1.0], n=2, bounds={})
@example(value=[1, 2.0], n=2, bounds={})
@example(value=[10 ** 400, 2.0], n=2, bounds={})
@example(value=[1.0, 2.0], n=3, bounds={})
@example(value=(1.0, 2.0), n=2, bounds={})
@example(value=[-1.0, 2.0], n=2, bounds={"low": 0.0})
def test_numbers_fast_path_agrees_with_the_full_check(value: Any, n: int,
                                                      bounds: dict[str, Any]) -> None:
    fields = _Fields({KEY: value}, WHERE, PREFIX, frozenset({KEY}), "a belief")
    fast = _outcome(lambda: fields.numbers(KEY, n, "[x, y, yaw]", **bounds))
    full = _outcome(lambda: _numbers(value, WHERE, f"{PREFIX}.{KEY}", n, "[x, y, yaw]",
                                     **bounds))
    assert _same(fast, full), (value, n, bounds, fast, full)


@settings(max_examples=400, deadline=None, derandomize=True)  # no wall-clock limit
@given(value=_scalars, low=st.sampled_from([-math.inf, 0.0, 0.5]),
       high=st.sampled_from([math.inf, 1.0]), low_open=st.booleans())
@example(value=math.inf, low=-math.inf, high=math.inf, low_open=False)
@example(value=math.nan, low=-math.inf, high=math.inf, low_open=False)
@example(value=True, low=-math.inf, high=math.inf, low_open=False)
@example(value=0.0, low=0.0, high=math.inf, low_open=True)
@example(value=1.5, low=0.0, high=1.0, low_open=False)
@example(value=3, low=0.0, high=math.inf, low_open=False)
def test_number_fast_path_agrees_with_the_full_check(value: Any, low: float, high: float,
                                                     low_open: bool) -> None:
    fields = _Fields({KEY: value}, WHERE, PREFIX, frozenset({KEY}), "a belief")
    fast = _outcome(lambda: fields.number(KEY, low=low, high=high, low_open=low_open,
                                          note="(the note)"))
    full = _outcome(lambda: _number(value, WHERE, f"{PREFIX}.{KEY}", low, high, low_open,
                                    "(the note)"))
    assert _same(fast, full), (value, low, high, low_open, fast, full)


def test_the_cases_a_fast_path_gets_wrong_first_are_refused() -> None:
    """Not vacuous: the values a careless fast path would take are in the strategies, and
    the rules refuse them (a NaN, an infinity, a bool, a float below an open bound)."""
    fields = _Fields({KEY: [0.0, math.nan, 1.0]}, WHERE, PREFIX, frozenset({KEY}), "a belief")
    assert _outcome(lambda: fields.numbers(KEY, 3, "[x, y, yaw]"))[0] == "refused"
    fields = _Fields({KEY: [0.0, True, 1.0]}, WHERE, PREFIX, frozenset({KEY}), "a belief")
    assert _outcome(lambda: fields.numbers(KEY, 3, "[x, y, yaw]"))[0] == "refused"
    fields = _Fields({KEY: math.inf}, WHERE, PREFIX, frozenset({KEY}), "a belief")
    assert _outcome(lambda: fields.number(KEY))[0] == "refused"
    fields = _Fields({KEY: 0.0}, WHERE, PREFIX, frozenset({KEY}), "a belief")
    assert _outcome(lambda: fields.number(KEY, low=0.0, low_open=True)) == (
        "refused", "trace.jsonl:7: belief.odom: expected a finite number > 0, found 0.0")
