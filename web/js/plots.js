// Plotly helpers (Plotly.js is served by the app from the installed `plotly` package).

export const ACTION_COLOURS = { pull: "#1f77b4", push: "#ff7f0e", "show me": "#2ca02c", slide: "#9467bd" };
export const OBJECT_COLOURS = { blue: "#2858dc", green: "#28aa46", red: "#d22828", yellow: "#e6b800" };
export const SHAPE_COLOURS = { apple: "#8c564b", banana: "#bcbd22", dice: "#17becf", phone: "#7f7f7f" };
export const JOINT_COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd"];

export function plotly() {
  return new Promise((resolve) => {
    if (window.Plotly) return resolve(window.Plotly);
    const wait = () => (window.Plotly ? resolve(window.Plotly) : setTimeout(wait, 30));
    wait();
  });
}

export const CONFIG = { displaylogo: false, responsive: true, modeBarButtonsToRemove: ["select2d", "lasso2d"] };

export function baseLayout(extra = {}) {
  return {
    margin: { l: 50, r: 10, t: 30, b: 40 },
    paper_bgcolor: "rgba(0,0,0,0)",
    plot_bgcolor: "#fff",
    font: { family: "system-ui, sans-serif", size: 12 },
    ...extra,
  };
}

// A vertical line at x (the shared time cursor) as a layout shape.
export function cursorShape(x, yref = "paper") {
  return { type: "line", x0: x, x1: x, y0: 0, y1: 1, yref, line: { color: "#e03030", width: 2 } };
}
