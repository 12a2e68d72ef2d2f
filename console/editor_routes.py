"""The editor's list of shipped sessions to open (operators and admins):

    GET /api/editor/shipped          {"sessions": [{id, family, level, index}, ...]}
    GET /api/editor/shipped/{id}     that session as the editor edits it (404: not shipped)

A shipped session is named by its id, never by a path, and read from the shipped suite's
folder only, as every session file is read (benchmark.authoring.session_folders). Saving under a
shipped session's id is refused (console.editor.save_session).
"""


from collections.abc import Callable
from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException

from benchmark.authoring.session_folders import SessionFolders, SessionPathError
from benchmark.authoring.suite import SESSIONS_DIR
from console.editor import editable_session
from console.shipped import edited_id, shipped_listing, shipped_path
from llm_tools.input_limits import preview

__all__ = ["add_editor_routes"]


def add_editor_routes(app: FastAPI, staff: Callable[..., str]) -> None:
    """Add the shipped-session routes to the console's `app` (`staff`: its key dependency)."""
    Staff = Annotated[str, Depends(staff)]

    @app.get("/api/editor/shipped")
    def shipped(role: Staff) -> dict[str, Any]:
        return {"sessions": shipped_listing()}

    @app.get("/api/editor/shipped/{ident}")
    def open_shipped(ident: str, role: Staff) -> dict[str, Any]:
        path = shipped_path(ident)
        if path is None:
            raise HTTPException(404, f"no shipped session {preview(ident)}; "
                                     "GET /api/editor/shipped lists them")
        try:  # a plain def route: FastAPI runs it in a worker thread
            found, data = SessionFolders((SESSIONS_DIR,)).read(path.name)
            session = editable_session(data, str(found))
        except SessionPathError as error:
            raise HTTPException(error.http_status, str(error)) from None
        except ValueError as error:
            raise HTTPException(422, str(error)) from None
        return {"session": session, "proposed_id": edited_id(ident)}
