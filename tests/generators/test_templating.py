"""Deterministic number formatting, JSON, comments and template errors of the shared helpers."""

from __future__ import annotations

import math
from pathlib import Path

import jinja2
import pytest

from rei.generators.errors import GenerationError
from rei.generators.templating import (
    check_xml,
    comment_text,
    dump_json,
    fmt,
    fmt_all,
    make_environment,
    normalise_angle,
    relative_to,
    render,
)


@pytest.mark.parametrize("value,text", [
    (0, "0"), (1.0, "1"), (0.5, "0.5"), (-0.25, "-0.25"), (-0.0, "0"), (-1e-9, "0"),
    (1 / 3, "0.333333"), (1e6, "1000000"), (0.1 + 0.2, "0.3"), (12, "12"),
    (math.pi, "3.141593"),
])
def test_fmt_is_fixed_precision_without_repr(value: float, text: str) -> None:
    assert fmt(value) == text


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_fmt_rejects_non_finite_numbers(bad: float) -> None:
    with pytest.raises(GenerationError, match="finite"):
        fmt(bad)


def test_vectors_and_json_are_deterministic() -> None:
    assert fmt_all((0.1 + 0.2, -0.0, 2)) == "0.3 0 2"
    text = dump_json({"b": 0.1 + 0.2, "a": [1, -0.0, None, True]})
    assert text == '{\n  "a": [\n    1,\n    0.0,\n    null,\n    true\n  ],\n  "b": 0.3\n}\n'
    with pytest.raises(GenerationError):
        dump_json({"x": math.nan})


def test_angles_are_normalised_into_minus_pi_to_pi() -> None:
    assert normalise_angle(math.radians(270)) == pytest.approx(-math.pi / 2)
    assert normalise_angle(-math.pi) == pytest.approx(math.pi)
    assert normalise_angle(0.5) == 0.5


def test_comments_never_close_early() -> None:
    text = str(comment_text("a -- b -"))
    assert "--" not in text and not text.endswith("-")


def test_relative_paths_never_absolute(tmp_path: Path) -> None:
    assert relative_to(str(tmp_path / "rooms" / "a.room"), str(tmp_path / "m" / "x.mission")) \
        == "../rooms/a.room"


def test_template_errors_name_the_template_and_line() -> None:
    env = make_environment(jinja2.DictLoader({
        "syntax.j2": "line one\n{% for x in %}\n",
        "undefined.j2": "line one\nline two\n{{ missing.field }}\n",
    }))
    with pytest.raises(GenerationError, match=r"template 'syntax.j2' line 2"):
        render(env, "syntax.j2")
    with pytest.raises(GenerationError, match=r"template 'undefined.j2' line 3: .*missing"):
        render(env, "undefined.j2")
    with pytest.raises(GenerationError, match="expected a template 'absent.j2'"):
        render(env, "absent.j2")


def test_xml_values_are_escaped_and_checked() -> None:
    env = make_environment(jinja2.DictLoader({"a.j2": "<a n=\"{{ v }}\"/>"}))
    text = render(env, "a.j2", v='"<&>')
    check_xml(text, "a.xml")
    with pytest.raises(GenerationError, match="not well-formed"):
        check_xml("<a><b></a>", "broken.xml")
