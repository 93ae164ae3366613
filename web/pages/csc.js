// Csc explorer: PCA of the three Csc spaces over every corpus recording (paper Figs. 9-10).

import { get } from "../js/api.js";
import { h, field, help, errorBox, fmt } from "../js/dom.js";
import { plotly, CONFIG, baseLayout, ACTION_COLOURS, OBJECT_COLOURS, SHAPE_COLOURS } from "../js/plots.js";

export const meta = { route: "csc", title: "Csc spaces", order: 30,
  description: "the context (Csc) patterns of every recording, projected by PCA" };

const SPACES = {
  s: ["somatosensory c_s,T", "Final Csc state of MTRNN_s after reading the proprioception: what the arm felt."],
  v: ["visual c_v,T", "Final Csc state of MTRNN_v after reading the visual features: what the camera saw."],
  a: ["auditory c_a,0", "Initial Csc state of MTRNN_a computed by the cell assemblies from c_s,T and c_v,T: what the robot is about to say."],
};
const PALETTES = { action: ACTION_COLOURS, colour: OBJECT_COLOURS, shape: SHAPE_COLOURS };
const MEASURES = {
  d_avg: ["d_avg", "eq. (14): average Euclidean distance between all patterns. Shrinks when patterns collapse."],
  d_rel: ["d_rel", "eq. (15): geometric mean of distance / d_avg; 1 means all patterns are equally far apart."],
  d_inter: ["d_inter", "eq. (22): average distance between patterns of the same manipulation, averaged over the four. Small = tight clusters."],
  d_intra: ["d_intra", "eq. (23): average distance between the centroids of the four manipulations. Larger than d_inter = clusters separate."],
};

export async function render(root, ctx) {
  const space = SPACES[ctx.params.space] ? ctx.params.space : "a";
  const colourBy = PALETTES[ctx.params.colour] ? ctx.params.colour : "action";
  const spaceSel = h("select", { id: "space" }, Object.entries(SPACES).map(([k, [label]]) => h("option", { value: k, selected: k === space }, `${k}: ${label}`)));
  const colourSel = h("select", { id: "colour-by" }, Object.keys(PALETTES).map((k) => h("option", { value: k, selected: k === colourBy }, k)));
  spaceSel.addEventListener("change", () => { location.hash = `#/csc?space=${spaceSel.value}&colour=${colourSel.value}`; });
  colourSel.addEventListener("change", () => { location.hash = `#/csc?space=${spaceSel.value}&colour=${colourSel.value}`; });
  const plot = h("div", { class: "plot square", id: "csc-plot" });
  const side = h("div", { class: "side" });
  root.append(h("h1", {}, "Csc spaces"),
    h("p", { class: "lead" }, "Each point is one corpus recording: its Csc pattern, reduced to two dimensions by PCA (exact SVD). Hover for the scene, click to open it. Filled markers: training recordings; open markers: test (never seen)."),
    h("div", { class: "controls" },
      field("space", spaceSel, "Which network's context units to show: s = somatosensory (MTRNN_s), v = visual (MTRNN_v), a = auditory (MTRNN_a, after the cell assemblies).", "Csc"),
      field("colour by", colourSel, "Colour the points by the manipulation, the object's colour or its shape, to see what each space clusters by.", "Csc")),
    h("p", { class: "muted" }, SPACES[space][1]),
    h("div", { class: "grid-plot" }, plot, side));

  let data;
  try {
    data = await get(`/api/csc?space=${space}`);
  } catch (e) {
    root.append(errorBox(e.message));
    return;
  }
  const Plotly = await plotly();
  const palette = PALETTES[colourBy];
  const traces = Object.keys(palette).map((cat) => {
    const pts = data.points.filter((p) => p[colourBy] === cat);
    return {
      type: "scatter", mode: "markers", name: cat, x: pts.map((p) => p.x), y: pts.map((p) => p.y),
      customdata: pts.map((p) => p.id),
      text: pts.map((p) => `${p.id} (${p.split})<br>teacher: ${p.action} the ${p.colour} ${p.shape}.<br>model: ${p.generated}`),
      hovertemplate: "%{text}<extra></extra>",
      marker: { color: palette[cat], size: 10, line: { color: palette[cat], width: 2 },
        symbol: pts.map((p) => (p.split === "test" ? "circle-open" : "circle")) },
    };
  });
  const highlight = data.points.find((p) => p.id === ctx.params.highlight);
  if (highlight) traces.push({ type: "scatter", mode: "markers+text", name: highlight.id, x: [highlight.x], y: [highlight.y],
    text: [highlight.id], textposition: "top center", hoverinfo: "skip", marker: { size: 22, symbol: "star", color: "#000" } });
  const ev = data.explained_variance_ratio;
  await Plotly.newPlot(plot, traces, baseLayout({ height: 560, hovermode: "closest",
    xaxis: { title: `PC1 (${(100 * ev[0]).toFixed(1)} %)`, zeroline: false },
    yaxis: { title: `PC2 (${(100 * (ev[1] ?? 0)).toFixed(1)} %)`, zeroline: false } }), CONFIG);
  plot.on("plotly_click", (e) => {
    const id = e.points[0] && e.points[0].customdata;
    if (id) location.hash = `#/scene/${id}`;
  });

  side.append(h("h2", {}, "Cluster measures ", help("The paper's distance measures on the original (not reduced) Csc patterns, grouped by manipulation (4.3).", "Csc")),
    h("table", { class: "measures", id: "measures" }, Object.entries(MEASURES).map(([k, [label, tip]]) =>
      h("tr", {}, h("th", {}, label, " ", help(tip, "Csc")), h("td", {}, fmt(data.measures[k], 4))))),
    h("p", { class: "muted small" }, `${data.points.length} recordings · ${data.dims} Csc units · model ${data.model}`),
    h("h2", {}, "Explained variance ", help("Share of the patterns' variance along each principal component; the plot shows PC1 and PC2.", "PCA")));
  const evPlot = h("div", { class: "plot small", id: "ev-plot" });
  side.append(evPlot);
  await Plotly.newPlot(evPlot, [{ type: "bar", x: ev.map((_, i) => `PC${i + 1}`), y: ev.map((v) => 100 * v), marker: { color: "#4a6fa5" } }],
    baseLayout({ height: 220, yaxis: { title: "%" }, margin: { l: 40, r: 5, t: 10, b: 40 } }), CONFIG);
}
