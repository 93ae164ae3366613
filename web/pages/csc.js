// Csc explorer: PCA of the three Csc spaces over every corpus recording (paper Figs. 9-10).

import { get } from "../js/api.js";
import { h, field, help, errorBox, fmt } from "../js/dom.js";
import { ACCENT, BY, CURSOR, HIGHLIGHT, WHITE } from "../js/palette.js";
import { plotly, chart } from "../js/plots.js";

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

// Why d_rel reads 0 (eq. 15 multiplies the pairwise distances: one zero distance makes it 0).
function dRelNote(data) {
  if (!(data.measures.d_rel < 5e-5)) return null;
  const distinct = new Set(data.points.map((p) => `${p.x.toPrecision(6)},${p.y.toPrecision(6)}`)).size;
  return h("tr", {}, h("td", { colspan: 2, class: "note", id: "d-rel-note" },
    `d_rel is 0 because recordings share the very same pattern here: the ${data.points.length} recordings land on only ${distinct} distinct points, and eq. (15) multiplies all pairwise distances, so one zero distance makes the product 0. `,
    "In end_to_end the cell assemblies choose one word per slot (winner-take-all word units) and c_a,0 = E p + e, so c_a,0 takes one of 4 × 4 × 4 = 64 values: every recording described with the same words lands on the same pattern."));
}

// Every point as a link (the keyboard's way to open a scene); focusing one marks it in the plot.
function pointList(data, onFocus) {
  const items = data.points.map((p) => h("li", {}, h("a", { href: `#/scene/${p.id}`, class: "point-link",
    onfocus: () => onFocus(p), onmouseenter: () => onFocus(p) }, p.id), ` (${p.split}): the model says “${p.generated || "(silence)"}”`));
  return h("details", { class: "point-list", id: "csc-point-list" },
    h("summary", {}, `All ${data.points.length} points as a list (open a scene with the keyboard)`),
    h("ol", { id: "csc-points", class: "scroll-list", tabindex: 0, "aria-label": "Csc points" }, items));
}

export async function render(root, ctx) {
  const spaceSel = h("select", { id: "space" }, Object.entries(SPACES).map(([k, [label]]) =>
    h("option", { value: k, selected: k === ctx.params.space }, `${k}: ${label}`)));
  const colourSel = h("select", { id: "colour-by" }, COLOUR_BY.map((k) => h("option", { value: k, selected: k === ctx.params.colour }, k)));
  if (!SPACES[ctx.params.space]) spaceSel.value = "a";
  if (!COLOUR_BY.includes(ctx.params.colour)) colourSel.value = "action";
  const about = h("p", { class: "muted" });
  const plot = h("div", { class: "plot square", id: "csc-plot" });
  const side = h("div", { class: "side" });
  const list = h("div");
  const error = h("div");
  root.append(h("h1", {}, "Csc spaces"),
    h("p", { class: "lead" }, "Each point is one corpus recording: its Csc pattern, reduced to two dimensions by PCA (exact SVD). Hover for the scene, click to open it. Filled markers: training recordings; open markers: test (never seen)."),
    h("div", { class: "controls" },
      field("space", spaceSel, "Which network's context units to show: s = somatosensory (MTRNN_s), v = visual (MTRNN_v), a = auditory (MTRNN_a, after the cell assemblies).", "Csc"),
      field("colour by", colourSel, "Colour the points by the manipulation, the object's colour or its shape, to see what each space clusters by.", "Csc")),
    about, error,
    h("div", { class: "grid-plot" }, plot, side), list);

  const Plotly = await plotly();
  let data = null;
  let focusTrace = -1;
  async function drawPoints() {
    const colourBy = colourSel.value;
    const palette = BY[colourBy];
    const traces = Object.keys(palette).map((cat) => {
      const pts = data.points.filter((p) => p[colourBy] === cat)
        .sort((p, q) => (p.split === "test") - (q.split === "test")); // the legend shows a filled marker
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
    focusTrace = traces.length;
    traces.push({ type: "scatter", mode: "markers", name: "focused", x: [], y: [], showlegend: false, hoverinfo: "skip",
      marker: { size: 20, symbol: "circle-open", color: CURSOR, line: { width: 3, color: CURSOR } } });
    const ev = data.explained_variance_ratio;
    await chart(plot, traces, { height: 560, hovermode: "closest",
      title: `${SPACES[spaceSel.value][0]} of ${data.points.length} recordings, first two principal components`,
      legend: { title: { text: `${colourBy} (open: test)` }, bgcolor: WHITE },
      xaxis: { title: `PC1 (${(100 * ev[0]).toFixed(1)} % of the variance)`, zeroline: false },
      yaxis: { title: `PC2 (${(100 * (ev[1] ?? 0)).toFixed(1)} % of the variance)`, zeroline: false } });
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
        [h("tr", {}, h("th", {}, label, " ", help(tip, "Csc")), h("td", {}, fmt(data.measures[k], 4))),
          k === "d_rel" ? dRelNote(data) : null])),
      h("p", { class: "muted small" }, `${data.points.length} recordings · ${data.dims} Csc units · model ${data.model}`),
      h("h2", {}, "Explained variance ", help("Share of the patterns' variance along each principal component; the plot shows PC1 and PC2.", "PCA")),
      evPlot);
    await chart(evPlot, [{ type: "bar", name: "explained variance", x: ev.map((_, i) => `PC${i + 1}`), y: ev.map((v) => 100 * v), marker: { color: ACCENT } }],
      { height: 240, title: "variance per principal component", xaxis: { title: "principal component" },
        yaxis: { title: "% of the variance" }, margin: { l: 50, r: 5, t: 40, b: 45 } });
    list.replaceChildren(pointList(data, (p) => Plotly.restyle(plot, { x: [[p.x]], y: [[p.y]] }, [focusTrace])));
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
