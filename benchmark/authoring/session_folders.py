"""Where a server reads session files when a request names one (`POST /sessions/load
{"path": ...}`, the console editor's "open a file"): only from configured folders, only
regular `.json` files of at most `MAX_SESSION_FILE_BYTES`, read off the event loop.

The folders are the shipped suite (`benchmark/sessions/`), those given with `--session-dir`,
and the console editor's save folder; single files are allowed too (those a server was
started with). A relative path is looked up in each folder in turn; an absolute one must lie
inside a folder, after `..` and symbolic links are resolved. A session can also be sent in a
request's body (an upload), which needs no folder.

Refusals name the reason, with the HTTP status a web surface answers (`SessionPathError`):
422 a path that is not text, not a `.json` name, or not a regular file (a FIFO, a device, a
folder); 403 outside the folders; 404 no such file in them; 413 over the size limit.
"""

from __future__ import annotations

import asyncio
import os
import stat
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from benchmark.authoring.suite import SESSIONS_DIR
from llm_tools.input_limits import (
    MAX_SESSION_NUMBER_ABS,
    InputError,
    check_text,
    parse_json,
    preview,
)

__all__ = ["MAX_SESSION_FILE_BYTES", "MAX_SESSION_PATH_CHARS", "SessionFolders",
           "SessionPathError"]

MAX_SESSION_FILE_BYTES = 16 * 1024 * 1024
"""The largest session file read on request (the shipped ones are under 120 kB)."""
MAX_SESSION_PATH_CHARS = 4096
_KINDS = ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISDIR, "a folder"),
          (stat.S_ISSOCK, "a socket"))


class SessionPathError(ValueError):
    """A session path refused; `http_status` is what a web surface answers."""

    def __init__(self, message: str, http_status: int) -> None:
        super().__init__(message)
        self.http_status = http_status


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


class SessionFolders:
    """The folders (and single files) session files are read from on request."""

    def __init__(self, folders: Iterable[Path] = (SESSIONS_DIR,),
                 files: Iterable[Path] = ()) -> None:
        self.folders: list[Path] = []
        self.files: list[Path] = []
        for folder in folders:
            self.allow_folder(folder)
        for file in files:
            self.allow_file(file)

    def allow_folder(self, folder: str | Path) -> None:
        """Read session files anywhere under `folder` (resolved now)."""
        resolved = Path(folder).resolve()
        if resolved not in self.folders:
            self.folders.append(resolved)

    def allow_file(self, file: str | Path) -> None:
        """Read this one file (a session a server was started with)."""
        resolved = Path(file).resolve()
        if resolved not in self.files:
            self.files.append(resolved)

    def describe(self) -> str:
        places = [str(f) for f in self.folders] + [str(f) for f in self.files]
        return ", ".join(places) or "none"

    def resolve(self, text: Any) -> Path:
        """The allowed file `text` names (not opened yet); SessionPathError otherwise."""
        if not isinstance(text, str) or not text.strip():
            raise SessionPathError(f"path: expected a session file's path, got "
                                   f"{preview(text)}", 422)
        try:
            check_text(text, "path", limit=MAX_SESSION_PATH_CHARS)
        except InputError as error:
            raise SessionPathError(str(error), 422) from None
        given = Path(text)
        candidates = [given] if given.is_absolute() else [f / given for f in self.folders]
        inside = False
        for candidate in candidates:
            try:
                resolved = candidate.resolve()
            except (OSError, RuntimeError):  # a symbolic link loop
                continue
            allowed = self._allows(resolved)
            if os.path.lexists(candidate):
                if not allowed:
                    raise self._outside(text)
                self._check_suffix(text, given)
                return resolved
            inside = inside or allowed
        if not inside:
            raise self._outside(text)
        self._check_suffix(text, given)
        raise SessionPathError(f"path {preview(text)}: no such session file in the session "
                               f"folders ({self.describe()})", 404)

    def _allows(self, resolved: Path) -> bool:
        return resolved in self.files or any(resolved.is_relative_to(f) for f in self.folders)

    def _outside(self, text: str) -> SessionPathError:
        return SessionPathError(
            f"path {preview(text)} is outside the session folders ({self.describe()}); a "
            "server reads session files from these only (add one with --session-dir DIR, or "
            "send the session in the body)", 403)

    @staticmethod
    def _check_suffix(text: str, given: Path) -> None:
        if given.suffix.lower() != ".json":
            raise SessionPathError(f"path {preview(text)}: a session file's name ends in "
                                   ".json", 422)

    def read(self, text: Any) -> tuple[Path, Any]:
        """The allowed file `text` names and its JSON (a session's bounds): blocking, so
        call it in a thread (`read_async`). A FIFO or device is refused before it is
        opened, and opened without blocking in case one replaced the file since."""
        path = self.resolve(text)
        raw = _read_regular(path)
        try:
            return path, parse_json(raw, str(path), max_bytes=MAX_SESSION_FILE_BYTES,
                                    max_number_abs=MAX_SESSION_NUMBER_ABS)
        except InputError as error:
            raise SessionPathError(str(error), error.http_status) from None

    async def read_async(self, text: Any) -> tuple[Path, Any]:
        """`read` in a worker thread, so the event loop keeps serving."""
        return await asyncio.to_thread(self.read, text)


def _check_stat(path: Path, info: os.stat_result) -> None:
    if not stat.S_ISREG(info.st_mode):
        raise SessionPathError(f"{path} is {_kind(info.st_mode)}, not a regular file: a "
                               "session is read from a regular .json file", 422)
    if info.st_size > MAX_SESSION_FILE_BYTES:
        raise SessionPathError(f"{path} is {info.st_size} bytes; a session file is at most "
                               f"{MAX_SESSION_FILE_BYTES} bytes (16 MiB)", 413)


def _read_regular(path: Path) -> bytes:
    try:
        _check_stat(path, os.stat(path))
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))
    except OSError as error:
        raise SessionPathError(f"{path}: cannot read: {error.strerror}", 422) from None
    with os.fdopen(fd, "rb") as file:
        _check_stat(path, os.fstat(fd))  # the file may have been replaced since
        data = file.read(MAX_SESSION_FILE_BYTES + 1)
    if len(data) > MAX_SESSION_FILE_BYTES:
        raise SessionPathError(f"{path} grew past {MAX_SESSION_FILE_BYTES} bytes while "
                               "read", 413)
    return data
