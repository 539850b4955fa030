// The chart's own Leaflet controls (chart.js adds them): the buttons that centre on the vehicle
// and fit the preview and the vehicles, and the legend of the link's reach and the lines drawn.

import { el } from "./ui.js";

// the buttons' icons (inline: no icon font to fetch)
const ICON_CENTRE = '<circle cx="8" cy="8" r="4.5"/><path d="M8 0v4M8 12v4M0 8h4M12 8h4"/>';
const ICON_FIT = '<path d="M1 5V1h4M11 1h4v4M15 11v4h-4M5 15H1v-4"/>';
const REACH = {
  in_range: "in range",
  marginal: "marginal",
  out_of_range: "out of range",
};

const FIT_PAD_PX = 24; // a fit's margin inside the chart's edges

/** A fit's padding (Leaflet's fitBounds options) inside the chart's element `box`: its margin,
 *  and on the right the buttons' column too, so that nothing fitted lies under them. */
export function fitPadding(box) {
  const buttons = box.querySelector(".leaflet-top.leaflet-right");
  const right = FIT_PAD_PX + (buttons ? buttons.offsetWidth : 0);
  return { paddingTopLeft: [FIT_PAD_PX, FIT_PAD_PX], paddingBottomRight: [right, FIT_PAD_PX] };
}

/** The centre and fit buttons (Leaflet `L`): `centre()` and `fit()` on a press. */
export function buttonsControl(L, { centre, fit }) {
  const Buttons = L.Control.extend({
    options: { position: "topright" },
    onAdd() {
      const box = el("div", { class: "leaflet-bar chart-buttons" });
      const button = (svg, title, testid, fn) => {
        const a = el("a", { href: "#", role: "button", title, "aria-label": title, testid, onclick: (e) => (e.preventDefault(), fn()) });
        a.innerHTML = `<svg viewBox="0 0 16 16" width="16" height="16" aria-hidden="true">${svg}</svg>`;
        return a;
      };
      box.append(
        button(ICON_CENTRE, "centre on the vehicle", "chart-centre-vehicle", centre),
        button(ICON_FIT, "fit the preview, the predicted track and the vehicle, or every vehicle of a fleet (and each new preview again)", "chart-fit", fit),
      );
      L.DomEvent.disableClickPropagation(box);
      return box;
    },
  });
  return new Buttons();
}

/** The legend (Leaflet `L`): the reach's three states and the lines. */
export function legendControl(L) {
  const Legend = L.Control.extend({
    options: { position: "bottomright" },
    onAdd() {
      const item = (cls, text, title) => el("li", { title }, el("span", { class: `swatch ${cls}`, "aria-hidden": "true" }), text);
      const box = el(
        "ul",
        { class: "chart-legend", testid: "chart-legend" },
        item("reach-in_range", REACH.in_range),
        item("reach-marginal", `${REACH.marginal} (> 75 %)`, "beyond 75 % of the ME link's range from the transmitter"),
        item("reach-out_of_range", REACH.out_of_range),
        item("predicted", "predicted", "what the twin predicts the vehicle will fly"),
        item("active", "active", "the path the vehicle flies, as the console mirrors it"),
        item("track", "track"),
      );
      L.DomEvent.disableClickPropagation(box);
      return box;
    },
  });
  return new Legend();
}
