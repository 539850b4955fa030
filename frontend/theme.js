// The night (dark) and day (high-contrast light) themes: a toggle in the header, remembered in
// localStorage; the first visit follows the system's prefers-color-scheme (theme-init.js
// applies the theme before the first paint; this module keeps the toggle in step).

import { $ } from "./ui.js";

const KEY = "nemesys.theme";

export function currentTheme() {
  return document.documentElement.dataset.theme === "day" ? "day" : "night";
}

export function setTheme(theme, remember = true) {
  const t = theme === "day" ? "day" : "night";
  document.documentElement.dataset.theme = t;
  if (remember) {
    try {
      localStorage.setItem(KEY, t);
    } catch {
      // storage refused (private mode): the theme holds for this page only
    }
  }
  const button = $("theme-toggle");
  if (button) {
    button.textContent = t === "day" ? "Night" : "Day";
    button.setAttribute("aria-pressed", String(t === "day"));
  }
}

export function initTheme() {
  setTheme(currentTheme(), false);
  $("theme-toggle").addEventListener("click", () => setTheme(currentTheme() === "day" ? "night" : "day"));
}
