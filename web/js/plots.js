// Plotly helpers (Plotly.js is served by the app from the installed `plotly` package); the colours
// come from palette.js. Every chart is drawn through `chart()`: it says what it shows (a title and
// axis titles; Plotly 3+ reads only { text } titles, `chart` accepts plain strings too) and gets a
// "show as table" alternative that lists the very numbers drawn.

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
    margin: { l: 60, r: 10, t: 40, b: 50 },
    paper_bgcolor: TRANSPARENT,
    plot_bgcolor: WHITE,
    colorway: CATEGORICAL,
    font: { family: "system-ui, sans-serif", size: 12 },
    ...extra,
  };
}

const asTitle = (t, size) => (typeof t === "string" ? { text: t, ...(size ? { font: { size } } : {}) } : t);

// The layout with every title (the figure's, each axis', each colour bar's) as Plotly's { text }.
function titled(layout) {
  const out = { ...layout, title: asTitle(layout.title, 14) };
  for (const [key, value] of Object.entries(layout)) {
    if (/^[xy]axis\d*$/.test(key) && value) out[key] = { ...value, title: asTitle(value.title) };
  }
  return out;
}

function titledTrace(trace) {
  const bar = trace.colorbar ?? trace.marker?.colorbar;
  if (!bar || typeof bar.title !== "string") return trace;
  return trace.colorbar ? { ...trace, colorbar: { ...bar, title: asTitle(bar.title) } }
    : { ...trace, marker: { ...trace.marker, colorbar: { ...bar, title: asTitle(bar.title) } } };
}

// Draws (or redraws) `traces` in `el` with `layout` over baseLayout; the first call wraps `el` in
// a figure with the table toggle (el keeps its id and its place in the page's layout).
export function chart(el, traces, layout = {}, config = CONFIG) {
  if (!tables.has(el)) tableToggle(el);
  return window.Plotly.react(el, traces.map(titledTrace), baseLayout(titled(layout)), config)
    .then((gd) => { refreshTable(el); return gd; });
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

// --- "show as table" ------------------------------------------------------------------------

const tables = new WeakMap(); // plot element -> { button, box }

function tableToggle(el) {
  const figure = document.createElement("figure");
  figure.className = "chart";
  el.replaceWith(figure);
  const button = document.createElement("button");
  button.type = "button";
  button.className = "table-toggle";
  button.textContent = "show as table";
  const box = document.createElement("div");
  box.className = "chart-table";
  box.id = `${el.id || "plot"}-table`;
  box.hidden = true;
  box.tabIndex = 0; // a long table scrolls: the keyboard must reach it
  button.setAttribute("aria-controls", box.id);
  button.setAttribute("aria-expanded", "false");
  button.addEventListener("click", () => {
    box.hidden = !box.hidden;
    button.setAttribute("aria-expanded", String(!box.hidden));
    button.textContent = box.hidden ? "show as table" : "hide the table";
    refreshTable(el);
  });
  figure.append(el, button, box);
  tables.set(el, { button, box });
}

function refreshTable(el) {
  const t = tables.get(el);
  if (t && !t.box.hidden) t.box.replaceChildren(dataTable(el.data || [], el.layout || {}));
}

const plain = (v) => (v === null || v === undefined ? "" : String(v).replace(/<br>/g, " · ").replace(/<[^>]+>/g, ""));
const cell = (v) => (typeof v === "number" ? (Number.isInteger(v) ? String(v) : v.toPrecision(4)) : plain(v));
const axisName = (layout, axis, fallback) => plain(layout[axis]?.title?.text) || fallback;

function element(tag, text, attrs = {}) {
  const e = document.createElement(tag);
  if (text !== undefined) e.textContent = text;
  Object.entries(attrs).forEach(([k, v]) => e.setAttribute(k, v));
  return e;
}

function tableOf(caption, head, rows) {
  const table = element("table", undefined, { class: "data-table" });
  if (caption) table.append(element("caption", caption));
  const tr = element("tr");
  head.forEach((c) => tr.append(element("th", c, { scope: "col" })));
  table.append(element("thead"));
  table.tHead.append(tr);
  const body = element("tbody");
  rows.forEach((r) => {
    const row = element("tr");
    r.forEach((c) => row.append(element("td", cell(c))));
    body.append(row);
  });
  table.append(body);
  return table;
}

// The numbers of a figure as a table: a heatmap as its grid, traces sharing their x as columns
// side by side, other traces one row per point.
function dataTable(data, layout) {
  const caption = plain(layout.title?.text);
  const xName = axisName(layout, "xaxis", "x"), yName = axisName(layout, "yaxis", "y");
  const heat = data.find((t) => t.type === "heatmap");
  if (heat) {
    const z = heat.z || [];
    const xs = heat.x || (z[0] || []).map((_, j) => j), ys = heat.y || z.map((_, i) => i);
    return tableOf(caption, [`${yName} \\ ${xName}`, ...xs.map(plain)], ys.map((y, i) => [plain(y), ...(z[i] || [])]));
  }
  const shown = data.filter((t) => t.x && t.y && t.x.some((v) => v !== null && v !== undefined));
  const sameX = shown.length > 1 && shown.every((t) => JSON.stringify(t.x) === JSON.stringify(shown[0].x));
  if (sameX || shown.length === 1) {
    const head = [xName], columns = [];
    shown.forEach((t, k) => {
      const name = plain(t.name) || (shown.length === 1 ? yName : `series ${k + 1}`);
      head.push(name); columns.push(t.y);
      if (t.error_y?.array) { head.push(`± ${name}`); columns.push(t.error_y.array); }
    });
    return tableOf(caption, head, shown[0].x.map((x, i) => [plain(x), ...columns.map((c) => c[i])]));
  }
  const rows = shown.flatMap((t) => t.x.map((x, i) => [plain(t.name), x, t.y[i], plain(Array.isArray(t.text) ? t.text[i] : t.text)]));
  return tableOf(caption, ["series", xName, yName, "label"], rows);
}
