"""A bug in a check must never make a file look clean in the editor (issue 13.5): the
server's analysis turns whatever escapes the checker into an INTERNAL diagnostic at 1:1.

In-process, because no known input breaks a check any more (the ones that did, a symlink
loop and a thousand {+}, are located diagnostics: tests/lsp/test_lsp_hostile.py).
"""

from __future__ import annotations

from pathlib import Path

from rei.lang.errors import Diagnostic
from rei.lang.lsp.server import _analyse
from rei.lang.workspace import Workspace
from tests.lsp.rooms import ROOM


class _BrokenWorkspace(Workspace):
    """A workspace whose checks have a bug (a stand-in for the next RecursionError)."""

    def check(self, path: str | Path) -> list[Diagnostic]:
        raise RecursionError("maximum recursion depth exceeded")


def test_an_internal_error_is_a_diagnostic_never_a_clean_file(tmp_path: Path) -> None:
    path = str(tmp_path / "any.room")
    analysis = _analyse(_BrokenWorkspace(), Path(path).as_uri(), path, ROOM, 3)
    [diagnostic] = analysis.diagnostics
    assert (diagnostic.rule, diagnostic.span.line, diagnostic.span.col) == ("INTERNAL", 1, 1)
    assert diagnostic.message.startswith("internal error while checking: RecursionError")
    assert "report" in diagnostic.message and analysis.version == 3
