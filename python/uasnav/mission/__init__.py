"""Mission selector (thesis §5.2): compliance matrices, UAS/camera database, regulations,
feasibility tests and scoring; the operation the requirements describe and its category
(:mod:`~uasnav.mission.operation`), SORA 2.5/2.0 (:mod:`~uasnav.mission.sora`), ED-269
geographical zones (:mod:`~uasnav.mission.zones`) and the authorisation summary
(:mod:`~uasnav.mission.summary`).

>>> from uasnav.mission import Requirements, select
>>> sel = select(Requirements())          # the thesis' precision-agriculture case
>>> sel.ranking[0].score >= 0
True
"""

from uasnav.mission.database import CameraTable, Database, UasTable, load_database
from uasnav.mission.feasibility import (
    Rejection,
    Requirements,
    ground_resolution_m,
    mission_time_s,
    required_hfov_deg,
)
from uasnav.mission.loading import fetch, load_document, parse_bytes, validate
from uasnav.mission.matrices import Matrices, load_matrices
from uasnav.mission.operation import Fact, Operation, ScenarioCheck, derive_operation
from uasnav.mission.regulations import Regulations, load_regulations
from uasnav.mission.request import (
    SELECT_OPTIONS,
    OptionError,
    SelectRequest,
    parse_select_options,
    run_select,
)
from uasnav.mission.scoring import Targets, Weights, rank, score_matrix, transfer
from uasnav.mission.selection import RankedPair, Selection, select
from uasnav.mission.sora import SoraResult, assess

__all__ = [
    "SELECT_OPTIONS",
    "CameraTable",
    "Database",
    "Fact",
    "Matrices",
    "Operation",
    "OptionError",
    "RankedPair",
    "Regulations",
    "Rejection",
    "Requirements",
    "ScenarioCheck",
    "SelectRequest",
    "Selection",
    "SoraResult",
    "Targets",
    "UasTable",
    "Weights",
    "assess",
    "derive_operation",
    "fetch",
    "ground_resolution_m",
    "load_database",
    "load_document",
    "load_matrices",
    "load_regulations",
    "mission_time_s",
    "parse_bytes",
    "parse_select_options",
    "rank",
    "required_hfov_deg",
    "run_select",
    "score_matrix",
    "select",
    "transfer",
    "validate",
]
