"""Response models: what every endpoint returns, as the OpenAPI (``/openapi.json``) shows it.

They mirror the handlers' output exactly (a field missing here would be dropped from the
response): ``common`` (parameters, a command, limit violations, check lines), ``errors``
(error bodies and each route's ``responses``), ``records`` (the mission log, dives, the vehicle),
``authoring``, ``chart``, ``training`` and ``scripts``. Shapes the vehicle sends (its status, its
acknowledgements) stay open: fields outside the contract are kept.
"""

from backend.api.schemas.authoring import (
    AddressedDecodeResult,
    DecodeResult,
    EncodeDoc,
    PatternDoc,
    PreviewDoc,
    Session,
)
from backend.api.schemas.chart import ChartDoc, DatumIn, LinkReach
from backend.api.schemas.common import (
    CheckLineDoc,
    CommandJson,
    LimitViolation,
    Params,
    ParamValue,
)
from backend.api.schemas.errors import (
    OPERATOR,
    DecodeFailure,
    ErrorDetail,
    LimitViolationError,
    ValidationErrorResponse,
    errors,
)
from backend.api.schemas.records import (
    Ack,
    CommandRecord,
    DiveDetail,
    DiveSummary,
    ReplayResult,
    VehicleView,
)
from backend.api.schemas.scripts import OnboardScript, RunState
from backend.api.schemas.training import (
    ChannelSettings,
    CurrentSettings,
    NewDive,
    ScenarioLoaded,
    TimeScale,
    TrainingOff,
    TrainingOn,
)

__all__ = [
    "OPERATOR",
    "Ack",
    "AddressedDecodeResult",
    "ChannelSettings",
    "ChartDoc",
    "CheckLineDoc",
    "CommandJson",
    "CommandRecord",
    "CurrentSettings",
    "DatumIn",
    "DecodeFailure",
    "DecodeResult",
    "DiveDetail",
    "DiveSummary",
    "EncodeDoc",
    "ErrorDetail",
    "LimitViolation",
    "LimitViolationError",
    "LinkReach",
    "NewDive",
    "OnboardScript",
    "ParamValue",
    "Params",
    "PatternDoc",
    "PreviewDoc",
    "ReplayResult",
    "RunState",
    "ScenarioLoaded",
    "Session",
    "TimeScale",
    "TrainingOff",
    "TrainingOn",
    "ValidationErrorResponse",
    "VehicleView",
    "errors",
]
