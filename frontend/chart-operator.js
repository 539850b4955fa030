// Whether the operator has moved the chart: only the operator's own input (a drag, the wheel,
// a double click, the arrow and zoom keys, the zoom buttons, a box zoom, a touch) counts, never
// the page's own fits, so the chart can refit each new preview until the operator takes over.

/** Call `moved()` on the operator's own moves of Leaflet map `map`; keep the zoom in
 *  `data-zoom` of its container (for the tests). */
export function watchOperator(map, moved) {
  map.on("dragstart boxzoomend", moved);
  const box = map.getContainer();
  for (const kind of ["wheel", "dblclick", "touchstart"]) box.addEventListener(kind, moved, { passive: true });
  box.addEventListener("keydown", (e) => /^(Arrow|\+|-|=)/.test(e.key) && moved());
  // Leaflet's zoom buttons stop their clicks: caught on the way down
  box.querySelector(".leaflet-control-zoom").addEventListener("click", moved, true);
  map.on("zoomend", () => (box.dataset.zoom = String(map.getZoom())));
}
