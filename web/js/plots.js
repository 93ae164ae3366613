// Plotly helpers (Plotly.js is served by the app from the installed `plotly` package); the colours
// come from palette.js.

import { CATEGORICAL, CURSOR, TRANSPARENT, WHITE } from "./palette.js";

export function plotly() {
  return new Promise((resolve) => {
    if (window.Plotly) return resolve(window.Plotly);
    const wait = () => (window.Plotly ? resolve(window.Plotly) : setTimeout(wait, 30));
    wait();
  });
}

export const CONFIG = { displaylogo: false, responsive: true, modeBarButtonsToRemove: ["select2d", "lasso2d"] };

// Traces without a colour of their own take the palette's categorical colours in turn.
export function baseLayout(extra = {}) {
  return {
    margin: { l: 50, r: 10, t: 30, b: 40 },
    paper_bgcolor: TRANSPARENT,
    plot_bgcolor: WHITE,
    colorway: CATEGORICAL,
    font: { family: "system-ui, sans-serif", size: 12 },
    ...extra,
  };
}

// A vertical line at x (the shared time cursor) as a layout shape.
export function cursorShape(x, yref = "paper") {
  return { type: "line", x0: x, x1: x, y0: 0, y1: 1, yref, line: { color: CURSOR, width: 2 } };
}

// One scatter trace per group of `keys` (points[i] belongs to keys[i]), in first-seen order.
export function groupPoints(points, keys, text = null) {
  const groups = new Map();
  points.forEach((p, i) => {
    const g = groups.get(keys[i]) || { x: [], y: [], text: [] };
    g.x.push(p[0]); g.y.push(p[1]);
    if (text) g.text.push(text(i));
    groups.set(keys[i], g);
  });
  return groups;
}
