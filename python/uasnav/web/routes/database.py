"""The database pages: ``/db/{table}``, filtered and sorted through query parameters."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Request
from fastapi.responses import HTMLResponse, RedirectResponse, Response

from uasnav.web import tables
from uasnav.web.context import ApiError, Documents, WebContext, web_context

router = APIRouter(include_in_schema=False)
Ctx = Annotated[WebContext, Depends(web_context)]


def table_of(docs: Documents, name: str) -> tables.Table:
    """The database table ``name``; an unknown name is a 404 naming the table."""
    makers = {
        "uas": lambda: tables.uas_table(docs.database),
        "cameras": lambda: tables.camera_table(docs.database),
        "regulations": lambda: tables.regulations_table(docs.regulations),
        "missions": lambda: tables.mission_table(docs.matrices),
        "equipment": lambda: tables.equipment_table(docs.matrices),
    }
    if name not in makers:
        raise ApiError(404, "table", f"table: {name!r} is not one of {', '.join(tables.TABLES)}")
    return makers[name]()


@router.get("/db")
def db_index() -> Response:
    return RedirectResponse("/db/uas", status_code=303)


@router.get("/db/{name}", response_class=HTMLResponse)
def db_page(
    request: Request, ctx: Ctx, name: str, q: str = "", sort: str = "", desc: bool = False
) -> Response:
    cols, rows = tables.filter_sort(table_of(ctx.docs, name), q[:200], sort, desc)
    page = {
        "request": request,
        "name": name,
        "title": tables.TABLES[name],
        "tables": tables.TABLES,
        "columns": cols,
        "rows": rows,
        "q": q[:200],
        "sort": sort,
        "desc": desc,
        "page": "db",
    }
    return ctx.templates.TemplateResponse(request, "db.html", page)
