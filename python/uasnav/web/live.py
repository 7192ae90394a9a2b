"""The ``/live`` page: a vehicle on live MAVLink telemetry, its intent's volumes, its F3548
conformance state and the causal GNSS/INS solution with its protection levels.

The stream is configured when the server starts, by environment variables (a web page never
chooses which port or device the server opens):

- ``UASNAV_LIVE_CONNECTION`` — a pymavlink connection string (``udpin:127.0.0.1:14550`` …);
- ``UASNAV_LIVE_INTENTS`` — operational intent JSON files, separated by ``os.pathsep``
  (vehicle 1 flies the first, 2 the second …).

One background thread receives the stream (from the first request of the page on) and feeds
the conformance monitor (:mod:`uasnav.live.conformance`) and the filter
(:mod:`uasnav.live.nav`). ``/live/events`` sends a snapshot as a server-sent event every
:data:`PERIOD_S` (10 Hz); ``/live/intents`` gives the volumes for the offline SVG map.
"""

from __future__ import annotations

import asyncio
import json
import os
import threading
import time
from collections import deque
from pathlib import Path
from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse, JSONResponse, StreamingResponse

#: Seconds between two snapshots sent to a page.
PERIOD_S = 0.1
CONNECTION_ENV = "UASNAV_LIVE_CONNECTION"
INTENTS_ENV = "UASNAV_LIVE_INTENTS"
_PAGE = Path(__file__).resolve().parent / "templates" / "live.html"

router = APIRouter()


class LiveHub:
    """The receiving thread and the latest snapshot (bounded: the last 50 events)."""

    def __init__(self, connection: str, intent_paths: list[str]) -> None:
        from uasnav.io.operational_intent import read_intents
        from uasnav.live.conformance import ConformanceMonitor

        self.connection = connection
        self.intents = [it for p in intent_paths for it in read_intents(p)]
        self.monitor = ConformanceMonitor(self.intents)
        self.lock = threading.Lock()
        self.vehicles: dict[int, dict[str, Any]] = {}
        self.events: deque[dict[str, Any]] = deque(maxlen=50)
        self.nav: dict[str, Any] | None = None
        self.messages = 0
        self.error: str | None = None
        self._thread: threading.Thread | None = None
        self._stop = [False]

    def start(self) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="uasnav-live", daemon=True)
            self._thread.start()

    def stop(self) -> None:
        self._stop[0] = True

    def _run(self) -> None:
        from uasnav.live.nav import LiveNav
        from uasnav.live.stream import open_connection, receive

        try:
            conn = open_connection(self.connection)
            nav = LiveNav()
        except Exception as e:  # shown on the page: the server itself keeps serving
            self.error = str(e)
            return
        last_flush = [0.0]

        def on_message(msg: Any, wall: float) -> None:
            evs = self.monitor.on_message(msg, wall)
            nav.on_message(msg)
            with self.lock:
                self.messages += 1
                self._note(evs)
                if msg.get_type() == "GLOBAL_POSITION_INT" and msg.get_srcSystem() in self.monitor.states():
                    v = self.vehicles.setdefault(msg.get_srcSystem(), {})
                    v.update(lat=msg.lat * 1e-7, lon=msg.lon * 1e-7, alt_amsl_m=msg.alt * 1e-3,
                             t_boot_s=msg.time_boot_ms * 1e-3)  # fmt: skip

        def on_tick(wall: float) -> None:
            evs = self.monitor.on_tick(wall)
            if wall - last_flush[0] >= PERIOD_S / 2:
                last_flush[0] = wall
                b = nav.flush()
                if len(b):
                    import numpy as np

                    with self.lock:
                        self.nav = {
                            "t_boot_s": float(b.t[-1]),
                            "lat": float(np.degrees(b.llh[-1, 0])),
                            "lon": float(np.degrees(b.llh[-1, 1])),
                            "alt_w84_m": float(b.llh[-1, 2]),
                            "hpl_m": float(b.protection[-1, 0]),
                            "vpl_m": float(b.protection[-1, 1]),
                        }
            if evs:
                with self.lock:
                    self._note(evs)

        try:
            receive(conn, on_message, on_tick, stop=self._stop)
        except Exception as e:  # a broken link ends the feed, not the server
            self.error = str(e)
        finally:
            conn.close()

    def _note(self, evs: list[dict[str, Any]]) -> None:
        for ev in evs:
            self.events.append(ev)
            v = self.vehicles.setdefault(ev["vehicle"], {})
            if ev["event"] == "state":
                v["state"] = ev["state"]
                v["margin_m"] = ev.get("margin_m")
                v["reason"] = ev["reason"]
            else:
                v["telemetry"] = ev["event"]

    def snapshot(self) -> dict[str, Any]:
        with self.lock:
            states = self.monitor.states()
            return {
                "time": time.time(),
                "messages": self.messages,
                "error": self.error,
                "vehicles": {str(k): {**self.vehicles.get(k, {}), "state": s} for k, s in states.items()},
                "nav": self.nav,
                "events": list(self.events)[-10:],
            }

    def volumes(self) -> dict[str, Any]:
        from uasnav.utm.volumes import _outline

        out = []
        for k, it in enumerate(self.intents):
            for i, v in enumerate(it.details.volumes):
                pts, r = _outline(v)
                out.append(
                    {
                        "intent": it.name,
                        "vehicle": k + 1,
                        "index": i,
                        "latlon": pts.tolist(),
                        "radius_m": None if r is None else float(r[0]),
                        "alt_w84_m": [v.volume.altitude_lower.value, v.volume.altitude_upper.value],
                    }
                )
        return {"volumes": out}


_hub: LiveHub | None = None
_hub_lock = threading.Lock()


def hub() -> LiveHub | None:
    """The hub of the configured stream (started on first use), or None when not configured."""
    global _hub
    conn = os.environ.get(CONNECTION_ENV, "").strip()
    paths = [p for p in os.environ.get(INTENTS_ENV, "").split(os.pathsep) if p.strip()]
    if not conn or not paths:
        return None
    with _hub_lock:
        if _hub is None:
            _hub = LiveHub(conn, paths)
            _hub.start()
        return _hub


@router.get("/live", include_in_schema=False)
def live_page() -> HTMLResponse:
    return HTMLResponse(_PAGE.read_text(encoding="utf-8"))


@router.get("/live/intents", include_in_schema=False)
def live_intents() -> JSONResponse:
    h = hub()
    if h is None:
        return JSONResponse(
            {"volumes": [], "error": f"no live stream configured ({CONNECTION_ENV}, {INTENTS_ENV})"}
        )
    return JSONResponse(h.volumes())


@router.get("/live/events", include_in_schema=False)
async def live_events(request: Request) -> StreamingResponse:
    async def stream() -> Any:
        while not await request.is_disconnected():
            h = hub()
            snap = (
                h.snapshot()
                if h is not None
                else {"error": f"no live stream configured: set {CONNECTION_ENV} and {INTENTS_ENV}"}
            )
            yield f"data: {json.dumps(snap, ensure_ascii=False)}\n\n"
            await asyncio.sleep(PERIOD_S)

    return StreamingResponse(stream(), media_type="text/event-stream", headers={"cache-control": "no-cache"})
