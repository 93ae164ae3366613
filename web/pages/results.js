// Results: the figures of docs/RESULTS.md, interactive (Plotly), from GET /api/results (the data
// `mtrnn report` wrote beside the PNGs).

import { get } from "../js/api.js";
import { h, answerOrError } from "../js/dom.js";
import { BY, HIGHLIGHT, MODE_COLOURS, colourOf } from "../js/palette.js";
import { plotly, chart, groupPoints } from "../js/plots.js";

export const meta = { route: "results", title: "Results", order: 90,
  description: "the evaluation report's figures, interactive" };

const SPLITS = ["train", "test", "mixed"];

// A chart drawn once the page has placed it (chart() wraps it with its table toggle).
function plot(id, traces, layout) {
  const el = h("div", { id, class: "plot" });
  queueMicrotask(() => chart(el, traces, { height: 360, ...layout }));
  return el;
}

// What each metric is, for the charts' titles and value axes (model/metrics.py, paper 4.3).
const METRICS = {
  sentence_exact: ["sentence exact", "share of recordings described word for word (0-1)"],
  f1: ["phoneme F1", "phoneme F1 of the minimum-edit alignment (0-1)"],
  edit_distance: ["phoneme edit distance", "weighted edit distance / target length (lower is better)"],
};

function modesSection(data) {
  const modes = Object.keys(data.modes || {});
  if (!modes.length) return [];
  return [h("h2", {}, "Training modes, same folds"),
    h("p", { class: "muted" }, "Mean ± standard error over runs; diamonds: the paper's means (faithful only)."),
    h("div", { class: "grid2" }, Object.entries(METRICS).map(([metric, [title, axis]]) => {
      const traces = modes.map((m) => ({
        type: "bar", name: `${m} (${data.modes[m].runs} runs)`, x: SPLITS, marker: { color: colourOf(MODE_COLOURS, m) },
        y: SPLITS.map((s) => data.modes[m].summary?.[s]?.[metric]?.mean ?? null),
        error_y: { type: "data", array: SPLITS.map((s) => data.modes[m].summary?.[s]?.[metric]?.sem ?? 0) },
      }));
      if (data.paper?.train?.[metric] !== undefined)
        traces.push({ type: "scatter", mode: "markers", name: "paper", x: SPLITS,
          y: SPLITS.map((s) => data.paper[s][metric]), marker: { symbol: "diamond", size: 11, color: HIGHLIGHT } });
      return plot(`modes-${metric}`, traces, { title: `${title} by training mode`, barmode: "group",
        xaxis: { title: "recordings scored (train, test, mixed)" }, yaxis: { title: axis } });
    }))];
}

function psiSection(data) {
  const rows = data.psi_s;
  if (!rows?.length) return [];
  const x = rows.map((r) => r.psi_s);
  const line = (key, name) => ({ x, y: rows.map((r) => r[key]), name, mode: "lines+markers",
    error_y: { type: "data", array: rows.map((r) => r[`${key}_sem`] ?? 0) } });
  const log = (y) => ({ xaxis: { type: "log", title: "ψ_s (self-organisation forcing of MTRNN_s, log)" }, yaxis: { title: y } });
  return [h("h2", {}, "Self-organisation forcing psi_s (Fig. 9)"), h("div", { class: "grid2", id: "psi-plots" },
    plot("fig9a", [line("mixed_f1", "mixed F1")], { title: "(a) phoneme F1, train and test mixed", ...log("phoneme F1 (0-1)") }),
    plot("fig9b", [line("mixed_edit_distance", "mixed edit distance")], { title: "(b) phoneme edit distance, mixed", ...log("edit distance / target length") }),
    plot("fig9c", [line("d_avg", "d_avg"), line("d_rel", "d_rel")], { title: "(c) d_avg, d_rel of c_s,T (eqs. 14-15)", ...log("distance (Csc units)") }),
    plot("fig9d", [line("d_inter", "d_inter"), line("d_intra", "d_intra")], { title: "(d) d_inter, d_intra of c_s,T (eqs. 22-23)", ...log("distance (Csc units)") }))];
}

function cosineSection(data) {
  const rows = data.cosine;
  if (!rows?.length) return [];
  const x = rows.map((r) => String(r.psi));
  const line = (key) => ({ x, y: rows.map((r) => r[key] ?? null), name: key, mode: "lines+markers",
    error_y: { type: "data", array: rows.map((r) => r[`${key}_sem`] ?? 0) } });
  const examples = Object.entries(data.cosine_examples || {}).map(([psi, pts], i) => plot(`fig3-${i}`,
    pts.map((p, k) => ({ x: [p[0]], y: [p[1]], mode: "markers", name: `sequence ${k + 1}`, marker: { size: 12 } })),
    { title: `(c) abstracted contexts of the four sequences, ψ = ${psi}`, xaxis: { title: "Csc unit 1 (internal state)" },
      yaxis: { title: "Csc unit 2 (internal state)" } }));
  return [h("h2", {}, "Contrary cosines (Fig. 3)"), h("div", { class: "grid2" },
    plot("fig3a", [line("epochs")], { title: "(a) epochs until the error converged", xaxis: { title: "ψ (self-organisation forcing)", type: "category" },
      yaxis: { title: "training epochs" } }),
    plot("fig3b", [line("d_avg"), line("d_rel")], { title: "(b) d_avg and d_rel of the abstracted contexts", xaxis: { title: "ψ (self-organisation forcing)", type: "category" },
      yaxis: { title: "distance (Csc units); d_rel: ratio" } }),
    ...examples)];
}

function pcaSection(data) {
  const runs = Object.entries(data.pca || {});
  if (!runs.length) return [];
  const colourBy = h("select", { id: "pca-colour", "aria-label": "colour by" },
    ["action", "colour", "object", "split"].map((k) => h("option", { value: k }, k)));
  const grid = h("div", { class: "grid2", id: "pca-plots" });
  function draw() {
    const by = colourBy.value;
    grid.replaceChildren(...runs.flatMap(([name, panels]) => panels.map((p, i) => {
      const groups = groupPoints(p.xy, p[by], (k) => `${p.ids[k]} (${p.split[k]})<br>says: ${p.generated[k]}`);
      return plot(`pca-${name}-${i}`, [...groups.entries()].map(([key, g]) => ({ ...g, name: key, mode: "markers",
        type: "scatter", hoverinfo: "text", marker: { size: 6, color: colourOf(BY[by], key) } })), { title: p.title,
        xaxis: { title: "PC1 of the Csc patterns" }, yaxis: { title: "PC2 of the Csc patterns" }, legend: { title: { text: by } } });
    })));
  }
  colourBy.addEventListener("change", draw);
  draw();
  return [h("h2", {}, "Csc spaces after activation by perception (Fig. 10)"),
    h("p", { class: "muted" }, "Lowest and highest test F1 run of each mode; hover a point to read what the model says. ",
      h("label", {}, "Colour by ", colourBy)), grid];
}

export async function render(root) {
  root.append(h("h1", {}, "Results"), h("p", { class: "lead" },
    "The numbers of docs/RESULTS.md, from the evaluation run store (", h("code", {}, "mtrnn evaluate"), ", ",
    h("code", {}, "mtrnn sweep"), ", ", h("code", {}, "mtrnn report"), ")."));
  const data = await answerOrError(root, get("/api/results"));
  if (!data) return;
  await plotly();
  root.append(...modesSection(data), ...psiSection(data), ...cosineSection(data), ...pcaSection(data));
}
