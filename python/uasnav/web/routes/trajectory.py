"""The trajectory page: upload a plan, get element times, the ETA and 4D waypoint times."""

from __future__ import annotations

import base64
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Request
from fastapi.responses import HTMLResponse, Response
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile

from uasnav.errors import UasnavError
from uasnav.web import prediction
from uasnav.web.context import MAX_BODY_BYTES, WebContext, read_form, web_context

router = APIRouter(include_in_schema=False)
Ctx = Annotated[WebContext, Depends(web_context)]


def traj_page(
    request: Request,
    ctx: WebContext,
    values: dict[str, Any],
    errors: dict[str, str],
    result: Any,
    status: int,
) -> Response:
    page: dict[str, Any] = {
        "request": request,
        "values": values,
        "errors": errors,
        "page": "trajectory",
        "result": None,
    }
    if result is not None:
        csv_text = prediction.waypoints_csv(result)
        page["result"] = result
        # a mission's times are the autopilot's, in its items table: the drawing names the waypoints
        page["drawing"] = prediction.route_drawing(result, with_times=result.autopilot is None)
        page["csv_href"] = "data:text/csv;base64," + base64.b64encode(csv_text.encode()).decode()
        if result.autopilot is not None:
            items = prediction.mission_items_csv(result.autopilot)
            page["items_href"] = "data:text/csv;base64," + base64.b64encode(items.encode()).decode()
        if result.origin is not None:
            gj = prediction.to_json_text(prediction.waypoints_geojson(result))
            page["geojson_href"] = (
                "data:application/geo+json;base64," + base64.b64encode(gj.encode()).decode()
            )
    page["suffixes"] = ", ".join(prediction.PLAN_SUFFIXES)
    page["autopilots"] = prediction.AUTOPILOT_LABELS
    page["max_upload"] = MAX_BODY_BYTES
    return ctx.templates.TemplateResponse(request, "trajectory.html", page, status_code=status)


async def predict_from_form(form: Any) -> prediction.RoutePrediction:
    """The prediction a trajectory form (page or API) asks for; a bad value is a
    :class:`~uasnav.web.prediction.FieldError` naming the field."""
    plan = form.get("plan")
    if not isinstance(plan, UploadFile) or not plan.filename:
        raise prediction.FieldError("plan", "plan: choose a plan file")
    data = await plan.read(prediction.MAX_UPLOAD_PLAN_BYTES + 1)
    wind = prediction.parse_number("wind_speed", form.get("wind_speed") or "0", 0.0, prediction.MAX_WIND_MS)
    wdir = prediction.parse_number("wind_from", form.get("wind_from") or "0", -360.0, 360.0)
    speed_text = form.get("speed") or ""
    speed = (
        prediction.parse_number("speed", speed_text, 0.0, prediction.MAX_SPEED_MS, lo_open=True)
        if str(speed_text).strip()
        else None
    )
    tolerance = prediction.parse_number("tolerance", form.get("tolerance") or "5", 0.0, 3600.0)
    autopilot = str(form.get("autopilot") or "").strip() or None
    if autopilot is not None and autopilot not in prediction.AUTOPILOTS:
        raise prediction.FieldError(
            "autopilot", f"autopilot: {autopilot!r} is not one of {', '.join(prediction.AUTOPILOTS)}"
        )
    up_plan = prediction.read_uploaded_plan(plan.filename, data)
    # an autopilot mission file: the mission as the autopilot flies it (`trajectory mission`)
    flown = (
        await run_in_threadpool(prediction.predict_autopilot, up_plan.mission, autopilot)
        if up_plan.mission is not None
        else None
    )
    required_text = str(form.get("required") or "")
    required = (
        prediction.parse_required(required_text, up_plan.route_ne.shape[0]) if required_text.strip() else None
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
    elif speed is None and flown is not None:
        speed, name = flown.cruise_ms, f"{name}; speed the autopilot's {flown.cruise_param}"
    try:
        result = await run_in_threadpool(
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
    result.autopilot = flown
    return result


@router.get("/trajectory", response_class=HTMLResponse)
def trajectory_form(request: Request, ctx: Ctx) -> Response:
    return traj_page(request, ctx, {}, {}, None, 200)


@router.post("/trajectory", response_class=HTMLResponse)
async def trajectory_post(request: Request, ctx: Ctx) -> Response:
    form = await read_form(request)
    values = {k: v for k, v in form.items() if isinstance(v, str)}
    try:
        result = await predict_from_form(form)
    except prediction.FieldError as e:
        return traj_page(request, ctx, values, {e.field: str(e)}, None, 422)
    return traj_page(request, ctx, values, {}, result, 200)
