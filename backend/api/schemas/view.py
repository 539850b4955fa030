"""A page's own 3D view (``X-Nemesys-View``)."""

from __future__ import annotations

from pydantic import BaseModel, Field


class ViewCleared(BaseModel):
    """What a clear did to the caller's own 3D view."""

    view: str | None = Field(description="the view id the request named (null: none)")
    cleared: bool = Field(description="false: that view showed nothing of the kind")
