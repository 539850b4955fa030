"""Decluttering of the 3D view's labels: no two labels closer than :data:`MIN_LABEL_SEPARATION_M`.

viser draws a label as screen-sized text at an anchor in the scene; labels whose anchors lie
a few metres apart overlap until unreadable at the view's usual distance (~25 m). A page's
labels (its preview, script preview and replay) are therefore placed by :func:`declutter`:

* in priority order (the order given); a label within the separation of one already placed
  is *merged* into it (its text appended, ``" · "``, at most :data:`MAX_MERGED` texts, then
  ``"+k more"``);
* a label within the separation of a *reserved* anchor (the shared scene's labels: the
  compass, the depth scale, the active path's label, the vehicle's label where the vehicle is
  when drawn) is lifted above its anchor by the separation (at most :data:`MAX_LIFTS` times)
  when ``lift`` allows, else dropped: the shared label already says it (e.g. a preview's start
  is where the vehicle is);
* at most :data:`MAX_VIEW_LABELS` labels are placed; the rest are dropped.

Distances are in the view frame (metres).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import Final

import numpy as np
import numpy.typing as npt

#: No two labels of a drawn scene are closer than this (m, between anchors).
MIN_LABEL_SEPARATION_M: Final = 3.0
#: At most this many labels per page (its preview, script preview and replay together).
MAX_VIEW_LABELS: Final = 12
#: A merged label shows at most this many texts (then "+k more").
MAX_MERGED: Final = 3
#: A label near a reserved anchor is lifted at most this many separations up, else dropped.
MAX_LIFTS: Final = 2


@dataclass(frozen=True)
class LabelSpec:
    """A label to place: scene node ``name``, ``text``, anchor ``position`` (view frame, m)."""

    name: str
    text: str
    position: tuple[float, float, float]
    #: near a reserved anchor: lift it above (True) or drop it (False)
    lift: bool = True
    #: texts merged into this one (placed labels only)
    merged: tuple[str, ...] = field(default=())

    @staticmethod
    def at(name: str, text: str, position: npt.ArrayLike, *, lift: bool = True) -> LabelSpec:
        p = np.asarray(position, dtype=np.float64).reshape(3)
        return LabelSpec(name, text, (float(p[0]), float(p[1]), float(p[2])), lift)

    @property
    def shown(self) -> str:
        """The text drawn: the label's own and the merged ones."""
        texts = (self.text, *self.merged)
        if len(texts) <= MAX_MERGED:
            return " · ".join(texts)
        return " · ".join(texts[:MAX_MERGED]) + f" +{len(texts) - MAX_MERGED} more"


def _near(p: npt.NDArray[np.float64], anchors: npt.NDArray[np.float64], sep_m: float) -> int:
    """Index of the first anchor closer than ``sep_m`` to ``p``, or -1."""
    if len(anchors) == 0:
        return -1
    d = np.linalg.norm(anchors - p, axis=1)
    hits = np.flatnonzero(d < sep_m)
    return int(hits[0]) if len(hits) else -1


def declutter(
    specs: Iterable[LabelSpec],
    reserved: Sequence[tuple[float, float, float]] = (),
    *,
    sep_m: float = MIN_LABEL_SEPARATION_M,
    max_labels: int = MAX_VIEW_LABELS,
) -> list[LabelSpec]:
    """The labels to draw, no two (nor one and a reserved anchor) closer than ``sep_m``."""
    fixed = np.asarray(reserved, dtype=np.float64).reshape(-1, 3)
    placed: list[LabelSpec] = []
    for spec in specs:
        p = np.asarray(spec.position, dtype=np.float64)
        lifts = 0
        while _near(p, fixed, sep_m) >= 0 and spec.lift and lifts < MAX_LIFTS:
            p = p + np.array((0.0, 0.0, sep_m))
            lifts += 1
        if _near(p, fixed, sep_m) >= 0:
            continue  # the shared label there says it
        anchors = np.array([s.position for s in placed], dtype=np.float64).reshape(-1, 3)
        k = _near(p, anchors, sep_m)
        if k >= 0:
            placed[k] = replace(placed[k], merged=(*placed[k].merged, spec.text))
        elif len(placed) < max_labels:
            placed.append(replace(spec, position=(float(p[0]), float(p[1]), float(p[2]))))
    return placed


def min_separation_m(positions: Sequence[Sequence[float]]) -> float:
    """The smallest distance between two of ``positions`` (inf for fewer than two)."""
    p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    if len(p) < 2:
        return float("inf")
    d = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=-1)
    d[np.diag_indices(len(p))] = np.inf
    return float(d.min())
