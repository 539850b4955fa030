"""``POST /api/predict``: the predicted track of a command (read-only, no token needed)."""

from __future__ import annotations

import math
import threading
import weakref
from typing import Annotated, Any

from fastapi import APIRouter, Query
from fastapi.responses import JSONResponse

from backend.api.deps import ConsoleDep
from backend.api.models import CommandIn
from backend.api.responses import DocResponse
from backend.api.schemas import errors
from backend.api.schemas.predict import Prediction
from backend.authoring.predict import MAX_HORIZON_S, Gate, PredictorBusy, predict
from backend.console import Console

router = APIRouter(prefix="/api", tags=["authoring"])

_GATES: weakref.WeakKeyDictionary[Console, Gate] = weakref.WeakKeyDictionary()
_GATES_LOCK = threading.Lock()


def _gate(console: Console) -> Gate:
    with _GATES_LOCK:
        gate = _GATES.get(console)
        if gate is None:
            gate = _GATES[console] = Gate()
        return gate


_RESPONSES = errors(
    (413, 422, 503),
    why={503: "a prediction is running and the queue is full; retry after Retry-After seconds"},
)
_RESPONSES[503]["headers"] = {
    "Retry-After": {
        "description": "seconds to wait before asking again",
        "schema": {"type": "integer"},
    }
}


@router.post(
    "/predict", response_class=DocResponse, response_model=Prediction, responses=_RESPONSES
)
def predict_track(
    body: CommandIn,
    console: ConsoleDep,
    horizon_s: Annotated[
        float, Query(gt=0, le=MAX_HORIZON_S, description="simulated seconds to cover at most")
    ] = MAX_HORIZON_S,
) -> JSONResponse:
    """Run the twin from the vehicle's state now with the command's frame (through the onboard
    decode), faster than real time, over ``horizon_s`` (or until a finite pattern completes
    and settles): the track it flies against the planned path. One prediction at a time; 503
    with Retry-After when a few are already waiting."""
    try:
        with _gate(console).slot():
            doc: dict[str, Any] = predict(console, body.pattern, dict(body.params), horizon_s)
    except PredictorBusy as err:
        return JSONResponse(
            {"detail": str(err)},
            status_code=503,
            headers={"Retry-After": str(math.ceil(err.retry_after_s))},
        )
    prediction = Prediction.model_validate(doc)
    if console.foxglove is not None:  # the live Foxglove view shows the latest asked for
        console.foxglove.prediction(
            prediction.x_m, prediction.y_m, prediction.z_m, f"prediction: {body.pattern}"
        )
    return DocResponse(prediction)
