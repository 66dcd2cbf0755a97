"""Exceptions of the Python API. Each carries where the problem is (`file`, `line`, `column`,
when known), as the CLI's `file:line:col: message` on stderr with exit code 2."""

from __future__ import annotations

import os
import re
from typing import Optional


class ModellintError(Exception):
    """modellint could not do the job (the CLI's exit code 2).

    `message` is what is wrong; `file`, `line`, `column` say where, when known (1-based)."""

    def __init__(
        self,
        message: str,
        file: Optional[str] = None,
        line: Optional[int] = None,
        column: Optional[int] = None,
    ) -> None:
        self.message = message
        self.file = file
        self.line = line
        self.column = column
        super().__init__(self.location() + message if file else message)

    def location(self) -> str:
        """`file:line:col: ` (as much of it as is known), or '' without a file."""
        if not self.file:
            return ""
        parts = [self.file] + [str(x) for x in (self.line, self.column) if x is not None]
        return ":".join(parts) + ": "


class ModelError(ModellintError):
    """The model, its spec or config could not be loaded (malformed XML, a missing include,
    a bad TOML key): `file:line:col` of the offending text."""


class RecordingError(ModellintError):
    """A recording could not be read or does not fit the model (`file:line` of the row or
    header, as `modellint gap` reports it)."""


class UsageError(ModellintError, ValueError):
    """An option the CLI would reject (unknown name, malformed value); the message is the
    CLI's, naming the flag."""


_UNKNOWN = re.compile(r"unexpected argument '--([^'=\s]+)")


def _usage_text(text: str) -> str:
    """clap's message in the API's words: an unknown flag is an unknown keyword option."""
    m = _UNKNOWN.search(text)
    if m:
        name = m.group(1).replace("-", "_")
        return (
            f"unknown option `{name}`: the keyword options are the flags of the `modellint` "
            f"command (`modellint gap --help`, `modellint fit --help`, `modellint --help`)"
        )
    return text.strip().removeprefix("error: ")


_AT = re.compile(r"^(?P<file>.+?):(?P<line>\d+): (?P<msg>.*)$", re.S)


def _split_location(text: str):
    """`file:line: message` or `file: message` where `file` exists → (file, line, message)."""
    m = _AT.match(text)
    if m and os.path.exists(m.group("file")):
        return m.group("file"), int(m.group("line")), m.group("msg")
    head, sep, rest = text.partition(": ")
    if sep and os.path.exists(head):
        return head, None, rest
    return None, None, text


def from_native(err: Exception, recordings: Optional[dict] = None) -> ModellintError:
    """The typed exception for a `modellint._native.NativeError(kind, text, file, line, col)`.
    `recordings` maps the CSV files written for in-memory recordings to their names, so that an
    error in one names the recording (and its row) rather than a temporary file."""
    kind, text, file, line, column = err.args
    if kind == "model":
        return ModelError(text, file, line, column)
    if kind == "usage":
        return UsageError(_usage_text(text))
    file, line, message = _split_location(text)
    if file is None:
        return ModellintError(message)
    if recordings and os.path.abspath(file) in recordings:
        name, header_lines = recordings[os.path.abspath(file)]
        row = line - header_lines if line is not None and line > header_lines else None
        where = f" (row {row} of the arrays)" if row is not None else ""
        return RecordingError(f"{message}{where}", f"<recording {name}>", row, None)
    return RecordingError(message, file, line, None)
