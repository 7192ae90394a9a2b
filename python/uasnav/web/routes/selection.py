"""The mission-selection page: the form, its results, and exports of the same answer."""

from __future__ import annotations

import json
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Request
from fastapi.responses import HTMLResponse, JSONResponse, PlainTextResponse, Response
from markupsafe import Markup
from starlette.datastructures import UploadFile

from uasnav.errors import UasnavError
from uasnav.jsonable import to_jsonable
from uasnav.mission import request as select_request
from uasnav.mission import summary
from uasnav.mission.matrices import NECESSARY
from uasnav.mission.request import OPTION_GROUPS, OptionError
from uasnav.web import area_map, forms, selection_view
from uasnav.web.context import (
    MAX_BODY_BYTES,
    MAX_FIELDS,
    MAX_FILES,
    MAX_PART_BYTES,
    ApiError,
    WebContext,
    data_uri,
    download,
    field_of,
    web_context,
)

router = APIRouter(include_in_schema=False)
Ctx = Annotated[WebContext, Depends(web_context)]


def grouped(fields: list[forms.FormField]) -> list[tuple[str, list[forms.FormField]]]:
    """The fields under their option's group, in the groups' order (an option with no group
    would fall under "Requirements": nothing is ever dropped)."""
    out: dict[str, list[forms.FormField]] = {g: [] for g in OPTION_GROUPS}
    for f in fields:
        out[f.option.group if f.option.group in out else "requirements"].append(f)
    return [(OPTION_GROUPS[g], fs) for g, fs in out.items() if fs]


def selection_page(
    request: Request,
    ctx: WebContext,
    values: dict[str, Any],
    errors: dict[str, str],
    result: dict[str, Any] | None,
    status: int,
) -> HTMLResponse:
    fields = forms.form_fields(ctx.choices)
    core = sorted((f for f in fields if f.core), key=lambda f: forms.CORE_FIELDS.index(f.name))
    advanced = [f for f in fields if not f.core]
    page = {
        "request": request,
        "core": core,
        "groups": grouped(advanced),
        "advanced_open": any(f.name in errors for f in advanced),
        "area_map": result.get("area_map") if result else None,
        "max_upload": MAX_BODY_BYTES,
        "values": values,
        "pairs": {
            o.name: forms.pair_values(values.get(o.name))
            for o in select_request.SELECT_OPTIONS
            if o.kind == "pairs"
        },
        "errors": errors,
        "result": result,
        "page": "select",
    }
    return ctx.templates.TemplateResponse(request, "select.html", page, status_code=status)


def run_view(ctx: WebContext, values: dict[str, Any], files: dict[str, Any]) -> dict[str, Any]:
    """The results part of the page for one request."""
    selection = ctx.selection(values, files)
    sel = to_jsonable(selection.to_dict())
    req = ctx.parse_select_options({**values, **files})
    equipment: dict[str, list[dict[str, Any]]] = {}
    for e in sel["equipment"]:
        equipment.setdefault(e["group"], []).append(e)
    # downloads of exactly what is shown (no second run, uploaded files included)
    downloads = {
        "json": data_uri("application/json", json.dumps(sel, ensure_ascii=False, indent=2)),
        "ranking": data_uri("text/csv", selection_view.ranking_csv(sel)),
        "rejections": data_uri("text/csv", selection_view.rejections_csv(sel)),
    }
    # the authorisation summary is the page's print view: one document, one renderer
    downloads["summary_html"] = data_uri("text/html", summary.summary_html(selection))
    downloads["summary_json"] = data_uri(
        "application/json", json.dumps(summary.summary_dict(selection), ensure_ascii=False, indent=2)
    )
    onboard = {x["id"]: x["state"] for x in sel["chosen_equipment"] or []}
    return {
        "sel": sel,
        "summary": Markup(summary.summary_fragment(selection)),
        "onboard": onboard,
        "equipment": equipment,
        "plots": selection_view.transfer_plots(sel, req.targets, ctx.docs.database),
        "breakdown": selection_view.breakdown(sel),
        "downloads": downloads,
        "margin": selection_view.margin,
        "necessary": NECESSARY,
        "area_map": map_of(req),
    }


def map_of(req: Any) -> Markup | None:
    """The offline map of the request's area (and zones), or None without an area."""
    area = getattr(req, "area", None)
    if area is None:
        return None
    lon, lat = area.centre()
    layers = area_map.MapLayers(area, getattr(req, "zones", None) or (), points={"take-off": (lat, lon)})
    return area_map.area_map(layers)


@router.get("/summary.css")
def summary_css() -> Response:
    # the authorisation summary's own stylesheet, so the printed page is that document
    return Response(summary.SUMMARY_CSS, media_type="text/css", headers={"cache-control": "no-cache"})


@router.get("/", response_class=HTMLResponse)
def index(request: Request, ctx: Ctx) -> Response:
    return selection_page(request, ctx, {}, {}, None, 200)


@router.post("/select", response_class=HTMLResponse)
async def select_form(request: Request, ctx: Ctx) -> Response:
    form = await request.form(max_files=MAX_FILES, max_fields=MAX_FIELDS, max_part_size=MAX_PART_BYTES)
    values = forms.values_from_form(form, form.getlist)
    up_area = form.get("area")
    has_area = isinstance(up_area, UploadFile) and bool(up_area.filename)
    errors = {**forms.field_errors(values), **forms.empty_required(form, has_area)}
    result = None
    files: dict[str, Any] = {}
    for opt in forms.form_fields(ctx.choices):
        up = form.get(opt.name)
        if opt.widget == "file" and isinstance(up, UploadFile) and up.filename:
            data = await up.read(forms.MAX_OPTION_FILE_BYTES + 1)
            try:
                files[opt.name] = forms.file_value(opt.name, up.filename, data)
            except OptionError as e:
                errors[e.option] = str(e)
    if not errors:
        try:
            result = run_view(ctx, values, files)
        except (OptionError, ApiError) as e:
            errors[field_of(e) or "form"] = getattr(e, "message", str(e))
        except UasnavError as e:
            errors["form"] = str(e)
    return selection_page(request, ctx, values, errors, result, 422 if errors else 200)


@router.get("/select/export.{fmt}")
def select_export(request: Request, ctx: Ctx, fmt: str, table: str = "ranking") -> Response:
    values = dict(request.query_params)
    values.pop("table", None)
    if fmt not in ("json", "csv"):
        raise ApiError(404, "format", f"format: {fmt!r} is not json or csv")
    sel = ctx.selection_json(values)
    if fmt == "json":
        return download(JSONResponse(sel), "selection.json")
    if table not in ("ranking", "rejections"):
        raise ApiError(422, "table", f"table: {table!r} is not ranking or rejections")
    text = selection_view.ranking_csv(sel) if table == "ranking" else selection_view.rejections_csv(sel)
    return download(PlainTextResponse(text, media_type="text/csv; charset=utf-8"), f"{table}.csv")
