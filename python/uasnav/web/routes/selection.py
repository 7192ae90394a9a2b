"""The mission-selection page: the form, its results, and exports of the same answer."""

from __future__ import annotations

import json
import logging
from typing import Annotated, Any

import numpy as np
from fastapi import APIRouter, Depends, Request
from fastapi.responses import HTMLResponse, JSONResponse, PlainTextResponse, Response
from markupsafe import Markup
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile

from uasnav.errors import UasnavError
from uasnav.geo import frames
from uasnav.jsonable import to_jsonable
from uasnav.mission import request as select_request
from uasnav.mission import summary
from uasnav.mission.matrices import NECESSARY
from uasnav.mission.request import OPTION_GROUPS, OptionError
from uasnav.web import area_map, forms, selection_view
from uasnav.web.context import (
    GENERIC_500,
    MAX_BODY_BYTES,
    ApiError,
    WebContext,
    data_uri,
    download,
    field_of,
    in_operator_words,
    read_form,
    web_context,
)

log = logging.getLogger("uasnav.web")
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
    kept: dict[str, tuple[str, str]] | None = None,
) -> HTMLResponse:
    fields = forms.form_fields(ctx.choices)
    core = sorted((f for f in fields if f.core), key=lambda f: forms.CORE_FIELDS.index(f.name))
    advanced = [f for f in fields if not f.core]
    page = {
        "request": request,
        "core": core,
        "groups": grouped(advanced),
        "advanced_open": any(f.name in errors for f in advanced)
        or any(n in errors for n in forms.PLAN_FIELDS),
        "plan_fields": forms.PLAN_FIELDS,
        "area_map": result.get("area_map") if result else None,
        "max_upload": MAX_BODY_BYTES,
        "values": values,
        # a field the operator emptied stays empty (values leave blank fields out)
        "posted": bool(values),
        "pairs": {
            o.name: forms.pair_values(values.get(o.name))
            for o in select_request.SELECT_OPTIONS
            if o.kind == "pairs"
        },
        "errors": errors,
        "kept": kept or {},
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
    # the authorisation summary is the page's print view: one document, one renderer, in the
    # form's words
    shown = in_operator_words(selection, values)
    downloads["summary_html"] = data_uri("text/html", summary.summary_html(shown))
    downloads["summary_json"] = data_uri(
        "application/json", json.dumps(summary.summary_dict(shown), ensure_ascii=False, indent=2)
    )
    onboard = {x["id"]: x["state"] for x in sel["chosen_equipment"] or []}
    return {
        "sel": sel,
        "summary": Markup(summary.summary_fragment(shown)),
        "onboard": onboard,
        "equipment": equipment,
        "plots": selection_view.transfer_plots(sel, req.targets, ctx.docs.database),
        "breakdown": selection_view.breakdown(sel),
        "downloads": downloads,
        "margin": selection_view.margin,
        "necessary": NECESSARY,
        "area_map": map_of(req),
        "req": req,
    }


#: Media types of the files a plan writes, by suffix.
_MIME = {".json": "application/json", ".plan": "application/json", ".html": "text/html"}


def plan_view(pr: Any) -> dict[str, Any]:
    """The survey-plan part of the page: ``result.json`` and a download of every file."""
    downloads = [
        (name, data_uri(_MIME.get(name[name.rfind(".") :], "text/plain"), data.decode("utf-8")))
        for name, data in pr.files.items()
    ]
    return {"result": pr.result, "downloads": downloads, "error": None}


def map_of(req: Any, pr: Any = None) -> Markup | None:
    """The offline map of the request's area and zones, with the survey lines and the take-off
    and pilot points when a plan was made; None without an area."""
    area = getattr(req, "area", None)
    if area is None:
        return None
    zones = getattr(req, "zones", None) or ()
    lines: list[list[tuple[float, float]]] = []
    dist = getattr(req, "distances", None) or {}
    if pr is not None and pr.survey is not None:
        lat0, lon0 = pr.survey.origin
        for ln in pr.survey.lines:
            en = np.asarray([ln.run_in_en, ln.start_en, ln.end_en, ln.run_out_en], dtype=float)
            la, lo, _ = frames.enu_to_geodetic(en[:, 0], en[:, 1], 0.0, lat0, lon0, 0.0)
            lines.append(list(zip(np.atleast_1d(la).tolist(), np.atleast_1d(lo).tolist(), strict=True)))
        dist = pr.result.get("distances") or dist
    points: dict[str, tuple[float, float]] = {}
    if dist.get("takeoff"):
        points["take-off"] = (float(dist["takeoff"][0]), float(dist["takeoff"][1]))
        if dist.get("pilot") and list(dist["pilot"]) != list(dist["takeoff"]):
            points["pilot"] = (float(dist["pilot"][0]), float(dist["pilot"][1]))
    else:
        lon, lat = area.centre()
        points["take-off"] = (lat, lon)
    return area_map.area_map(area_map.MapLayers(area, zones, lines, points))


@router.get("/summary.css")
def summary_css() -> Response:
    # the authorisation summary's own stylesheet, so the printed page is that document
    return Response(summary.SUMMARY_CSS, media_type="text/css", headers={"cache-control": "no-cache"})


@router.get("/", response_class=HTMLResponse)
def index(request: Request, ctx: Ctx) -> Response:
    return selection_page(request, ctx, {}, {}, None, 200)


@router.post("/select", response_class=HTMLResponse)
async def select_form(request: Request, ctx: Ctx) -> Response:
    form = await read_form(request)
    values = forms.values_from_form(form, form.getlist)
    errors: dict[str, str] = {}
    result = None
    files: dict[str, Any] = {}
    # uploads, or the documents of the last run the page kept (a file field cannot be re-filled)
    kept: dict[str, tuple[str, str]] = {}
    file_names = [f.name for f in forms.form_fields(ctx.choices) if f.widget == "file"]
    file_names += [n for n, spec in forms.PLAN_FIELDS.items() if spec[3] == "file"]
    for name in file_names:
        up = form.get(name)
        try:
            if isinstance(up, UploadFile) and up.filename:
                data = await up.read(forms.MAX_OPTION_FILE_BYTES + 1)
                files[name] = forms.file_value(name, up.filename, data)
                kept[name] = forms.kept_file(up.filename, data)
            elif (k := forms.read_kept(name, form)) is not None:
                files[name] = forms.file_value(name, k[0], k[1])
                kept[name] = forms.kept_file(k[0], k[1])
        except OptionError as e:
            errors[e.option] = str(e)
    # values checked with the documents: a take-off point is measured on the area
    errors = {**forms.field_errors({**values, **files}), **errors}
    errors.update(forms.empty_required(form, "area" in files))
    extra = forms.plan_values(form)
    values.update(extra)
    if not errors:
        intents = files.pop("intents", None)
        try:
            result = run_view(ctx, {k: v for k, v in values.items() if k not in extra}, files)
            if "area" in files and ctx.run_plan is not None:
                result.update(await plan_part(ctx, values, files, intents, result["req"]))
        except (OptionError, ApiError) as e:
            errors[field_of(e) or "form"] = getattr(e, "message", str(e))
            result = None
        except UasnavError as e:
            errors["form"] = str(e)
            result = None
    return selection_page(request, ctx, values, errors, result, 422 if errors else 200, kept)


async def plan_part(
    ctx: WebContext, values: dict[str, Any], files: dict[str, Any], intents: Any, req: Any
) -> dict[str, Any]:
    """The survey plan of the uploaded area (``uasnav plan`` on the form's values) and its map;
    a plan nothing can fly is said in the plan's part, the selection above it still shown."""
    opts = {**values, **files}
    if intents is not None:
        opts["intents"] = (intents,)
    try:
        pr = await run_in_threadpool(ctx.run_plan, opts)
    except OptionError:
        raise
    except (UasnavError, ValueError) as e:
        return {"plan": {"result": None, "downloads": [], "error": str(e)}}
    except Exception:
        # the selection above stands on its own: a planner failure costs the plan, not the page
        log.exception("survey plan failed")
        return {"plan": {"result": None, "downloads": [], "error": GENERIC_500}}
    return {"plan": plan_view(pr), "area_map": map_of(req, pr)}


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
