"""The task and template editor's routes (operators and admins, as every editor route; an
agent's key is refused with 403: templates, check trees and oracle proofs are hidden from
agents):

    GET  /api/editor/templates               {"templates": [{id, source, file, category, ...}]}
    GET  /api/editor/templates/{id}          {id, source, file, text} (404: no such template)
    POST /api/editor/templates/validate      {text} -> {ok, id, category, ...}
                                             | 422 {ok: false, error, field}
    POST /api/editor/templates/instantiate   {session, text, count, seed}
                                             -> {template, tasks: [{task, entities, tree}],
                                                 unfit, note} | 422 {ok: false, error, field}
    POST /api/editor/templates/save          {text} -> {ok, id, path} (templates/<id>.json in
                                             the editor's save folder) | 422
    POST /api/editor/tasks/recheck           {session} -> {tasks: [{id, solvable, leaf,
                                             endpoint, reason}], solvable, total} | 422
    POST /api/editor/proofs                  {session, task_id} -> the proof (202; 409 while
                                             another flies; 422 for a task that cannot fly)
    GET  /api/editor/proofs/{id}             the proof: status running, passed, failed or
                                             error; its record (checks, replay) once done

Bodies are bounded and parsed as on every surface (`llm_tools.body_limit.json_body`), then
validated by their pydantic models (console.request_bodies).
"""

from collections.abc import Callable
from typing import TYPE_CHECKING, Annotated, Any

from fastapi import Depends, FastAPI, HTTPException
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from console.editor import EditorError
from console.request_bodies import InstantiateBody, ProveBody, RecheckBody, TemplateTextBody
from console.task_editor import (
    TemplateTextError,
    check_template,
    instantiate,
    recheck,
    save_template,
    template_listing,
    template_text,
)
from console.task_proof import ProofBusy
from llm_tools.body_limit import json_body
from llm_tools.input_limits import MAX_SESSION_NUMBER_ABS, preview

if TYPE_CHECKING:
    from console.app import ConsoleState

__all__ = ["add_task_editor_routes"]


def _body(model: type[Any]) -> Any:
    return Depends(json_body(model, max_number_abs=MAX_SESSION_NUMBER_ABS))


def _refusal(error: ValueError) -> JSONResponse:
    if isinstance(error, TemplateTextError):
        return JSONResponse(error.to_json(), status_code=422)
    failure = error if isinstance(error, EditorError) else EditorError(str(error))
    return JSONResponse(failure.to_json(), status_code=422)


def add_task_editor_routes(app: FastAPI, state: "ConsoleState", staff: Callable[..., str]
                           ) -> None:
    """Add the task and template editor's routes to the console's `app`."""
    Staff = Annotated[str, Depends(staff)]

    @app.get("/api/editor/templates")
    def templates(role: Staff) -> dict[str, Any]:
        return {"templates": template_listing(state.editor_root)}

    @app.get("/api/editor/templates/{ident}")
    def template(ident: str, role: Staff) -> dict[str, Any]:
        found = template_text(ident, state.editor_root)
        if found is None:
            raise HTTPException(404, f"no template {preview(ident)}; GET /api/editor/templates "
                                     "lists them")
        return found

    @app.post("/api/editor/templates/validate")
    def validate(role: Staff, body: Annotated[TemplateTextBody, _body(TemplateTextBody)]
                 ) -> JSONResponse:
        try:
            model = check_template(body.text)
        except TemplateTextError as error:
            return _refusal(error)
        return JSONResponse({"ok": True, "id": model.id, "category": model.category,
                             "difficulty": model.difficulty, "phrasings": len(model.phrasings),
                             "entities": [g.group for g in model.entities]})

    @app.post("/api/editor/templates/instantiate")
    def draw(role: Staff, body: Annotated[InstantiateBody, _body(InstantiateBody)]
             ) -> JSONResponse:
        try:
            return JSONResponse(instantiate(body.session, body.text, count=body.count,
                                            seed=body.seed))
        except ValueError as error:
            return _refusal(error)

    @app.post("/api/editor/templates/save")
    async def save(role: Staff, body: Annotated[TemplateTextBody, _body(TemplateTextBody)]
                   ) -> JSONResponse:
        try:
            return JSONResponse(await run_in_threadpool(save_template, body.text,
                                                        state.editor_root))
        except ValueError as error:
            return _refusal(error)

    @app.post("/api/editor/tasks/recheck")
    def recheck_tasks(role: Staff, body: Annotated[RecheckBody, _body(RecheckBody)]
                      ) -> JSONResponse:
        try:
            return JSONResponse(recheck(body.session))
        except ValueError as error:
            return _refusal(error)

    @app.post("/api/editor/proofs")
    async def prove(role: Staff, body: Annotated[ProveBody, _body(ProveBody)]
                    ) -> JSONResponse:
        try:
            session, spec = await run_in_threadpool(state.proofs.prepare, body.session,
                                                    body.task_id)
            proof = state.proofs.start(session, spec)
        except ProofBusy as busy:
            raise HTTPException(409, str(busy)) from None
        except ValueError as error:
            return _refusal(error)
        return JSONResponse(proof.to_json(), status_code=202)

    @app.get("/api/editor/proofs/{ident}")
    def proof(ident: str, role: Staff) -> dict[str, Any]:
        found = state.proofs.seen(ident)
        if found is None:
            raise HTTPException(404, f"no proof {preview(ident)} (the last "
                                     f"{len(state.proofs.proofs)} are kept)")
        return found.to_json()
