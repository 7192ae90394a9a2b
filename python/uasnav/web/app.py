"""The web application of ``uasnav serve``: mission selection and trajectory prediction.

One FastAPI application serves the HTML pages (Jinja2 templates, one stylesheet and one small
script of this package: nothing from a CDN), the JSON API (``/api/…``) and its OpenAPI
description (``/openapi.json``, rendered as a page at ``/api`` by the app itself). Each page and
the API is a router of :mod:`uasnav.web.routes`; pages and API call the same functions:
:func:`uasnav.mission.request.run_select` on the documents loaded when the server started, and
:mod:`uasnav.web.prediction`. The ``/live`` page (:mod:`uasnav.web.live`) shows live
telemetry.

Every page works without JavaScript: forms post, tables filter and sort through query
parameters, downloads are links. Errors: a bad value is a 4xx naming the field (on a page, the
message beside the field); anything unexpected is a 500 with a generic message, the details only
in the server log.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, Response
from fastapi.staticfiles import StaticFiles
from fastapi.templating import Jinja2Templates

from uasnav import __version__
from uasnav.mission.planner import plan
from uasnav.mission.request import parse_select_options, run_select
from uasnav.mission.scoring import PARAMETERS
from uasnav.web import forms, live
from uasnav.web.context import (
    GENERIC_500,
    MAX_BODY_BYTES,
    ApiError,
    Documents,
    WebContext,
    auto_num,
    choices_of,
    load_documents,
    num,
    plain,
)
from uasnav.web.page_errors import OversizePages, PageRenderer
from uasnav.web.routes import api, api_page, database, selection, trajectory
from uasnav.web.routes.api import select_schema
from uasnav.web.security import BodyTooLarge, GuardMiddleware

log = logging.getLogger("uasnav.web")
HERE = Path(__file__).parent

_SECURITY_HEADERS = {
    "content-security-policy": (
        "default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'; "
        "form-action 'self'; frame-ancestors 'none'; base-uri 'none'"
    ),
    "x-content-type-options": "nosniff",
    # no-referrer would make the browser send "Origin: null" on our own form posts
    "referrer-policy": "same-origin",
    "x-frame-options": "DENY",
}


def _error_json(status: int, field: str | None, message: str) -> JSONResponse:
    return JSONResponse({"error": message, "field": field}, status_code=status)


def create_app(docs: Documents | None = None, allowed_hosts: tuple[str, ...] = ()) -> Any:
    """The ASGI application (FastAPI wrapped in the Host/Origin/size guard).

    Parameters
    ----------
    docs : Documents, optional
        Loaded database, matrices and regulations; default the shipped copies.
    allowed_hosts : tuple of str
        Host names this server answers to besides the loopback names.
    """
    docs = docs or load_documents()
    app = FastAPI(
        title="uasnav mission planner",
        version=__version__,
        description="Mission selection (thesis §5.2) and trajectory prediction (thesis §5.1).",
        docs_url=None,
        redoc_url=None,
    )
    templates = Jinja2Templates(directory=str(HERE / "templates"))
    templates.env.globals.update(version=__version__, sources=docs.sources, parameters=PARAMETERS)
    templates.env.filters["num"] = num
    templates.env.filters["auto"] = auto_num
    templates.env.filters["plain"] = plain
    app.state.docs = docs
    app.state.web = WebContext(
        docs=docs,
        templates=templates,
        choices=choices_of(docs),
        # looked up at call time, so the selector this module names is the one that runs
        run_select=lambda *a, **k: run_select(*a, **k),
        parse_select_options=lambda v: parse_select_options(v),
        run_plan=lambda *a, **k: plan(*a, **k),
    )
    _add_error_handlers(app, templates)

    # -- routers: one per page, one for the JSON API ------------------------------------------
    app.mount("/static", StaticFiles(directory=str(HERE / "static")), name="static")
    app.include_router(selection.router)
    app.include_router(trajectory.router)
    app.include_router(database.router)
    app.include_router(api_page.router)
    app.include_router(api.router)
    app.include_router(live.router)

    # -- middleware (outermost last) -----------------------------------------------------------
    guarded = GuardMiddleware(app, allowed_hosts, MAX_BODY_BYTES, _SECURITY_HEADERS)
    return OversizePages(guarded, _oversize_pages(app.state.web), MAX_BODY_BYTES)


def _oversize_pages(web: WebContext) -> dict[str, PageRenderer]:
    """Each page's answer to a form post over the body limit: the page, the message beside its
    upload fields."""

    def select(request: Request, message: str) -> Response:
        names = [f.name for f in forms.form_fields(web.choices) if f.widget == "file"]
        errors = {name: f"{name}: {message}" for name in names} or {"form": message}
        return selection.selection_page(request, web, {}, errors, None, 413)

    def predict(request: Request, message: str) -> Response:
        return trajectory.traj_page(request, web, {}, {"plan": f"plan: {message}"}, None, 413)

    return {"/select": select, "/trajectory": predict}


def _add_error_handlers(app: FastAPI, templates: Jinja2Templates) -> None:
    """Every error as JSON ``{"error", "field"}`` on the API, as a page elsewhere."""

    @app.exception_handler(ApiError)
    async def _api_error(request: Request, e: ApiError) -> Response:
        return _error_json(e.status, e.field, e.message)

    @app.exception_handler(RequestValidationError)
    async def _validation(request: Request, e: RequestValidationError) -> Response:
        err = e.errors()[0] if e.errors() else {}
        loc = [str(x) for x in err.get("loc", ()) if x not in ("body", "query", "path")]
        name = loc[-1] if loc else None
        return _error_json(422, name, f"{name}: {err.get('msg', 'invalid value')}")

    @app.exception_handler(BodyTooLarge)
    async def _too_large(request: Request, e: BodyTooLarge) -> Response:
        return _error_json(413, "body", str(e))

    @app.exception_handler(Exception)
    async def _internal(request: Request, e: Exception) -> Response:
        log.exception("unexpected error on %s %s", request.method, request.url.path)
        if request.url.path.startswith("/api"):
            return _error_json(500, None, GENERIC_500)
        return HTMLResponse(
            templates.get_template("error.html").render(request=request, message=GENERIC_500), status_code=500
        )


__all__ = ["Documents", "create_app", "load_documents", "select_schema"]
