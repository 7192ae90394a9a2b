"""What every page and API route of the web application shares.

The application factory (:func:`uasnav.web.app.create_app`) builds one :class:`WebContext` and
stores it on ``app.state``; each router reads it through the :func:`web_context` dependency.
The selector itself reaches the routes through the context too (``run_select``,
``parse_select_options``), so the factory decides which functions serve a request.
"""

from __future__ import annotations

import base64
import dataclasses
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from fastapi import Request
from fastapi.responses import Response
from fastapi.templating import Jinja2Templates

from uasnav.errors import UasnavError
from uasnav.jsonable import to_jsonable
from uasnav.mission import request as select_request
from uasnav.mission.database import Database, load_database
from uasnav.mission.matrices import Matrices, load_matrices
from uasnav.mission.regulations import Regulations, load_regulations
from uasnav.mission.request import OptionError
from uasnav.web import forms

#: Largest request body (bytes): a plan and a model upload with room to spare.
MAX_BODY_BYTES = 16 * 2**20
#: Largest JSON body of ``POST /api/select`` (bytes).
MAX_JSON_BYTES = 256 * 2**10
#: Multipart limits: files, fields, bytes per non-file part (a document the page keeps from the
#: last run is a non-file part: base64 of at most an option file; the body limit bounds them all).
MAX_FILES, MAX_FIELDS = 4, 96
MAX_PART_BYTES = forms.MAX_OPTION_FILE_BYTES * 4 // 3 + 4096
GENERIC_500 = "internal server error: the details are in the server log"


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


@dataclass(frozen=True)
class WebContext:
    """The loaded documents, the templates and the selector the routes call."""

    docs: Documents
    templates: Jinja2Templates
    #: (value, label) choices the loaded documents offer for text options.
    choices: dict[str, tuple[tuple[str, str], ...]]
    run_select: Callable[..., Any]
    parse_select_options: Callable[[Mapping[str, Any]], Any]
    #: ``uasnav.plan``: the survey of an uploaded area, its flights, intents and files.
    run_plan: Callable[..., Any] | None = None

    def selection(self, values: Mapping[str, Any], files: Mapping[str, Any] | None = None) -> Any:
        """The selector on the server's documents; a bad value is an :class:`ApiError` 422
        naming the option.

        ``values`` come from the request and may not name a data source or a file; ``files``
        maps file options to the documents the request carried (bytes, an ``Upload`` or parsed
        JSON), never to a path.
        """
        for key in values:
            opt = next((o for o in select_request.SELECT_OPTIONS if o.name == key), None)
            if opt is not None and not forms.is_field(opt):
                what = (
                    "data sources are set when the server starts"
                    if opt.kind == "source"
                    else "server side only"
                )
                raise ApiError(422, key, f"{key}: {what}, not part of a request")
            if opt is not None and forms.widget(opt) == "file":
                raise ApiError(422, key, f"{key}: upload the file (form) or give its content (JSON body)")
        merged = {**values, **(files or {})}
        docs = self.docs
        mission = merged.get("mission")
        if isinstance(mission, str) and mission.strip() and mission.strip() not in docs.matrices.missions:
            known = ", ".join(docs.matrices.missions)
            raise ApiError(422, "mission", f"mission: unknown mission {mission!r}; known: {known}")
        jur = merged.get("jurisdiction")
        if isinstance(jur, str) and jur.strip() and jur.strip() not in docs.regulations.jurisdictions:
            known = ", ".join(docs.regulations.jurisdictions)
            raise ApiError(422, "jurisdiction", f"jurisdiction: unknown jurisdiction {jur!r}; known: {known}")
        try:
            return self.run_select(
                merged, database=docs.database, matrices=docs.matrices, regulations=docs.regulations
            )
        except OptionError as e:
            raise ApiError(422, e.option, str(e)) from None
        except UasnavError as e:
            raise ApiError(422, None, str(e)) from None

    def selection_json(
        self, values: Mapping[str, Any], files: Mapping[str, Any] | None = None
    ) -> dict[str, Any]:
        """:meth:`selection` as the JSON ``uasnav select --json`` prints."""
        return to_jsonable(self.selection(values, files).to_dict())


async def read_form(request: Request) -> Any:
    """The request's form (urlencoded or multipart) within the server's part limits."""
    return await request.form(max_files=MAX_FILES, max_fields=MAX_FIELDS, max_part_size=MAX_PART_BYTES)


def web_context(request: Request) -> WebContext:
    """FastAPI dependency: the application's :class:`WebContext`."""
    return request.app.state.web  # type: ignore[no-any-return]


def field_of(e: Exception) -> str | None:
    """The option or field an error names, if any."""
    return getattr(e, "option", None) or getattr(e, "field", None)


def data_uri(mime: str, text: str) -> str:
    """``text`` as a ``data:`` URI (downloads of what the page shows, no second request)."""
    return f"data:{mime};charset=utf-8;base64," + base64.b64encode(text.encode("utf-8")).decode("ascii")


def download(resp: Response, filename: str) -> Response:
    """``resp`` as an attachment named ``filename``."""
    resp.headers["content-disposition"] = f'attachment; filename="{filename}"'
    return resp


def choices_of(docs: Documents) -> dict[str, tuple[tuple[str, str], ...]]:
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


_OPTION_NAME = re.compile(r"--([a-z][a-z0-9-]*)")


def plain(text: Any) -> str:
    """``text`` with command-line option names (``--altitude``) replaced by the form's field
    labels ("Altitude"), for answers shared with the command line."""
    labels = {o.flag: o.label for o in select_request.SELECT_OPTIONS if o.label}

    def label(m: re.Match[str]) -> str:
        return f"“{labels[m.group(0)]}”" if m.group(0) in labels else m.group(0)

    return _OPTION_NAME.sub(label, str(text))


#: Where the pilot distance comes from when an area was uploaded and no distance typed.
AREA_DISTANCE_WORDS = select_request.AREA_DISTANCE_WORDS


def in_operator_words(selection: Any, typed: Mapping[str, Any]) -> Any:
    """``selection`` whose operation derivation (the authorisation summary's "from" column)
    names the form's fields instead of command-line options, and says when the pilot distance
    was measured on the uploaded area rather than typed. ``typed``: the values the operator
    entered. The API's answer keeps the selector's own wording."""
    op = getattr(selection, "operation", None)
    if op is None:
        return selection
    from_area = typed.get("max_distance") in (None, "") and selection.requirements.max_distance_m is not None

    def words(text: str) -> str:
        if from_area:
            text = text.replace("--max-distance", AREA_DISTANCE_WORDS)
        return plain(text)

    facts = tuple(dataclasses.replace(f, requirement=words(f.requirement)) for f in op.derivation)
    return dataclasses.replace(selection, operation=dataclasses.replace(op, derivation=facts))


def auto_num(x: Any) -> str:
    """A database value with the decimals it needs: whole numbers plain, small ones to 4
    significant digits."""
    if isinstance(x, bool) or not isinstance(x, int | float):
        return num(x)
    if float(x).is_integer():
        return num(x, 0)
    return num(x, 2) if abs(x) >= 1 else f"{x:.4g}"


def num(x: Any, digits: int = 2) -> str:
    """A number for a table cell: fixed decimals, thousands separated; '—' for none."""
    if x is None:
        return "—"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int | float):
        return f"{x:,.{digits}f}"
    return str(x)
