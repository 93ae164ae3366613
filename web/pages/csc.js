// Csc explorer: PCA of the three Csc spaces over every corpus recording (paper Figs. 9-10).

import { get } from "../js/api.js";
import { h, field, help, errorBox, fmt } from "../js/dom.js";
import { ACCENT, BY, HIGHLIGHT } from "../js/palette.js";
import { plotly, CONFIG, baseLayout } from "../js/plots.js";

export const meta = { route: "csc", title: "Csc spaces", order: 30,
  description: "the context (Csc) patterns of every recording, projected by PCA" };

const SPACES = {
  s: ["somatosensory c_s,T", "Final Csc state of MTRNN_s after reading the proprioception: what the arm felt."],
  v: ["visual c_v,T", "Final Csc state of MTRNN_v after reading the visual features: what the camera saw."],
  a: ["auditory c_a,0", "Initial Csc state of MTRNN_a computed by the cell assemblies from c_s,T and c_v,T: what the robot is about to say."],
};
const COLOUR_BY = ["action", "colour", "shape"];
const MEASURES = {
  d_avg: ["d_avg", "eq. (14): average Euclidean distance between all patterns. Shrinks when patterns collapse."],
  d_rel: ["d_rel", "eq. (15): geometric mean of distance / d_avg; 1 means all patterns are equally far apart."],
  d_inter: ["d_inter", "eq. (22): average distance between patterns of the same manipulation, averaged over the four. Small = tight clusters."],
  d_intra: ["d_intra", "eq. (23): average distance between the centroids of the four manipulations. Larger than d_inter = clusters separate."],
};

export async function render(root, ctx) {
  const spaceSel = h("select", { id: "space" }, Object.entries(SPACES).map(([k, [label]]) =>
    h("option", { value: k, selected: k === ctx.params.space }, `${k}: ${label}`)));
  const colourSel = h("select", { id: "colour-by" }, COLOUR_BY.map((k) => h("option", { value: k, selected: k === ctx.params.colour }, k)));
  if (!SPACES[ctx.params.space]) spaceSel.value = "a";
  if (!COLOUR_BY.includes(ctx.params.colour)) colourSel.value = "action";
  const about = h("p", { class: "muted" });
  const plot = h("div", { class: "plot square", id: "csc-plot" });
  const side = h("div", { class: "side" });
  const error = h("div");
  root.append(h("h1", {}, "Csc spaces"),
    h("p", { class: "lead" }, "Each point is one corpus recording: its Csc pattern, reduced to two dimensions by PCA (exact SVD). Hover for the scene, click to open it. Filled markers: training recordings; open markers: test (never seen)."),
    h("div", { class: "controls" },
      field("space", spaceSel, "Which network's context units to show: s = somatosensory (MTRNN_s), v = visual (MTRNN_v), a = auditory (MTRNN_a, after the cell assemblies).", "Csc"),
      field("colour by", colourSel, "Colour the points by the manipulation, the object's colour or its shape, to see what each space clusters by.", "Csc")),
    about, error,
    h("div", { class: "grid-plot" }, plot, side));

  const Plotly = await plotly();
  let data = null;
  async function drawPoints() {
    const colourBy = colourSel.value;
    const palette = BY[colourBy];
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
      text: [highlight.id], textposition: "top center", hoverinfo: "skip", marker: { size: 22, symbol: "star", color: HIGHLIGHT } });
    const ev = data.explained_variance_ratio;
    await Plotly.react(plot, traces, baseLayout({ height: 560, hovermode: "closest",
      xaxis: { title: `PC1 (${(100 * ev[0]).toFixed(1)} %)`, zeroline: false },
      yaxis: { title: `PC2 (${(100 * (ev[1] ?? 0)).toFixed(1)} %)`, zeroline: false } }), CONFIG);
    plot.removeAllListeners("plotly_click");
    plot.on("plotly_click", (e) => {
      const id = e.points[0] && e.points[0].customdata;
      if (id) location.hash = `#/scene/${id}`;
    });
  }

  async function drawSide() {
    const ev = data.explained_variance_ratio;
    const evPlot = h("div", { class: "plot small", id: "ev-plot" });
    side.replaceChildren(h("h2", {}, "Cluster measures ", help("The paper's distance measures on the original (not reduced) Csc patterns, grouped by manipulation (4.3).", "Csc")),
      h("table", { class: "measures", id: "measures" }, Object.entries(MEASURES).map(([k, [label, tip]]) =>
        h("tr", {}, h("th", {}, label, " ", help(tip, "Csc")), h("td", {}, fmt(data.measures[k], 4))))),
      h("p", { class: "muted small" }, `${data.points.length} recordings · ${data.dims} Csc units · model ${data.model}`),
      h("h2", {}, "Explained variance ", help("Share of the patterns' variance along each principal component; the plot shows PC1 and PC2.", "PCA")),
      evPlot);
    await Plotly.newPlot(evPlot, [{ type: "bar", x: ev.map((_, i) => `PC${i + 1}`), y: ev.map((v) => 100 * v), marker: { color: ACCENT } }],
      baseLayout({ height: 220, yaxis: { title: "%" }, margin: { l: 40, r: 5, t: 10, b: 40 } }), CONFIG);
  }

  async function load() {
    const space = spaceSel.value;
    ctx.setParams({ space, colour: colourSel.value });
    about.textContent = SPACES[space][1];
    try {
      data = await get("/api/csc", { space });
      error.replaceChildren();
    } catch (e) {
      error.replaceChildren(errorBox(e.message));
      return;
    }
    await drawPoints();
    await drawSide();
  }

  spaceSel.addEventListener("change", load);
  colourSel.addEventListener("change", () => { ctx.setParams({ colour: colourSel.value }); if (data) drawPoints(); });
  await load();
}
