// Before the first paint: the theme remembered in localStorage, else the system's preference.
(() => {
  let theme = null;
  try {
    theme = localStorage.getItem("nemesys.theme");
  } catch {
    theme = null;
  }
  if (theme !== "day" && theme !== "night") {
    theme = window.matchMedia && window.matchMedia("(prefers-color-scheme: light)").matches ? "day" : "night";
  }
  document.documentElement.dataset.theme = theme;
})();
