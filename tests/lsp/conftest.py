"""A real LSP client (pytest-lsp) driving the real ``rei-lsp`` over stdio, and helpers.

The client records every ``publishDiagnostics`` in order, so a test can wait for the
diagnostics of one document version (or the next re-check of a document) without sleeping.
"""

from __future__ import annotations

import asyncio
import sys
from pathlib import Path
from typing import Any

import pytest_lsp
from lsprotocol import types
from pygls.protocol import default_converter
from pytest_lsp import ClientServerConfig, LanguageClient
from pytest_lsp.client import DEFAULT_CLIENT_FEATURES, register_lsp_features

SERVER_COMMAND = [sys.executable, "-m", "rei.lang.lsp.server"]
WAIT_SECONDS = 120.0
"""Only a guard against a hung test run; no test asserts on time."""


class RecordingClient(LanguageClient):
    """pytest-lsp's client, also keeping every published diagnostics message in order."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.published: list[types.PublishDiagnosticsParams] = []
        self.published_event = asyncio.Event()


def _record(client: RecordingClient, params: types.PublishDiagnosticsParams) -> None:
    client.diagnostics[params.uri] = params.diagnostics
    client.published.append(params)
    client.published_event.set()


def make_client() -> RecordingClient:
    client = RecordingClient(converter_factory=default_converter)
    features = dict(DEFAULT_CLIENT_FEATURES)
    features[types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS] = _record
    register_lsp_features(client, features)
    return client


CONFIG = ClientServerConfig(server_command=SERVER_COMMAND, client_factory=make_client)


def initialize_params(root: Path | None = None) -> types.InitializeParams:
    return types.InitializeParams(
        capabilities=types.ClientCapabilities(
            text_document=types.TextDocumentClientCapabilities(
                document_symbol=types.DocumentSymbolClientCapabilities(
                    hierarchical_document_symbol_support=True),
                hover=types.HoverClientCapabilities(
                    content_format=[types.MarkupKind.Markdown, types.MarkupKind.PlainText]),
                publish_diagnostics=types.PublishDiagnosticsClientCapabilities(
                    version_support=True),
            ),
            general=types.GeneralClientCapabilities(
                position_encodings=[types.PositionEncodingKind.Utf16]),
        ),
        root_uri=root.as_uri() if root is not None else None,
    )


async def wait_published(client: RecordingClient, uri: str, *, after: int = 0,
                         version: int | None = None) -> list[types.Diagnostic]:
    """The diagnostics of the first publish for ``uri`` at index ``after`` or later (of
    ``version`` when given)."""

    async def wait() -> list[types.Diagnostic]:
        while True:
            client.published_event.clear()
            for params in client.published[after:]:
                if params.uri == uri and (version is None or params.version == version):
                    return list(params.diagnostics)
            await client.published_event.wait()

    return await asyncio.wait_for(wait(), WAIT_SECONDS)


def publish_index(client: RecordingClient, uri: str, version: int) -> int:
    """Where in the record the diagnostics of one version of a document were last published
    (versions restart when a document is opened again)."""
    return max(i for i, p in enumerate(client.published)
               if p.uri == uri and p.version == version)


class Editor:
    """Opens, edits, saves and closes documents through the client, like an editor does."""

    def __init__(self, client: RecordingClient) -> None:
        self.client = client
        self.versions: dict[str, int] = {}
        self.texts: dict[str, str] = {}

    async def open(self, path: Path, text: str | None = None) -> list[types.Diagnostic]:
        uri = path.resolve().as_uri()
        text = path.read_text(encoding="utf-8") if text is None else text
        mark = len(self.client.published)
        self.versions[uri] = 1
        self.texts[uri] = text
        language = path.suffix.lstrip(".")
        self.client.text_document_did_open(types.DidOpenTextDocumentParams(
            text_document=types.TextDocumentItem(uri=uri, language_id=language, version=1,
                                                 text=text)))
        return await wait_published(self.client, uri, after=mark, version=1)

    def change_nowait(self, path: Path, text: str) -> int:
        """Replace the whole text; the new version."""
        uri = path.resolve().as_uri()
        self.versions[uri] += 1
        self.texts[uri] = text
        self.client.text_document_did_change(types.DidChangeTextDocumentParams(
            text_document=types.VersionedTextDocumentIdentifier(uri=uri,
                                                                version=self.versions[uri]),
            content_changes=[types.TextDocumentContentChangeWholeDocument(text=text)]))
        return self.versions[uri]

    async def change(self, path: Path, text: str) -> list[types.Diagnostic]:
        mark = len(self.client.published)
        version = self.change_nowait(path, text)
        return await wait_published(self.client, path.resolve().as_uri(), after=mark,
                                    version=version)

    async def edit(self, path: Path, line: int, start: int, end: int, new: str
                   ) -> list[types.Diagnostic]:
        """An incremental edit of one line's characters [start, end) (0-based)."""
        uri = path.resolve().as_uri()
        mark = len(self.client.published)
        self.versions[uri] += 1
        lines = self.texts[uri].split("\n")
        lines[line] = lines[line][:start] + new + lines[line][end:]
        self.texts[uri] = "\n".join(lines)
        self.client.text_document_did_change(types.DidChangeTextDocumentParams(
            text_document=types.VersionedTextDocumentIdentifier(uri=uri,
                                                                version=self.versions[uri]),
            content_changes=[types.TextDocumentContentChangePartial(
                range=types.Range(start=types.Position(line=line, character=start),
                                  end=types.Position(line=line, character=end)),
                text=new)]))
        return await wait_published(self.client, uri, after=mark, version=self.versions[uri])

    def save(self, path: Path) -> None:
        self.client.text_document_did_save(types.DidSaveTextDocumentParams(
            text_document=types.TextDocumentIdentifier(uri=path.resolve().as_uri())))

    async def close(self, path: Path) -> list[types.Diagnostic]:
        uri = path.resolve().as_uri()
        mark = len(self.client.published)
        self.client.text_document_did_close(types.DidCloseTextDocumentParams(
            text_document=types.TextDocumentIdentifier(uri=uri)))
        self.versions.pop(uri, None)
        return await wait_published(self.client, uri, after=mark)


def position_of(text: str, needle: str, occurrence: int = 0, offset: int = 0
                ) -> types.Position:
    """The LSP position (UTF-16) of the ``occurrence``-th ``needle`` in ``text``, plus
    ``offset`` characters."""
    start = -1
    for _ in range(occurrence + 1):
        start = text.index(needle, start + 1)
    start += offset
    line = text.count("\n", 0, start)
    line_start = text.rfind("\n", 0, start) + 1
    prefix = text[line_start:start]
    return types.Position(line=line, character=len(prefix.encode("utf-16-le")) // 2)


@pytest_lsp.fixture(config=CONFIG, scope="module")
async def client(lsp_client: RecordingClient):  # type: ignore[no-untyped-def]
    """One initialized session of the real server per test module (a module may define its
    own ``client``, as test_rename_references does for its workspace folder)."""
    await lsp_client.initialize_session(initialize_params())
    yield
    await lsp_client.shutdown_session()
