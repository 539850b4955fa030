// The parameter form of one pattern, built from the dictionary's field descriptions, so a new
// pattern or field needs no change here. Used by the authoring column and by script steps.

import { el, on, withUnit } from "./ui.js";

/** The dictionary as returned by GET /api/dictionary, indexed by pattern name. */
export const dictionary = { list: [], byName: new Map() };

/** The vehicle's top speed (m/s) from the session's profile; null: unknown. */
let topSpeed = null;

/** A field's default: the dictionary's, but a speed no faster than the vehicle can fly
 * (floored to the centimetre per second, so it never exceeds the top speed). */
export function defaultOf(field) {
  const d = field.default;
  if (field.name !== "speed" || topSpeed === null || typeof d !== "number") return d;
  return Math.min(d, Math.floor(topSpeed * 100) / 100);
}

on("session", ({ session }) => {
  const top = session && session.profile ? session.profile.top_speed_mps : null;
  topSpeed = typeof top === "number" && top > 0 ? top : null;
});

export function setDictionary(list) {
  dictionary.list = Array.isArray(list) ? list : [];
  dictionary.byName = new Map(dictionary.list.map((p) => [p.name, p]));
}

export function fieldOf(pattern, name) {
  const p = dictionary.byName.get(pattern);
  return p ? (p.fields || []).find((f) => f.name === name) : undefined;
}

export function unitOf(pattern, name) {
  const f = fieldOf(pattern, name);
  return f ? f.unit || "" : "";
}

/** "circle: speed 0.18 m/s, depth 3 m, radius 5 m, direction cw" */
export function commandText(cmd) {
  if (!cmd || !cmd.pattern) return "–";
  const params = cmd.params || {};
  const parts = Object.entries(params).map(([k, v]) => `${k} ${withUnit(v, unitOf(cmd.pattern, k))}`);
  return parts.length ? `${cmd.pattern}: ${parts.join(", ")}` : cmd.pattern;
}

/** Fill a <select> with the dictionary's patterns. */
export function fillPatternSelect(select, selected) {
  select.replaceChildren(
    ...dictionary.list.map((p) => el("option", { value: p.name, title: p.doc || "" }, `${p.label || p.name} (ID ${p.id})`)),
  );
  if (selected && dictionary.byName.has(selected)) select.value = selected;
}

export function defaultParams(pattern) {
  const p = dictionary.byName.get(pattern);
  const out = {};
  for (const f of (p && p.fields) || []) out[f.name] = defaultOf(f);
  return out;
}

/** The value a form control holds: numbers as numbers, anything unparsable as typed. */
function readControl(field, control) {
  if (field.kind === "choice") return control.value;
  const text = control.value.trim();
  if (text === "") return control.validity && control.validity.badInput ? "invalid" : "";
  const n = Number(text);
  return Number.isFinite(n) ? n : text;
}

function fieldRow(field, value, prefix, onChange) {
  const id = `${prefix}param-${field.name}`;
  const hintId = `${id}-hint`;
  const unit = field.unit || "";
  let control;
  if (field.kind === "choice") {
    control = el("select", { id, testid: id, "aria-describedby": hintId },
      ...(field.choices || []).map((c) => el("option", { value: c }, c)));
    control.value = value ?? field.default;
  } else {
    control = el("input", {
      id, testid: id, type: "number", inputmode: "decimal",
      step: field.kind === "count" ? "1" : "any", "aria-describedby": hintId,
    });
    if (field.period === undefined && field.min !== undefined) control.min = field.min;
    if (field.period === undefined && field.max !== undefined) control.max = field.max;
    control.value = value ?? defaultOf(field) ?? "";
  }
  control.addEventListener("input", onChange);
  control.addEventListener("change", onChange);
  const hint = [field.range || `${withUnit(field.min, unit)} to ${withUnit(field.max, unit)}`];
  if (field.error && field.error !== "exact") hint.push(`error ${field.error}`);
  return el("div", { class: "field param", dataset: { field: field.name } },
    el("label", { for: id, title: field.doc || "" }, field.label || field.name, unit ? el("span", { class: "muted" }, ` (${unit})`) : null),
    el("div", { class: "input-unit" }, control, unit ? el("span", { class: "unit", "aria-hidden": "true" }, unit) : null),
    el("small", { id: hintId, class: "hint", title: field.steps || "" }, hint.join(" · ")),
    el("output", { class: "snap", testid: `${prefix}snap-${field.name}`, for: id, hidden: true }),
    el("span", { class: "field-error", testid: `${prefix}error-${field.name}`, role: "alert", hidden: true }),
  );
}

/**
 * Build the form of `pattern` into `container`. prefix namespaces ids and test ids ("" for the
 * authoring column: param-<name>, snap-<name>, error-<name>). Returns the form's API.
 */
export function paramForm(container, pattern, values, { prefix = "", onChange = () => {} } = {}) {
  const p = dictionary.byName.get(pattern);
  const fields = (p && p.fields) || [];
  const controls = new Map();
  const rows = fields.map((f) => {
    const row = fieldRow(f, values ? values[f.name] : undefined, prefix, onChange);
    controls.set(f.name, { field: f, row, control: row.querySelector("input, select") });
    return row;
  });
  container.replaceChildren(...(rows.length ? rows : [el("p", { class: "hint" }, "This pattern has no parameters.")]));

  return {
    pattern,
    read() {
      const out = {};
      for (const [name, { field, control }] of controls) out[name] = readControl(field, control);
      return out;
    },
    /** errors: Map param -> message; anything not a field is ignored here. */
    setErrors(errors) {
      for (const [name, { row, control }] of controls) {
        const msg = errors.get(name);
        const box = row.querySelector(".field-error");
        box.textContent = msg || "";
        box.hidden = !msg;
        control.toggleAttribute("aria-invalid", Boolean(msg));
        row.classList.toggle("has-error", Boolean(msg));
      }
    },
    setWarnings(params) {
      for (const [name, { row }] of controls) row.classList.toggle("has-warning", params.has(name));
    },
    /** snaps: [{field, requested, sent, unit, changed}] from the encoder. */
    setSnaps(snaps) {
      const byField = new Map((snaps || []).map((s) => [s.field, s]));
      for (const [name, { row }] of controls) {
        const out = row.querySelector(".snap");
        const s = byField.get(name);
        const show = Boolean(s && s.changed);
        out.hidden = !show;
        out.textContent = show ? `${withUnit(s.requested, s.unit, 6)} -> ${withUnit(s.sent, s.unit, 6)}` : "";
        out.title = show ? "requested -> sent: the 8-bit scale snapped the value" : "";
      }
    },
    focus(name) {
      const c = controls.get(name);
      if (c) c.control.focus();
    },
  };
}
