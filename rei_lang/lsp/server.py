"""``rei-lsp``: the REI language server over stdio, for .room, .mission and .vepl files.

Built on pygls 2 (rather than textX-LS 0.3, which is pre-alpha, pins pygls 1.3, reports one
error per file across a whole line and answers no navigation request). Diagnostics are
``Workspace.check`` — the very code ``rei-gen check`` runs — with each span converted to
the client's code units; the rule id is the diagnostic's ``code``.

Concurrency: all use of the (not thread-safe) ``Workspace`` happens on one worker thread,
in submission order, so the event loop keeps answering requests while a big file is being
checked; an edit that arrives during a check stops that check (rei.lang.lsp.cancelling) and
the edits coalesce into one check of the newest text. Requests read the last finished
analysis, an immutable snapshot; a request about a document opened but not checked yet
waits for its first check. A handler must never let an exception escape: it logs it and
answers empty (a refused rename answers with the reason). The protocol is read by
rei.lang.lsp.framing, which bounds what a client can make the server hold.
"""

from __future__ import annotations

import asyncio
import functools
import inspect
import logging
import sys
import threading
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, BinaryIO, TypeVar

from lsprotocol import types
from pygls.exceptions import JsonRpcException
from pygls.io_ import StdoutWriter
from pygls.lsp.server import LanguageServer
from pygls.uris import from_fs_path, to_fs_path

from rei.lang.errors import Diagnostic, Severity, Span
from rei.lang.lsp import completion as completing
from rei.lang.lsp import framing, symbols, vepl_support
from rei.lang.lsp.cancelling import CheckCanceller
from rei.lang.lsp.navigation import Found, Place, find_in_mission, find_in_room
from rei.lang.lsp.outline import Symbol, mission_outline, room_outline
from rei.lang.lsp.positions import LineIndex, Units, units_for
from rei.lang.mission.document import MissionDocument
from rei.lang.room.document import RoomDocument
from rei.lang.room.model import Room
from rei.lang.source import read_bounded
from rei.lang.workspace import Workspace, known_suffixes

__all__ = ["ReiLanguageServer", "build_server", "main"]

SERVER_NAME = "rei-lsp"
SERVER_VERSION = "0.1.0"
log = logging.getLogger("rei.lsp")
R = TypeVar("R")


@dataclass(frozen=True)
class Analysis:
    """One checked version of an open document: an immutable snapshot requests read."""

    uri: str
    path: str
    version: int | None
    text: str
    diagnostics: tuple[Diagnostic, ...]
    room: RoomDocument | None = None
    mission: MissionDocument | None = None
    vepl: Any = None
    imports_room: str | None = None
    """Resolved path of the room a mission imports (for re-checking it when the room changes)."""


def _resolved(path: str) -> str:
    try:
        return str(Path(path).resolve())
    except (OSError, RuntimeError, ValueError):
        return path


def uri_to_path(uri: str) -> str:
    """The file path of a document URI; an editor's unsaved ``untitled:`` buffer keeps its
    name so that its suffix still selects the language."""
    path = to_fs_path(uri)
    if path:
        return path
    return "/" + uri.split(":", 1)[-1].lstrip("/")


def path_to_uri(path: str) -> str:
    return from_fs_path(_resolved(path)) or Path(_resolved(path)).as_uri()


class ReiLanguageServer(LanguageServer):
    """The server's state lives on this object (nothing at module level)."""

    def __init__(self) -> None:
        super().__init__(SERVER_NAME, SERVER_VERSION,
                         text_document_sync_kind=types.TextDocumentSyncKind.Incremental)
        self.rei = Workspace()
        self.checker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rei-check")
        self.canceller = CheckCanceller()
        self.analyses: dict[str, Analysis] = {}
        self.last_parsed: dict[str, Analysis] = {}
        """Per URI, the newest analysis whose file parsed: names for completion while typing."""
        self.running: set[str] = set()
        self.dirty: set[str] = set()
        self.foreign: dict[str, set[str]] = {}
        """Per URI, the other files (a catalogue) it published diagnostics to."""
        self.first_check: dict[str, asyncio.Event] = {}
        """Per URI being checked: set when the check is done (requests that wait for it)."""

    def start_io(self, stdin: BinaryIO | None = None, stdout: BinaryIO | None = None) -> None:
        """Serve over stdio with REI's bounded reader (rei.lang.lsp.framing) instead of
        pygls's, which a wrong Content-Length could make allocate without bound."""
        self._stop_event = threading.Event()
        reader = framing.BoundedStdin(stdin or sys.stdin.buffer, self.thread_pool)
        self.protocol.set_writer(StdoutWriter(stdout or sys.stdout.buffer))
        try:
            asyncio.run(framing.read_messages(self._stop_event, reader, self.protocol))
        except BrokenPipeError:
            log.error("the client closed the connection; stopping")
        except (KeyboardInterrupt, SystemExit):
            pass
        finally:
            self.shutdown()  # type: ignore[no-untyped-call]

    # --- analysis -------------------------------------------------------------------------

    def units(self) -> Units:
        try:
            return units_for(self.workspace.position_encoding)
        except Exception:  # before initialisation there is no workspace yet
            return units_for(None)

    def submit(self, fn: Callable[..., R], *args: Any) -> asyncio.Future[R]:
        return asyncio.get_running_loop().run_in_executor(self.checker, fn, *args)

    def buffer_changed(self, uri: str) -> None:
        """An open buffer has new text: hand it to the workspace, then check it again."""
        document = self.workspace.text_documents.get(uri)
        if document is None:
            return
        if uri in self.running and self.canceller.cancel(uri):
            log.info("stopped the check of %s: newer text arrived", uri)
        self.submit(self.rei.set_text, uri_to_path(uri), document.source)
        self.schedule(uri)

    def schedule(self, uri: str) -> None:
        if uri in self.running:
            self.dirty.add(uri)
            return
        self.running.add(uri)
        asyncio.get_running_loop().create_task(self._check_until_current(uri))

    async def _check_until_current(self, uri: str) -> None:
        try:
            while True:
                self.dirty.discard(uri)
                document = self.workspace.text_documents.get(uri)
                if document is None:
                    return
                analysis = await self.submit(self.canceller.run, uri,
                                             self.canceller.generation(uri), _analyse, self.rei,
                                             uri, uri_to_path(uri), document.source,
                                             document.version)
                if analysis is None:  # stopped for newer text (or the document closed)
                    self.submit(self.rei.invalidate)  # it may have stopped mid-cache
                    if uri in self.dirty:
                        continue
                    return
                if uri in self.dirty:
                    continue  # newer text arrived while checking: its check supersedes this one
                if uri not in self.workspace.text_documents:
                    return
                self._store(analysis)
                self.publish(analysis)
                if analysis.room is not None:
                    key = _resolved(analysis.path)
                    for other in list(self.analyses.values()):
                        if other.imports_room == key:
                            self.schedule(other.uri)
                return
        except Exception:
            log.exception("checking %s failed", uri)
        finally:
            self.running.discard(uri)
            self._first_check_done(uri)  # a failed check must not keep requests waiting

    async def ready(self, uri: str, *, current: bool = False) -> Analysis | None:
        """The newest analysis of a document. For a document opened but not checked yet,
        wait for its first check (a request must not answer 'nothing here' meanwhile); with
        ``current``, also wait while a check of newer text runs (a rename right after an
        edit must see the names as they are now)."""
        while uri in self.workspace.text_documents and uri in self.running and (
                uri not in self.analyses or current):
            await self.first_check.setdefault(uri, asyncio.Event()).wait()
        return self.analyses.get(uri)

    def _first_check_done(self, uri: str) -> None:
        event = self.first_check.pop(uri, None)
        if event is not None:
            event.set()

    def _store(self, analysis: Analysis) -> None:
        self.analyses[analysis.uri] = analysis
        self._first_check_done(analysis.uri)
        parsed = ((analysis.room is not None and analysis.room.room is not None)
                  or (analysis.mission is not None and analysis.mission.mission is not None)
                  or vepl_support.specification(analysis.vepl) is not None)
        if parsed:
            self.last_parsed[analysis.uri] = analysis

    def publish(self, analysis: Analysis) -> None:
        own = _resolved(analysis.path)
        units = self.units()
        index = LineIndex.of(analysis.text, units)
        mine: list[types.Diagnostic] = []
        others: dict[str, list[Diagnostic]] = {}
        for diagnostic in analysis.diagnostics:
            if diagnostic.span.file == analysis.path or _resolved(diagnostic.span.file) == own:
                mine.append(to_lsp(diagnostic, index))
            elif not diagnostic.span.file.startswith("<"):
                others.setdefault(diagnostic.span.file, []).append(diagnostic)
        self.text_document_publish_diagnostics(types.PublishDiagnosticsParams(
            uri=analysis.uri, diagnostics=mine, version=analysis.version))
        published: set[str] = set()
        for file, diagnostics in others.items():
            other_index = LineIndex.of(_read_text(file), units)
            uri = path_to_uri(file)
            published.add(uri)
            self.text_document_publish_diagnostics(types.PublishDiagnosticsParams(
                uri=uri, diagnostics=[to_lsp(d, other_index) for d in diagnostics]))
        for uri in self.foreign.get(analysis.uri, set()) - published:
            self.clear(uri)
        self.foreign[analysis.uri] = published

    def clear(self, uri: str) -> None:
        self.text_document_publish_diagnostics(types.PublishDiagnosticsParams(uri=uri,
                                                                              diagnostics=[]))

    def closed(self, uri: str) -> None:
        path = uri_to_path(uri)
        self.canceller.cancel(uri)
        self.submit(self.rei.forget_text, path)
        gone = self.analyses.pop(uri, None)
        self.last_parsed.pop(uri, None)
        self._first_check_done(uri)
        self.clear(uri)
        for other in self.foreign.pop(uri, set()):
            self.clear(other)
        if gone is not None and gone.room is not None:
            # Missions that import this room now read it from the disk.
            key = _resolved(path)
            for other_analysis in list(self.analyses.values()):
                if other_analysis.imports_room == key:
                    self.schedule(other_analysis.uri)

    def files_changed_on_disk(self) -> None:
        self.submit(self.rei.invalidate)
        for uri in list(self.workspace.text_documents):
            self.schedule(uri)

    # --- requests -------------------------------------------------------------------------

    def found_at(self, uri: str, position: types.Position) -> tuple[Found, Analysis] | None:
        analysis = self.analyses.get(uri)
        if analysis is None:
            return None
        index = LineIndex.of(analysis.text, self.units())
        line, col = index.rei_position(position)
        found: Found | None = None
        if analysis.room is not None:
            found = find_in_room(analysis.room, index, line, col)
        elif analysis.mission is not None:
            found = find_in_mission(analysis.mission, index, line, col)
        elif analysis.vepl is not None:
            found = vepl_support.find(analysis.vepl, index, line, col)
        return (found, analysis) if found is not None else None

    def location(self, place: Place) -> types.Location:
        text = place.text
        if text is None:
            text = self._open_text(place.path) or _read_text(place.path)
        index = LineIndex.of(text, self.units())
        return types.Location(uri=path_to_uri(place.path), range=index.range(place.span))

    # --- rename and references ----------------------------------------------------------

    async def target_at(self, uri: str, position: types.Position) -> Resolved | None:
        """The declared name under the cursor, with the names its file already declares."""
        await self.ready(uri, current=True)
        document = self.workspace.text_documents.get(uri)
        parsed = self.last_parsed.get(uri)
        if document is None or parsed is None:
            return None
        text = document.source
        line, col = LineIndex.of(text, self.units()).rei_position(position)
        # Tokenising a big file takes a while: off the event loop (the inputs are immutable).
        return await asyncio.to_thread(_resolve, uri_to_path(uri), text, parsed, line, col)

    async def rename_target(self, uri: str, position: types.Position) -> Resolved:
        """``target_at``, or the RequestFailed answer that says nothing here can be renamed."""
        resolved = await self.target_at(uri, position)
        if resolved is None:
            raise JsonRpcException(code=REQUEST_FAILED,
                                   message="nothing to rename here: put the cursor on a name "
                                           "this file or its room declares")
        return resolved

    async def occurrences(self, resolved: Resolved) -> list[symbols.Occurrence]:
        target = resolved.target
        text = self.text_of(target.path) or ""
        if target.language == "vepl":
            return await asyncio.to_thread(symbols.vepl_occurrences, target, text)
        if target.language == "mission":
            return symbols.goal_occurrences(target.path, text, target.name)
        assert resolved.room is not None
        room = resolved.room
        # Missions beside the room and under the workspace folders, read off the event loop.
        roots = [str(Path(target.path).parent), *self.workspace_roots()]
        on_disk = await asyncio.to_thread(symbols.mission_files, roots)
        open_missions = [uri_to_path(u) for u in self.workspace.text_documents
                         if u.endswith(".mission")]
        missions = list(dict.fromkeys([*(_resolved(p) for p in open_missions), *on_disk]))
        texts = {p: self._open_text(p) for p in [target.path, *missions]}
        unopened = [p for p, t in texts.items() if t is None]
        read = await asyncio.to_thread(lambda: {p: symbols.read_text(p) for p in unopened})
        texts.update(read)
        return await asyncio.to_thread(symbols.room_references, room, target.path, target,
                                       lambda p: texts[p] if p in texts else symbols.read_text(p),
                                       missions)

    def text_of(self, path: str) -> str | None:
        """A file's text as the editor holds it (an open buffer), else as saved."""
        text = self._open_text(path)
        return text if text is not None else symbols.read_text(path)

    def workspace_roots(self) -> list[str]:
        try:
            folders = [to_fs_path(f.uri) for f in self.workspace.folders.values()]
            root = self.workspace.root_path
        except Exception:  # before initialisation there is no workspace yet
            return []
        return [p for p in [*folders, root] if p]

    def locations(self, found: Iterable[symbols.Occurrence]) -> list[types.Location]:
        out = []
        for occurrence in found:
            index = LineIndex.of(occurrence.text, self.units())
            out.append(types.Location(uri=path_to_uri(occurrence.path),
                                      range=index.range(occurrence.span)))
        return out

    def _open_text(self, path: str) -> str | None:
        uri = path_to_uri(path)
        document = self.workspace.text_documents.get(uri)
        return document.source if document is not None else None


@dataclass(frozen=True)
class Resolved:
    """A rename or references request's target, and what its file already declares."""

    target: symbols.Target
    declared: dict[str, str]
    room: Room | None
    """The room that declares it (room names only)."""
    written: Span | None = None
    """Where the cursor's name is written in the request's file."""


def _resolve(path: str, text: str, parsed: Analysis, line: int, col: int) -> Resolved | None:
    """The declared name at a 1-based line and column of ``text`` (the last parsed analysis
    of the file says what it declares), with where it is written."""
    toks = symbols.tokens(text)
    token = symbols.token_at(toks, symbols.offset_of(text, line, col))
    if token is None:
        return None
    resolved = _resolve_token(path, text, toks, parsed, token)
    if resolved is None:
        return None
    return replace(resolved, written=symbols.span_of(path, text, token.start, token.end))


def _resolve_token(path: str, text: str, toks: list[symbols.Token], parsed: Analysis,
                   token: symbols.Token) -> Resolved | None:
    suffix = Path(path).suffix
    if suffix == ".room" and parsed.room is not None and parsed.room.room is not None:
        room = parsed.room.room
        if not any(t.start == token.start for _, t in symbols.room_name_tokens(toks)):
            return None
        target = symbols.room_target(room, path, token.text)
        return Resolved(target, symbols.room_declared(room), room) if target else None
    if suffix == ".mission" and parsed.mission is not None:
        room_doc = parsed.mission.room
        imported = room_doc.room if room_doc is not None else None
        target = symbols.mission_target(text, path, token, imported, parsed.imports_room)
        if target is None:
            return None
        if target.language == "room" and imported is not None:
            return Resolved(target, symbols.room_declared(imported), imported)
        return Resolved(target, {g: "goal" for g in symbols.goal_names(text)}, None)
    spec = vepl_support.specification(parsed.vepl)
    if suffix == ".vepl" and spec is not None:
        target = symbols.vepl_target(spec, text, path, token)
        if target is None:
            return None
        declared = symbols.vepl_declared(spec)
        if target.scope is not None:
            declared.update(symbols.local_names(text, target.scope))
        return Resolved(target, declared, None)
    return None


def _read_text(path: str) -> str:
    """A file's text for positions, or "" (bounded, regular files only: a FIFO named as a
    catalogue must not stop the server)."""
    data = read_bounded(path)
    return "" if isinstance(data, Diagnostic) else data.decode("utf-8", errors="replace")


MAX_LISTED_ROOMS = 200


def _room_files(mission_path: str) -> list[str]:
    """The .room files beside a mission (what ``in "…"`` can name), a bounded list."""
    try:
        folder = Path(mission_path).parent
        names = sorted(p.name for p in folder.glob("*.room") if p.is_file())
    except OSError:
        return []
    return names[:MAX_LISTED_ROOMS]


INTERNAL_MESSAGE = ("internal error while checking: {error}; the file is not known to be valid. "
                    "Please report this, with the file, at the REI issue tracker")


def _analyse(workspace: Workspace, uri: str, path: str, text: str, version: int | None
             ) -> Analysis:
    """Runs on the checker thread: the workspace's diagnostics and models of one file.

    A bug in a check must never look like a clean file: whatever escapes the checker is
    shown as an INTERNAL diagnostic at 1:1 (and logged with its traceback)."""
    try:
        return _checked(workspace, uri, path, text, version)
    except Exception as exc:  # any bug of any check (RecursionError included)
        log.exception("checking %s failed", path)
        error = f"{type(exc).__name__}: {exc}"[:300]
        diagnostic = Diagnostic(Span.point(path), "INTERNAL",
                                INTERNAL_MESSAGE.format(error=error))
        return Analysis(uri, path, version, text, (diagnostic,))


def _checked(workspace: Workspace, uri: str, path: str, text: str, version: int | None
             ) -> Analysis:
    if workspace.overlays.get(_resolved(path)) != text:
        # Normally set already (in edit order) by buffer_changed; setting it again would
        # throw away the cached rooms, which a mission re-check after a room edit reuses.
        workspace.set_text(path, text)
    suffix = Path(path).suffix
    if suffix not in known_suffixes():
        # A language whose checker is not installed (yet): say nothing rather than
        # 'expected a .room or .mission'.
        return Analysis(uri, path, version, text, ())
    diagnostics = tuple(workspace.check(path))
    if suffix == ".room":
        return Analysis(uri, path, version, text, diagnostics, room=workspace.room(path))
    if suffix == ".mission":
        mission = workspace.mission(path)
        imported = (_resolved(mission.mission.room_path) if mission.mission is not None
                    else None)
        return Analysis(uri, path, version, text, diagnostics, mission=mission,
                        imports_room=imported)
    return Analysis(uri, path, version, text, diagnostics, vepl=_vepl_model(workspace, path))


def _vepl_model(workspace: Workspace, path: str) -> Any:
    """The .vepl document when the VEPL language is installed (it is optional here)."""
    try:
        return vepl_support.analyse(workspace.source(path))
    except Exception:
        log.exception("reading the .vepl model of %s failed", path)
        return None


def to_lsp(diagnostic: Diagnostic, index: LineIndex) -> types.Diagnostic:
    return types.Diagnostic(
        range=index.range(diagnostic.span),
        message=diagnostic.message,
        severity=(types.DiagnosticSeverity.Error if diagnostic.severity is Severity.ERROR
                  else types.DiagnosticSeverity.Warning),
        code=diagnostic.rule,
        source="rei",
    )


def guarded(default: Callable[[], Any]) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Log any exception of a handler and answer ``default()`` instead: one broken request
    must never take the server down. A ``JsonRpcException`` (a refused rename) is the
    answer, not a bug: it passes through. Works on plain and on async handlers (those that
    wait for a document's check)."""

    def failed(fn: Callable[..., Any]) -> Any:
        log.exception("%s failed", fn.__name__)
        return default()

    def decorate(fn: Callable[..., Any]) -> Callable[..., Any]:
        if inspect.iscoroutinefunction(fn):
            @functools.wraps(fn)
            async def waiting(*args: Any, **kwargs: Any) -> Any:
                try:
                    return await fn(*args, **kwargs)
                except JsonRpcException:
                    raise
                except Exception:
                    return failed(fn)

            return waiting

        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            try:
                return fn(*args, **kwargs)
            except JsonRpcException:
                raise
            except Exception:
                return failed(fn)

        return wrapper

    return decorate


_SYMBOL_KINDS = {
    "room": types.SymbolKind.Module, "mission": types.SymbolKind.Module,
    "grid": types.SymbolKind.Array, "floor": types.SymbolKind.Field,
    "wall": types.SymbolKind.Constant, "object": types.SymbolKind.Object,
    "human": types.SymbolKind.Object, "robot": types.SymbolKind.Class,
    "goal": types.SymbolKind.Event, "query": types.SymbolKind.Function,
    "event": types.SymbolKind.Event, "signal": types.SymbolKind.Constant,
    "requirement": types.SymbolKind.Interface,
}
_COMPLETION_KINDS = {
    "keyword": types.CompletionItemKind.Keyword, "floor": types.CompletionItemKind.Field,
    "wall": types.CompletionItemKind.Constant, "type": types.CompletionItemKind.Class,
    "query": types.CompletionItemKind.Function, "file": types.CompletionItemKind.File,
    "event": types.CompletionItemKind.Event, "parameter": types.CompletionItemKind.Variable,
}


def _document_symbol(symbol: Symbol, index: LineIndex) -> types.DocumentSymbol:
    full = index.range(symbol.span)
    selection = index.range(symbol.selection)
    if not (_before(full.start, selection.start) and _before(selection.end, full.end)):
        selection = types.Range(start=full.start, end=full.start)
    return types.DocumentSymbol(
        name=symbol.name or "?", detail=symbol.detail,
        kind=_SYMBOL_KINDS.get(symbol.kind, types.SymbolKind.Variable),
        range=full, selection_range=selection,
        children=[_document_symbol(c, index) for c in symbol.children])


def _before(a: types.Position, b: types.Position) -> bool:
    return (a.line, a.character) <= (b.line, b.character)


def build_server() -> ReiLanguageServer:
    server = ReiLanguageServer()

    @server.feature(types.TEXT_DOCUMENT_DID_OPEN)
    @guarded(lambda: None)
    def did_open(ls: ReiLanguageServer, params: types.DidOpenTextDocumentParams) -> None:
        ls.buffer_changed(params.text_document.uri)

    @server.feature(types.TEXT_DOCUMENT_DID_CHANGE)
    @guarded(lambda: None)
    def did_change(ls: ReiLanguageServer, params: types.DidChangeTextDocumentParams) -> None:
        ls.buffer_changed(params.text_document.uri)

    @server.feature(types.TEXT_DOCUMENT_DID_SAVE)
    @guarded(lambda: None)
    def did_save(ls: ReiLanguageServer, params: types.DidSaveTextDocumentParams) -> None:
        ls.buffer_changed(params.text_document.uri)

    @server.feature(types.TEXT_DOCUMENT_DID_CLOSE)
    @guarded(lambda: None)
    def did_close(ls: ReiLanguageServer, params: types.DidCloseTextDocumentParams) -> None:
        ls.closed(params.text_document.uri)

    @server.feature(types.WORKSPACE_DID_CHANGE_WATCHED_FILES)
    @guarded(lambda: None)
    def watched_files(ls: ReiLanguageServer, params: types.DidChangeWatchedFilesParams) -> None:
        ls.files_changed_on_disk()

    @server.feature(types.TEXT_DOCUMENT_COMPLETION,
                    types.CompletionOptions(trigger_characters=[":"]))
    @guarded(lambda: None)
    async def completion(ls: ReiLanguageServer, params: types.CompletionParams
                         ) -> types.CompletionList | None:
        uri = params.text_document.uri
        await ls.ready(uri)
        document = ls.workspace.text_documents.get(uri)
        if document is None:
            return None
        index = LineIndex.of(document.source, ls.units())
        line, col = index.rei_position(params.position)
        before = "\n".join(index.lines[max(0, line - 200):line - 1]
                           + (index.line_text(line)[:col - 1],))
        parsed = ls.last_parsed.get(uri)
        suffix = Path(uri_to_path(uri)).suffix
        candidates: list[completing.Candidate]
        if suffix == ".room":
            room_doc = parsed.room if parsed is not None else None
            candidates = completing.room_completions(
                before, room_doc.room if room_doc else None,
                room_doc.catalogue if room_doc else None)
        elif suffix == ".mission":
            mission_doc = parsed.mission if parsed is not None else None
            room = (mission_doc.room.room if mission_doc is not None
                    and mission_doc.room is not None else None)
            candidates = completing.mission_completions(before, room,
                                                        _room_files(uri_to_path(uri)))
        elif suffix == ".vepl":
            model = parsed.vepl if parsed is not None else None
            candidates = completing.vepl_completions(before,
                                                     vepl_support.completion_names(model))
        else:
            candidates = []
        items = [types.CompletionItem(label=c.label, detail=c.detail or None,
                                      kind=_COMPLETION_KINDS.get(c.kind))
                 for c in candidates]
        return types.CompletionList(is_incomplete=False, items=items)

    @server.feature(types.TEXT_DOCUMENT_DEFINITION)
    @guarded(lambda: None)
    async def definition(ls: ReiLanguageServer, params: types.DefinitionParams
                         ) -> list[types.Location] | None:
        await ls.ready(params.text_document.uri)
        hit = ls.found_at(params.text_document.uri, params.position)
        if hit is None or hit[0].declaration is None:
            return None
        return [ls.location(hit[0].declaration)]

    @server.feature(types.TEXT_DOCUMENT_HOVER)
    @guarded(lambda: None)
    async def hover(ls: ReiLanguageServer, params: types.HoverParams) -> types.Hover | None:
        await ls.ready(params.text_document.uri)
        hit = ls.found_at(params.text_document.uri, params.position)
        if hit is None:
            return None
        found, analysis = hit
        index = LineIndex.of(analysis.text, ls.units())
        return types.Hover(
            contents=types.MarkupContent(kind=types.MarkupKind.Markdown, value=found.hover),
            range=index.range(found.written.span))

    @server.feature(types.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    @guarded(lambda: None)
    async def document_symbol(ls: ReiLanguageServer, params: types.DocumentSymbolParams
                              ) -> list[types.DocumentSymbol] | None:
        await ls.ready(params.text_document.uri)
        analysis = ls.last_parsed.get(params.text_document.uri)
        if analysis is None:
            return []
        index = LineIndex.of(analysis.text, ls.units())
        symbols: Iterable[Symbol] = ()
        if analysis.room is not None and analysis.room.room is not None:
            symbols = [room_outline(analysis.room.room, index)]
        elif analysis.mission is not None and analysis.mission.mission is not None:
            symbols = [mission_outline(analysis.mission.mission, index)]
        elif analysis.vepl is not None:
            symbols = vepl_support.outline(analysis.vepl, index)
        return [_document_symbol(s, index) for s in symbols]

    @server.feature(types.TEXT_DOCUMENT_REFERENCES)
    @guarded(lambda: None)
    async def references(ls: ReiLanguageServer, params: types.ReferenceParams
                         ) -> list[types.Location] | None:
        resolved = await ls.target_at(params.text_document.uri, params.position)
        if resolved is None:
            return None
        found = await ls.occurrences(resolved)
        if not params.context.include_declaration:
            found = [o for o in found if not o.declaration]
        return ls.locations(found)

    @server.feature(types.TEXT_DOCUMENT_PREPARE_RENAME)
    @guarded(lambda: None)
    async def prepare_rename(ls: ReiLanguageServer, params: types.PrepareRenameParams
                             ) -> types.PrepareRenamePlaceholder | None:
        resolved = await ls.rename_target(params.text_document.uri, params.position)
        if resolved.target.refused is not None:
            raise JsonRpcException(code=REQUEST_FAILED, message=resolved.target.refused)
        assert resolved.written is not None
        text = ls.workspace.text_documents[params.text_document.uri].source
        return types.PrepareRenamePlaceholder(
            range=LineIndex.of(text, ls.units()).range(resolved.written),
            placeholder=resolved.target.name)

    @server.feature(types.TEXT_DOCUMENT_RENAME,
                    types.RenameOptions(prepare_provider=True))
    @guarded(lambda: None)
    async def rename(ls: ReiLanguageServer, params: types.RenameParams
                     ) -> types.WorkspaceEdit | None:
        resolved = await ls.rename_target(params.text_document.uri, params.position)
        try:
            symbols.check_new_name(resolved.target, params.new_name, resolved.declared)
        except symbols.RenameRefused as refused:
            raise JsonRpcException(code=REQUEST_FAILED, message=str(refused)) from None
        changes: dict[str, list[types.TextEdit]] = {}
        found = await ls.occurrences(resolved)
        for location in ls.locations(found):
            changes.setdefault(location.uri, []).append(
                # A grid's made-up cell names are occurrences by their prefix only.
                types.TextEdit(range=location.range, new_text=params.new_name))
        return types.WorkspaceEdit(changes=changes)

    return server


REQUEST_FAILED = -32803
"""LSP's RequestFailed: the request was valid but cannot be done (the message says why)."""


class _RefusalIsNotABug(logging.Filter):
    """pygls logs every error answer with a traceback; a refused rename is an answer the
    user asked for, so its record loses the traceback and becomes an INFO line."""

    def filter(self, record: logging.LogRecord) -> bool:
        error = record.exc_info[1] if record.exc_info else None
        if isinstance(error, JsonRpcException) and error.code == REQUEST_FAILED:
            record.exc_info = None
            record.levelno, record.levelname = logging.INFO, "INFO"
            record.msg, record.args = "refused: %s", (error.message,)
            return logging.getLogger(record.name).isEnabledFor(logging.INFO)
        return True


def main(argv: list[str] | None = None) -> int:
    """Serve the Language Server Protocol on stdin/stdout until the client says exit."""
    import argparse

    parser = argparse.ArgumentParser(
        prog="rei-lsp",
        description="The REI language server (Language Server Protocol over stdio) for "
                    ".room, .mission and .vepl files. Point your editor at this command.")
    parser.add_argument("--stdio", action="store_true",
                        help="serve over stdin/stdout (the default; accepted because many "
                             "editors pass it)")
    parser.add_argument("--log-level", default="WARNING",
                        choices=("DEBUG", "INFO", "WARNING", "ERROR"),
                        help="what the server logs to stderr")
    args = parser.parse_args(argv)
    logging.basicConfig(stream=sys.stderr, level=args.log_level,
                        format="rei-lsp %(levelname)s %(name)s: %(message)s")
    logging.getLogger("pygls.protocol.json_rpc").addFilter(_RefusalIsNotABug())
    server = build_server()
    try:
        server.start_io()
    finally:
        server.checker.shutdown(wait=False, cancel_futures=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
