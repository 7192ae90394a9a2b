"""``/api``: the OpenAPI description rendered as a page by the app itself (no CDN)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Request
from fastapi.responses import HTMLResponse, Response

from uasnav.web.context import WebContext, web_context

router = APIRouter(include_in_schema=False)


@router.get("/api", response_class=HTMLResponse)
def api_docs(request: Request, ctx: Annotated[WebContext, Depends(web_context)]) -> Response:
    return ctx.templates.TemplateResponse(
        request, "api.html", {"request": request, "spec": request.app.openapi(), "page": "api"}
    )
