// The mission script's preview drawn in its own panel: a plan view (north up) of the whole
// script's path, with where each step takes effect. The 3D view (top of the page) draws the
// same path, but at 1280x800 it is out of sight while the operator works in the script panel,
// below the fold (issue 20): this view is where the operator is looking, and is scrolled into
// view when drawn.

const SVG = "http://www.w3.org/2000/svg";

function svgEl(tag, attrs = {}, text = null) {
  const node = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, String(v));
  if (text !== null) node.textContent = text;
  return node;
}

function metres(v) {
  return `${Math.round(v * 10) / 10} m`;
}

/** Draw the preview's combined path ({x_m: north, y_m: east, z_m, step_start}) and its steps
 * into the figure `box` (an <svg> and a <figcaption> inside); scroll it into view. */
export function drawScriptPlan(box, path, steps, onShow3d) {
  const svg = box.querySelector("svg");
  const caption = box.querySelector("figcaption");
  const north = Array.isArray(path && path.x_m) ? path.x_m : [];
  const east = Array.isArray(path && path.y_m) ? path.y_m : [];
  const depth = Array.isArray(path && path.z_m) ? path.z_m : [];
  const n = Math.min(north.length, east.length);
  svg.replaceChildren();
  if (n === 0) {
    box.hidden = true;
    return;
  }
  let [minE, maxE, minN, maxN] = [Math.min(...east), Math.max(...east), Math.min(...north), Math.max(...north)];
  const span = Math.max(maxE - minE, maxN - minN, 2);
  const pad = span * 0.08;
  minE -= pad; maxE += pad; minN -= pad; maxN += pad;
  const w = Math.max(maxE - minE, span * 0.5);
  const h = Math.max(maxN - minN, span * 0.5);
  // east to the right, north up: (e, -n) in the SVG's y-down space
  svg.setAttribute("viewBox", `${minE} ${-maxN} ${w} ${h}`);
  const points = [];
  for (let i = 0; i < n; i++) points.push(`${east[i].toFixed(2)},${(-north[i]).toFixed(2)}`);
  svg.append(svgEl("polyline", { points: points.join(" "), class: "plan-path", "vector-effect": "non-scaling-stroke" }));
  const r = span * 0.018;
  const font = span * 0.06;
  const starts = Array.isArray(path.step_start) ? path.step_start : [];
  starts.forEach((k, s) => {
    if (!(k >= 0 && k < n)) return;
    const step = steps[s] || {};
    const mark = svgEl("g", { class: "plan-step", "data-step": s });
    mark.append(svgEl("title", {}, `step ${s + 1}: ${step.pattern || ""}${step.timing_text ? `, ${step.timing_text}` : ""}`));
    mark.append(svgEl("circle", { cx: east[k], cy: -north[k], r }));
    mark.append(svgEl("text", { x: east[k] + r * 1.4, y: -north[k] - r * 1.4, "font-size": font }, String(s + 1)));
    svg.append(mark);
  });
  const finite = depth.filter(Number.isFinite);
  const [shallow, deep] = finite.length ? [metres(Math.min(...finite)), metres(Math.max(...finite))] : [];
  const depths = !finite.length ? "" : shallow === deep ? `depth ${deep}` : `depth ${shallow} to ${deep}`;
  const show3d = document.createElement("button");
  show3d.type = "button";
  show3d.className = "link-button";
  show3d.dataset.testid = "script-plan-3d";
  show3d.textContent = "show the 3D view";
  show3d.addEventListener("click", onShow3d);
  caption.replaceChildren(
    `Plan view, north up: ${metres(maxE - minE - 2 * pad)} east-west by ${metres(maxN - minN - 2 * pad)} north-south`,
    depths ? `, ${depths}` : "",
    path.repeats ? "; the last step repeats: one lap shown" : "",
    ". The numbers mark where each step takes effect; the same path is drawn in the 3D view (",
    show3d,
    ").",
  );
  box.hidden = false;
  box.scrollIntoView({ block: "nearest" });
}
