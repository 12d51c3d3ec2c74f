"""Shared plumbing of template-based targets: jinja2 environments, number formatting, XML checks.

Each target renders files from its own template folder (``generators/templates/<target>/``)
with undefined names as errors, formats every number through ``fmt`` (fixed precision, no
``repr``, no ``-0``) so the same model gives the same bytes, and parses every XML it writes
with lxml (validating it where a schema exists) before the file is handed to ``write_tree``.
This module must never write files or read the textX model: it only turns values into text.
"""

from __future__ import annotations

import json
import math
from importlib import resources
from typing import Any

import jinja2
import markupsafe
from lxml import etree

from rei.generators.errors import GenerationError

DECIMALS = 6
"""Micrometres and microradians: far below anything a simulator or a robot resolves."""


def fmt(value: float | int, decimals: int = DECIMALS) -> str:
    """A number as fixed-precision text without trailing zeros: 1, 0.5, -0.25 (never -0)."""
    number = float(value)
    if not math.isfinite(number):
        raise GenerationError(f"expected a finite number in the generated file, found {number}")
    rounded = round(number, decimals) + 0.0  # + 0.0 turns -0.0 into 0.0
    text = f"{rounded:.{decimals}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def fmt_all(values: Any, decimals: int = DECIMALS) -> str:
    """Numbers joined by spaces, as SDF vectors and poses want them."""
    return " ".join(fmt(v, decimals) for v in values)


def rounded(value: Any, decimals: int = DECIMALS) -> Any:
    """A JSON-ready copy of a value with every float rounded (for deterministic JSON)."""
    if isinstance(value, bool) or value is None or isinstance(value, (str, int)):
        return value
    if isinstance(value, float):
        fmt(value)  # rejects non-finite numbers
        return round(value, decimals) + 0.0
    if isinstance(value, dict):
        return {str(k): rounded(v, decimals) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [rounded(v, decimals) for v in value]
    raise TypeError(f"cannot put {type(value).__name__} into generated JSON")


def dump_json(value: Any) -> str:
    """Deterministic JSON: sorted keys, rounded floats, two-space indent, final newline."""
    return json.dumps(rounded(value), indent=2, sort_keys=True, ensure_ascii=False,
                      allow_nan=False) + "\n"


def comment_text(text: str) -> markupsafe.Markup:
    """Text safe inside an XML comment: no '--', no escaping (comments are read by people)."""
    cleaned = str(text).replace("--", "- -").replace("\n", " ")
    if cleaned.endswith("-"):
        cleaned += " "
    return markupsafe.Markup(cleaned)


def template_loader(target: str) -> jinja2.BaseLoader:
    """The loader of a target's template folder inside the installed package."""
    return jinja2.PackageLoader("rei.generators", f"templates/{target}")


def make_environment(loader: jinja2.BaseLoader, *, xml: bool = True) -> jinja2.Environment:
    """A strict environment: undefined names fail, values are XML-escaped when ``xml``."""
    env = jinja2.Environment(loader=loader, undefined=jinja2.StrictUndefined,
                             autoescape=xml, keep_trailing_newline=True, trim_blocks=True,
                             lstrip_blocks=True)
    env.filters["f"] = fmt
    env.filters["vec"] = fmt_all
    env.filters["comment"] = comment_text
    return env


def render(env: jinja2.Environment, name: str, **context: Any) -> str:
    """Render one template; any failure becomes a GenerationError naming template and line."""
    try:
        return env.get_template(name).render(**context)
    except jinja2.TemplateSyntaxError as exc:
        raise GenerationError(f"template '{exc.name or name}' line {exc.lineno}: "
                              f"{exc.message}") from None
    except jinja2.TemplateNotFound as exc:
        raise GenerationError(f"expected a template '{exc.name}', found none in the "
                              f"target's template folder") from None
    except GenerationError as exc:
        raise GenerationError(f"template '{name}': {exc}") from None
    except Exception as exc:  # noqa: BLE001  (undefined names, filters, anything in the template)
        line = _template_line(exc, name)
        where = f" line {line}" if line is not None else ""
        raise GenerationError(f"template '{name}'{where}: {type(exc).__name__}: {exc}") from None


def _template_line(exc: BaseException, name: str) -> int | None:
    """The template line a render error happened at, from the traceback jinja2 rewrites."""
    tb = exc.__traceback__
    line = None
    while tb is not None:
        filename = tb.tb_frame.f_code.co_filename
        if filename.endswith(name) or filename == "<template>":
            line = tb.tb_lineno
        tb = tb.tb_next
    return line


def _schema(name: str) -> etree.XMLSchema:
    # Parsed per check rather than cached in the module: a few milliseconds, and no state.
    with resources.files("rei.generators.schemas").joinpath(name).open("rb") as handle:
        return etree.XMLSchema(etree.parse(handle))


def check_xml(text: str, what: str, schema: str | None = None) -> None:
    """Raise GenerationError unless ``text`` is well-formed XML (and valid against ``schema``)."""
    try:
        document = etree.fromstring(text.encode("utf-8"))
    except etree.XMLSyntaxError as exc:
        raise GenerationError(f"generated {what} is not well-formed XML: {exc}") from None
    if schema is not None:
        validator = _schema(schema)
        if not validator.validate(document):
            first = validator.error_log[0]
            raise GenerationError(f"generated {what} does not follow {schema}: line "
                                  f"{first.line}: {first.message}")


def normalise_angle(angle: float) -> float:
    """An angle in radians mapped into (-pi, pi], so 270 degrees is written as -pi/2."""
    wrapped = math.remainder(angle, math.tau)
    return math.pi if math.isclose(wrapped, -math.pi) else wrapped


def relative_to(path: str, start_file: str) -> str:
    """``path`` written relative to the folder of ``start_file`` (POSIX separators).

    Generated files name their sources this way, never by absolute path, so the same input
    gives the same bytes wherever the project is checked out.
    """
    import os.path  # noqa: PLC0415

    folder = os.path.dirname(os.path.abspath(start_file))
    return os.path.relpath(os.path.abspath(path), folder).replace(os.sep, "/")
