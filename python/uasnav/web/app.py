"""The web application of ``uasnav serve``: mission selection and trajectory prediction.

One FastAPI application serves the HTML pages (Jinja2 templates, one stylesheet and one small
script of this package: nothing from a CDN), the JSON API (``/api/…``) and its OpenAPI
description (``/openapi.json``, rendered as a page at ``/api`` by the app itself). Pages and API
call the same functions: :func:`uasnav.mission.request.run_select` on the documents loaded when
the server started, and :mod:`uasnav.web.prediction`.

Every page works without JavaScript: forms post, tables filter and sort through query
parameters, downloads are links. Errors: a bad value is a 4xx naming the field (on a page, the
message beside the field); anything unexpected is a 500 with a generic message, the details only
in the server log.
"""

from __future__ import annotations

import base64
import json
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, PlainTextResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles
from fastapi.templating import Jinja2Templates
from markupsafe import Markup
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile

from uasnav import __version__
from uasnav.errors import DataFormatError, UasnavError
from uasnav.jsonable import to_jsonable
from uasnav.mission import request as select_request
from uasnav.mission import summary
from uasnav.mission.database import Database, load_database
from uasnav.mission.matrices import NECESSARY, Matrices, load_matrices
from uasnav.mission.regulations import Regulations, load_regulations
from uasnav.mission.request import OPTION_GROUPS, OptionError, parse_select_options, run_select
from uasnav.mission.scoring import PARAMETERS
from uasnav.web import forms, prediction, selection_view, tables
from uasnav.web.security import BodyTooLarge, GuardMiddleware

log = logging.getLogger("uasnav.web")
HERE = Path(__file__).parent

#: Largest request body (bytes): a plan and a model upload with room to spare.
MAX_BODY_BYTES = 16 * 2**20
#: Largest JSON body of ``POST /api/select`` (bytes).
MAX_JSON_BYTES = 256 * 2**10
#: Multipart limits: files, fields, bytes per non-file part.
MAX_FILES, MAX_FIELDS, MAX_PART_BYTES = 4, 64, 64 * 2**10
GENERIC_500 = "internal server error: the details are in the server log"
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


@dataclass
class Documents:
    """The documents the server loaded once at start (never named by a request)."""

    database: Database
    matrices: Matrices
    regulations: Regulations
    sources: dict[str, str] = field(default_factory=dict)


def load_documents(
    db: str | None = None, matrices: str | None = None, regulations: str | None = None
) -> Documents:
    """Load (and validate) the three documents: paths, URLs, or the shipped copies."""
    d = load_database(db)
    m = load_matrices(matrices)
    r = load_regulations(regulations)
    return Documents(
        d, m, r, {"database": d.where, "matrices": m.source or "shipped", "regulations": r.where}
    )


class ApiError(Exception):
    """A 4xx answer naming the field (or header) at fault."""

    def __init__(self, status: int, field: str | None, message: str) -> None:
        super().__init__(message)
        self.status, self.field, self.message = status, field, message


def _field_of(e: Exception) -> str | None:
    return getattr(e, "option", None) or getattr(e, "field", None)


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
    templates.env.filters["num"] = _num
    templates.env.filters["auto"] = _auto
    app.mount("/static", StaticFiles(directory=str(HERE / "static")), name="static")
    from uasnav.web.live import router as live_router  # the /live page (live MAVLink telemetry)

    app.include_router(live_router)

    @app.get("/summary.css", include_in_schema=False)
    def summary_css() -> Response:
        # the authorisation summary's own stylesheet, so the printed page is that document
        return Response(summary.SUMMARY_CSS, media_type="text/css", headers={"cache-control": "no-cache"})

    app.state.docs = docs

    choices = _choices(docs)

    # -- errors ------------------------------------------------------------------------------
    def error_json(status: int, field: str | None, message: str) -> JSONResponse:
        return JSONResponse({"error": message, "field": field}, status_code=status)

    @app.exception_handler(ApiError)
    async def _api_error(request: Request, e: ApiError) -> Response:
        return error_json(e.status, e.field, e.message)

    @app.exception_handler(RequestValidationError)
    async def _validation(request: Request, e: RequestValidationError) -> Response:
        err = e.errors()[0] if e.errors() else {}
        loc = [str(x) for x in err.get("loc", ()) if x not in ("body", "query", "path")]
        name = loc[-1] if loc else None
        return error_json(422, name, f"{name}: {err.get('msg', 'invalid value')}")

    @app.exception_handler(BodyTooLarge)
    async def _too_large(request: Request, e: BodyTooLarge) -> Response:
        return error_json(413, "body", str(e))

    @app.exception_handler(Exception)
    async def _internal(request: Request, e: Exception) -> Response:
        log.exception("unexpected error on %s %s", request.method, request.url.path)
        if request.url.path.startswith("/api"):
            return error_json(500, None, GENERIC_500)
        return HTMLResponse(
            templates.get_template("error.html").render(request=request, message=GENERIC_500), status_code=500
        )

    # -- mission selection ---------------------------------------------------------------------
    def selection_page(
        request: Request,
        values: dict[str, Any],
        errors: dict[str, str],
        result: dict[str, Any] | None,
        status: int,
    ) -> HTMLResponse:
        ctx = {
            "request": request,
            "groups": _grouped(forms.form_fields(choices)),
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
        return templates.TemplateResponse(request, "select.html", ctx, status_code=status)

    def run_view(values: dict[str, Any], files: dict[str, Any]) -> dict[str, Any]:
        selection = _selection(values, docs, files)
        sel = to_jsonable(selection.to_dict())
        req = parse_select_options({**values, **files})
        equipment: dict[str, list[dict[str, Any]]] = {}
        for e in sel["equipment"]:
            equipment.setdefault(e["group"], []).append(e)
        # downloads of exactly what is shown (no second run, uploaded files included)
        downloads = {
            "json": _data_uri("application/json", json.dumps(sel, ensure_ascii=False, indent=2)),
            "ranking": _data_uri("text/csv", selection_view.ranking_csv(sel)),
            "rejections": _data_uri("text/csv", selection_view.rejections_csv(sel)),
        }
        # the authorisation summary is the page's print view: one document, one renderer
        downloads["summary_html"] = _data_uri("text/html", summary.summary_html(selection))
        downloads["summary_json"] = _data_uri(
            "application/json", json.dumps(summary.summary_dict(selection), ensure_ascii=False, indent=2)
        )
        onboard = {x["id"]: x["state"] for x in sel["chosen_equipment"] or []}
        return {
            "sel": sel,
            "summary": Markup(summary.summary_fragment(selection)),
            "onboard": onboard,
            "equipment": equipment,
            "plots": selection_view.transfer_plots(sel, req.targets, docs.database),
            "breakdown": selection_view.breakdown(sel),
            "downloads": downloads,
            "margin": selection_view.margin,
            "necessary": NECESSARY,
        }

    @app.get("/", response_class=HTMLResponse, include_in_schema=False)
    def index(request: Request) -> Response:
        return selection_page(request, {}, {}, None, 200)

    @app.post("/select", response_class=HTMLResponse, include_in_schema=False)
    async def select_form(request: Request) -> Response:
        form = await request.form(max_files=MAX_FILES, max_fields=MAX_FIELDS, max_part_size=MAX_PART_BYTES)
        values = forms.values_from_form(form, form.getlist)
        errors = forms.field_errors(values)
        result = None
        files: dict[str, Any] = {}
        for opt in forms.form_fields(choices):
            up = form.get(opt.name)
            if opt.widget == "file" and isinstance(up, UploadFile) and up.filename:
                data = await up.read(forms.MAX_OPTION_FILE_BYTES + 1)
                try:
                    files[opt.name] = forms.file_value(opt.name, up.filename, data)
                except OptionError as e:
                    errors[e.option] = str(e)
        if not errors:
            try:
                result = run_view(values, files)
            except (OptionError, ApiError) as e:
                errors[_field_of(e) or "form"] = getattr(e, "message", str(e))
            except UasnavError as e:
                errors["form"] = str(e)
        return selection_page(request, values, errors, result, 422 if errors else 200)

    @app.get("/select/export.{fmt}", include_in_schema=False)
    def select_export(request: Request, fmt: str, table: str = "ranking") -> Response:
        values = dict(request.query_params)
        values.pop("table", None)
        if fmt not in ("json", "csv"):
            raise ApiError(404, "format", f"format: {fmt!r} is not json or csv")
        sel = _run_select(values, docs)
        if fmt == "json":
            return _download(JSONResponse(sel), "selection.json")
        if table not in ("ranking", "rejections"):
            raise ApiError(422, "table", f"table: {table!r} is not ranking or rejections")
        text = selection_view.ranking_csv(sel) if table == "ranking" else selection_view.rejections_csv(sel)
        return _download(PlainTextResponse(text, media_type="text/csv; charset=utf-8"), f"{table}.csv")

    # -- database pages ---------------------------------------------------------------------------
    def table_of(name: str) -> tables.Table:
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

    @app.get("/db", include_in_schema=False)
    def db_index() -> Response:
        return RedirectResponse("/db/uas", status_code=303)

    @app.get("/db/{name}", response_class=HTMLResponse, include_in_schema=False)
    def db_page(request: Request, name: str, q: str = "", sort: str = "", desc: bool = False) -> Response:
        cols, rows = tables.filter_sort(table_of(name), q[:200], sort, desc)
        ctx = {
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
        return templates.TemplateResponse(request, "db.html", ctx)

    # -- trajectory ---------------------------------------------------------------------------
    def traj_page(
        request: Request, values: dict[str, Any], errors: dict[str, str], result: Any, status: int
    ) -> Response:
        ctx = {"request": request, "values": values, "errors": errors, "page": "trajectory", "result": None}
        if result is not None:
            csv_text = prediction.waypoints_csv(result)
            ctx["result"] = result
            ctx["drawing"] = prediction.route_drawing(result)
            ctx["csv_href"] = "data:text/csv;base64," + base64.b64encode(csv_text.encode()).decode()
            if result.origin is not None:
                gj = prediction.to_json_text(prediction.waypoints_geojson(result))
                ctx["geojson_href"] = (
                    "data:application/geo+json;base64," + base64.b64encode(gj.encode()).decode()
                )
        ctx["suffixes"] = ", ".join(prediction.PLAN_SUFFIXES)
        return templates.TemplateResponse(request, "trajectory.html", ctx, status_code=status)

    async def predict_from_form(form: Any) -> prediction.RoutePrediction:
        plan = form.get("plan")
        if not isinstance(plan, UploadFile) or not plan.filename:
            raise prediction.FieldError("plan", "plan: choose a plan file")
        data = await plan.read(prediction.MAX_UPLOAD_PLAN_BYTES + 1)
        wind = prediction.parse_number(
            "wind_speed", form.get("wind_speed") or "0", 0.0, prediction.MAX_WIND_MS
        )
        wdir = prediction.parse_number("wind_from", form.get("wind_from") or "0", -360.0, 360.0)
        speed_text = form.get("speed") or ""
        speed = (
            prediction.parse_number("speed", speed_text, 0.0, prediction.MAX_SPEED_MS, lo_open=True)
            if str(speed_text).strip()
            else None
        )
        tolerance = prediction.parse_number("tolerance", form.get("tolerance") or "5", 0.0, 3600.0)
        up_plan = prediction.read_uploaded_plan(plan.filename, data)
        required_text = str(form.get("required") or "")
        required = (
            prediction.parse_required(required_text, up_plan.route_ne.shape[0])
            if required_text.strip()
            else None
        )
        up = form.get("model")
        if isinstance(up, UploadFile) and up.filename:
            model = prediction.read_uploaded_model(await up.read(prediction.MAX_UPLOAD_MODEL_BYTES + 1))
            name = "uploaded model"
        else:
            from uasnav.web.default_model import default_model

            # trained on first use (seconds): off the event loop, so other requests go on
            model, name = await run_in_threadpool(default_model), "built-in model (simulated flights)"
        if speed is None and up_plan.cruise_ms is not None:
            speed, name = up_plan.cruise_ms, f"{name}; speed from the plan"
        try:
            return await run_in_threadpool(
                prediction.predict_plan,
                model,
                up_plan.route_ne,
                up_plan.origin,
                wind,
                wdir,
                speed,
                name,
                required,
                tolerance,
            )
        except UasnavError as e:
            raise prediction.FieldError("plan", f"plan: {e}") from None

    @app.get("/trajectory", response_class=HTMLResponse, include_in_schema=False)
    def trajectory_form(request: Request) -> Response:
        return traj_page(request, {}, {}, None, 200)

    @app.post("/trajectory", response_class=HTMLResponse, include_in_schema=False)
    async def trajectory_post(request: Request) -> Response:
        form = await request.form(max_files=MAX_FILES, max_fields=MAX_FIELDS, max_part_size=MAX_PART_BYTES)
        values = {k: v for k, v in form.items() if isinstance(v, str)}
        try:
            result = await predict_from_form(form)
        except prediction.FieldError as e:
            return traj_page(request, values, {e.field: str(e)}, None, 422)
        return traj_page(request, values, {}, result, 200)

    # -- JSON API -----------------------------------------------------------------------------------
    @app.post(
        "/api/select",
        tags=["mission"],
        summary="Run the mission selector (same answer as `uasnav select --json`)",
        openapi_extra={
            "requestBody": {"required": True, "content": {"application/json": {"schema": select_schema()}}},
            "responses": {"422": {"description": "A bad value; `field` names the option."}},
        },
    )
    async def api_select(request: Request) -> Response:
        body = await _json_body(request)
        if not isinstance(body, dict):
            raise ApiError(422, "body", "body: expected a JSON object of selector options")
        # a file option carries the document itself (text or JSON), never a path
        files: dict[str, Any] = {}
        for opt in select_request.SELECT_OPTIONS:
            if opt.name in body and forms.is_field(opt) and forms.widget(opt) == "file":
                files[opt.name] = _file_content(opt.name, body.pop(opt.name))
        return JSONResponse(_run_select(body, docs, files))

    @app.get(
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
                    "help": o.help,
                }
                for o in select_request.SELECT_OPTIONS
                if forms.is_field(o)
            ]
        )

    @app.get(
        "/api/db/{name}",
        tags=["database"],
        summary="A database table: uas, cameras, regulations, missions, equipment",
    )
    def api_db(name: str, q: str = "", sort: str = "", desc: bool = False) -> Response:
        cols, rows = tables.filter_sort(table_of(name), q[:200], sort, desc)
        return JSONResponse(to_jsonable({"table": name, "columns": cols, "rows": rows}))

    @app.post(
        "/api/trajectory/predict",
        tags=["trajectory"],
        summary="Predict element times, ETA and 4D waypoint times of an uploaded plan",
        openapi_extra={"requestBody": {"required": True, "content": {"multipart/form-data": PREDICT_SCHEMA}}},
    )
    async def api_predict(request: Request) -> Response:
        if not request.headers.get("content-type", "").startswith("multipart/form-data"):
            raise ApiError(415, "content-type", "content-type: expected multipart/form-data with a plan file")
        form = await request.form(max_files=MAX_FILES, max_fields=MAX_FIELDS, max_part_size=MAX_PART_BYTES)
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

    @app.get("/api", response_class=HTMLResponse, include_in_schema=False)
    def api_docs(request: Request) -> Response:
        return templates.TemplateResponse(
            request, "api.html", {"request": request, "spec": app.openapi(), "page": "api"}
        )

    return GuardMiddleware(app, allowed_hosts, MAX_BODY_BYTES, _SECURITY_HEADERS)


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
    for o in select_request.SELECT_OPTIONS:
        if not forms.is_field(o):
            continue
        s: dict[str, Any] = {"description": o.help + (f" Unit: {o.unit}." if o.unit else "")}
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


async def _json_body(request: Request) -> Any:
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


def _file_content(name: str, value: Any) -> Any:
    """A file option's document given in a JSON body: text (passed as UTF-8 bytes, so that no
    parser can take it for a path) or a parsed JSON object/array (passed as it is)."""
    if isinstance(value, str):
        return forms.file_value(name, name, value.encode("utf-8"))
    if isinstance(value, dict | list):
        return value
    raise ApiError(
        422, name, f"{name}: expected the file's content (text or JSON), got {type(value).__name__}"
    )


def _data_uri(mime: str, text: str) -> str:
    return f"data:{mime};charset=utf-8;base64," + base64.b64encode(text.encode("utf-8")).decode("ascii")


def _run_select(
    values: dict[str, Any], docs: Documents, files: dict[str, Any] | None = None
) -> dict[str, Any]:
    """``run_select`` on the server's documents, as the JSON ``uasnav select --json`` prints
    (:func:`_selection`)."""
    return to_jsonable(_selection(values, docs, files).to_dict())


def _selection(values: dict[str, Any], docs: Documents, files: dict[str, Any] | None = None) -> Any:
    """``run_select`` on the server's documents; a bad value is an :class:`ApiError` 422
    naming the option.

    ``values`` come from the request and may not name a data source or a file; ``files`` maps
    file options to the documents the request carried (bytes, an ``Upload`` or parsed JSON),
    never to a path.
    """
    for key in values:
        opt = next((o for o in select_request.SELECT_OPTIONS if o.name == key), None)
        if opt is not None and not forms.is_field(opt):
            what = (
                "data sources are set when the server starts" if opt.kind == "source" else "server side only"
            )
            raise ApiError(422, key, f"{key}: {what}, not part of a request")
        if opt is not None and forms.widget(opt) == "file":
            raise ApiError(422, key, f"{key}: upload the file (form) or give its content (JSON body)")
    values = {**values, **(files or {})}
    mission = values.get("mission")
    if isinstance(mission, str) and mission.strip() and mission.strip() not in docs.matrices.missions:
        known = ", ".join(docs.matrices.missions)
        raise ApiError(422, "mission", f"mission: unknown mission {mission!r}; known: {known}")
    jur = values.get("jurisdiction")
    if isinstance(jur, str) and jur.strip() and jur.strip() not in docs.regulations.jurisdictions:
        known = ", ".join(docs.regulations.jurisdictions)
        raise ApiError(422, "jurisdiction", f"jurisdiction: unknown jurisdiction {jur!r}; known: {known}")
    try:
        sel = run_select(values, database=docs.database, matrices=docs.matrices, regulations=docs.regulations)
    except OptionError as e:
        raise ApiError(422, e.option, str(e)) from None
    except UasnavError as e:
        raise ApiError(422, None, str(e)) from None
    return sel


def _download(resp: Response, filename: str) -> Response:
    resp.headers["content-disposition"] = f'attachment; filename="{filename}"'
    return resp


def _choices(docs: Documents) -> dict[str, tuple[tuple[str, str], ...]]:
    """Choices the loaded documents offer for text options."""
    types = sorted(set(docs.database.cameras.types))
    cats: dict[str, str] = {"": "default"}
    for jid, j in docs.regulations.jurisdictions.items():
        for cid in j.categories:
            cats.setdefault(cid, f"{cid} ({jid})")
    return {
        "mission": tuple((mid, f"{m.name}") for mid, m in docs.matrices.missions.items()),
        "imagery": (("any", "any"), *((t, t) for t in types)),
        "jurisdiction": tuple(
            (jid, j.name.split(",")[0]) for jid, j in docs.regulations.jurisdictions.items()
        ),
        "category": tuple(cats.items()),
    }


def _grouped(fields: list[forms.FormField]) -> list[tuple[str, list[forms.FormField]]]:
    """The fields under their option's group, in the groups' order (an option with no group
    would fall under "Requirements": nothing is ever dropped)."""
    out: dict[str, list[forms.FormField]] = {g: [] for g in OPTION_GROUPS}
    for f in fields:
        out[f.option.group if f.option.group in out else "requirements"].append(f)
    return [(OPTION_GROUPS[g], fs) for g, fs in out.items() if fs]


def _auto(x: Any) -> str:
    """A database value with the decimals it needs: whole numbers plain, small ones to 4
    significant digits."""
    if isinstance(x, bool) or not isinstance(x, int | float):
        return _num(x)
    if float(x).is_integer():
        return _num(x, 0)
    return _num(x, 2) if abs(x) >= 1 else f"{x:.4g}"


def _num(x: Any, digits: int = 2) -> str:
    """A number for a table cell: fixed decimals, thousands separated; '—' for none."""
    if x is None:
        return "—"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int | float):
        return f"{x:,.{digits}f}"
    return str(x)


__all__ = ["Documents", "create_app", "load_documents", "select_schema"]
