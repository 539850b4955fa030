"""The mission log as CSV: the record's own columns, then the acknowledgement's figures."""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from typing import Any

#: CSV columns taken from the acknowledgement (the rest are the record's own).
CSV_ACK_COLUMNS = ("corrected_bits", "decode_latency_ms", "replan_latency_ms")
#: The CSV export's columns, in order.
CSV_COLUMNS = (
    "id",
    "dive",
    "created_at",
    "operator",
    "target",
    "kind",
    "pattern",
    "params",
    "hex",
    "bits",
    "state",
    "attempts",
    "sent_at",
    "acked_at",
    "reason",
    "copies",
    "copies_sent",
    "p_delivered",
    "superseded_by",
    *CSV_ACK_COLUMNS,
)


def csv_columns(fleet: bool = False) -> tuple[str, ...]:
    """The CSV export's columns: :data:`CSV_COLUMNS`, and with a fleet the ``vehicle`` each
    record is for, after ``target``."""
    if not fleet:
        return CSV_COLUMNS
    at = CSV_COLUMNS.index("target") + 1
    return (*CSV_COLUMNS[:at], "vehicle", *CSV_COLUMNS[at:])


def csv_rows(records: Iterable[Mapping[str, Any]], *, fleet: bool = False) -> Iterable[list[str]]:
    """The log as CSV rows (header first, :func:`csv_columns`); JSON columns as JSON text."""
    columns = csv_columns(fleet)
    yield list(columns)
    for r in records:
        ack = r.get("ack") or {}
        values = (ack.get(c) if c in CSV_ACK_COLUMNS else r.get(c) for c in columns)
        yield [
            json.dumps(v) if isinstance(v, dict | list) else "" if v is None else str(v)
            for v in values
        ]
