"""The JSON API (``/api/…``), described at ``/openapi.json``: the same functions as the pages."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Depends, Request
from fastapi.responses import JSONResponse, PlainTextResponse, Response

from uasnav.errors import DataFormatError
from uasnav.jsonable import to_jsonable
from uasnav.mission import request as select_request
from uasnav.web import forms, prediction, tables
from uasnav.web.context import (
    MAX_JSON_BYTES,
    ApiError,
    WebContext,
    read_form,
    web_context,
)
from uasnav.web.routes.database import table_of
from uasnav.web.routes.trajectory import predict_from_form

router = APIRouter()
Ctx = Annotated[WebContext, Depends(web_context)]

#: The multipart body of ``POST /api/trajectory/predict`` for the OpenAPI description.
PREDICT_SCHEMA: dict[str, Any] = {
    "schema": {
        "type": "object",
        "required": ["plan"],
        "properties": {
            "plan": {
                "type": "string",
                "format": "binary",
                "description": "Plan: QGroundControl .plan, Mission Planner .waypoints, or CSV "
                "(lat,lon[,alt] or north,east)",
            },
            "model": {
                "type": "string",
                "format": "binary",
                "description": "Model JSON of `uasnav trajectory train` (default: the built-in model)",
            },
            "autopilot": {
                "type": "string",
                "enum": ["arducopter", "px4-mc", "plane"],
                "description": "Autopilot that flies a .plan/.waypoints mission (firmware defaults); "
                "default from the plan as `uasnav trajectory mission`. The answer's `autopilot` object "
                "carries the keys of `uasnav trajectory mission --json` (null for a CSV route)",
            },
            "wind_speed": {"type": "number", "minimum": 0, "maximum": 100, "description": "m/s"},
            "wind_from": {"type": "number", "description": "deg from north, where the wind comes from"},
            "speed": {"type": "number", "exclusiveMinimum": 0, "description": "commanded speed, m/s"},
            "required": {"type": "string", "description": "4D plan: required time per waypoint, s (T0,T1,…)"},
            "tolerance": {
                "type": "number",
                "minimum": 0,
                "default": 5,
                "description": "4D time tolerance, s",
            },
            "format": {"type": "string", "enum": ["json", "csv", "geojson"]},
        },
    }
}


def select_schema() -> dict[str, Any]:
    """JSON schema of ``POST /api/select``'s body, from the option table."""
    props: dict[str, Any] = {}
    kind_types: dict[str, Any] = {
        "real": "number",
        "int": "integer",
        "flag": "boolean",
        "choice": "string",
        "text": "string",
        "size": ["string", "array"],
        "pairs": ["string", "object"],
        "file": ["string", "object"],
    }
    for o in select_request.SELECT_OPTIONS:
        if not forms.is_field(o):
            continue
        s: dict[str, Any] = {"description": forms.operator_help(o) + (f" Unit: {o.unit}." if o.unit else "")}
        if o.kind in kind_types:
            s["type"] = kind_types[o.kind]
        if o.minimum is not None:
            s["exclusiveMinimum" if o.minimum_open else "minimum"] = o.minimum
        if o.maximum is not None:
            s["maximum"] = o.maximum
        if o.choices:
            s["enum"] = list(o.choices)
        if o.default is not None:
            s["default"] = to_jsonable(o.default)
        props[o.name] = s
    return {"type": "object", "additionalProperties": False, "properties": props}


async def json_body(request: Request) -> Any:
    """The request's JSON body, size-bounded; content type, encoding and syntax checked."""
    from uasnav import jsoncheck

    ctype = request.headers.get("content-type", "")
    if not ctype.split(";")[0].strip().lower() == "application/json":
        # also a CSRF guard: a cross-site HTML form cannot send application/json
        raise ApiError(415, "content-type", "content-type: expected application/json")
    raw = b""
    async for chunk in request.stream():
        raw += chunk
        if len(raw) > MAX_JSON_BYTES:
            raise ApiError(413, "body", f"body: over {MAX_JSON_BYTES} bytes")
    try:
        return jsoncheck.parse(raw.decode("utf-8"), "body: not valid JSON")
    except UnicodeDecodeError:
        raise ApiError(400, "body", "body: not UTF-8") from None
    except DataFormatError as e:
        raise ApiError(400, "body", str(e)) from None


def file_content(name: str, value: Any) -> Any:
    """A file option's document given in a JSON body: text (passed as UTF-8 bytes, so that no
    parser can take it for a path) or a parsed JSON object/array (passed as it is)."""
    if isinstance(value, str):
        return forms.file_value(name, name, value.encode("utf-8"))
    if isinstance(value, dict | list):
        return value
    raise ApiError(
        422, name, f"{name}: expected the file's content (text or JSON), got {type(value).__name__}"
    )


@router.post(
    "/api/select",
    tags=["mission"],
    summary="Run the mission selector (same answer as `uasnav select --json`)",
    openapi_extra={
        "requestBody": {"required": True, "content": {"application/json": {"schema": select_schema()}}},
        "responses": {"422": {"description": "A bad value; `field` names the option."}},
    },
)
async def api_select(request: Request, ctx: Ctx) -> Response:
    body = await json_body(request)
    if not isinstance(body, dict):
        raise ApiError(422, "body", "body: expected a JSON object of selector options")
    # a file option carries the document itself (text or JSON), never a path
    files: dict[str, Any] = {}
    for opt in select_request.SELECT_OPTIONS:
        if opt.name in body and forms.is_field(opt) and forms.widget(opt) == "file":
            files[opt.name] = file_content(opt.name, body.pop(opt.name))
    return JSONResponse(ctx.selection_json(body, files))


@router.get(
    "/api/options", tags=["mission"], summary="The selector's options (names, kinds, units, defaults)"
)
def api_options() -> Response:
    return JSONResponse(
        [
            {
                "name": o.name,
                "kind": o.kind,
                "default": to_jsonable(o.default),
                "unit": o.unit,
                "minimum": o.minimum,
                "maximum": o.maximum,
                "choices": list(o.choices) if o.choices else None,
                "label": o.label,
                "help": forms.operator_help(o),
            }
            for o in select_request.SELECT_OPTIONS
            if forms.is_field(o)
        ]
    )


@router.get(
    "/api/db/{name}",
    tags=["database"],
    summary="A database table: uas, cameras, regulations, missions, equipment",
)
def api_db(ctx: Ctx, name: str, q: str = "", sort: str = "", desc: bool = False) -> Response:
    cols, rows = tables.filter_sort(table_of(ctx.docs, name), q[:200], sort, desc)
    return JSONResponse(to_jsonable({"table": name, "columns": cols, "rows": rows}))


@router.post(
    "/api/trajectory/predict",
    tags=["trajectory"],
    summary="Predict element times, ETA and 4D waypoint times of an uploaded plan",
    openapi_extra={"requestBody": {"required": True, "content": {"multipart/form-data": PREDICT_SCHEMA}}},
)
async def api_predict(request: Request) -> Response:
    if not request.headers.get("content-type", "").startswith("multipart/form-data"):
        raise ApiError(415, "content-type", "content-type: expected multipart/form-data with a plan file")
    form = await read_form(request)
    fmt = form.get("format") or "json"
    if fmt not in ("json", "csv", "geojson"):
        raise ApiError(422, "format", f"format: {fmt!r} is not json, csv or geojson")
    try:
        r = await predict_from_form(form)
        if fmt == "csv":
            return PlainTextResponse(prediction.waypoints_csv(r), media_type="text/csv; charset=utf-8")
        if fmt == "geojson":
            return JSONResponse(
                to_jsonable(prediction.waypoints_geojson(r)), media_type="application/geo+json"
            )
    except prediction.FieldError as e:
        raise ApiError(422, e.field, str(e)) from None
    return JSONResponse(to_jsonable(r.to_dict()))
