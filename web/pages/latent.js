// Latent explorer: click anywhere on the auditory Csc plane and read what the robot would say there.

import { get, post } from "../js/api.js";
import { h, help, errorBox, fmt, answerOrError } from "../js/dom.js";
import { ACTION_SYMBOLS, COLOUR_COLOURS, HIGHLIGHT } from "../js/palette.js";
import { plotly, CONFIG, baseLayout } from "../js/plots.js";

export const meta = { route: "latent", title: "Latent explorer", order: 40,
  description: "what would the robot say here? generate from any point of the auditory Csc plane" };

export async function render(root, ctx) {
  const plot = h("div", { class: "plot square", id: "latent-plot" });
  const said = h("q", { id: "latent-utterance" }, "click the plane");
  const info = h("div", { class: "muted small", id: "latent-info" });
  const history = h("ol", { class: "history", id: "latent-history" });
  root.append(h("h1", {}, "Latent explorer ", help("The auditory Csc space c_a,0 reduced to its first two principal components. A click maps the point back to a full c_a,0 (the other components at the corpus mean: inverse PCA) and lets MTRNN_a speak from it.", "Csc")),
    h("p", { class: "lead" }, "The points are the corpus recordings (colour = object colour, symbol = manipulation). Click anywhere, also between the clusters, to hear what the generator composes there."),
    h("div", { class: "grid-plot" }, plot,
      h("div", { class: "side" }, h("h2", {}, "The robot says ", help("Decoded from MTRNN_a's output: phonemes -> nearest words of the lexicon.", "phoneme")),
        h("p", { class: "said big" }, said), info, h("h2", {}, "Clicked so far"), history)));
  const data = await answerOrError(root, get("/api/csc", { space: "a" }));
  if (!data) return;
  const Plotly = await plotly();
  const xs = data.points.map((p) => p.x), ys = data.points.map((p) => p.y);
  const pad = (a) => { const lo = Math.min(...a), hi = Math.max(...a), d = (hi - lo || 1) * 0.25; return [lo - d, hi + d]; };
  const corpus = { type: "scatter", mode: "markers", name: "corpus", x: xs, y: ys,
    text: data.points.map((p) => `${p.id}<br>model: ${p.generated}`), hovertemplate: "%{text}<extra></extra>",
    marker: { size: 8, opacity: 0.55, color: data.points.map((p) => COLOUR_COLOURS[p.colour]), symbol: data.points.map((p) => ACTION_SYMBOLS[p.action]) } };
  const probe = { type: "scatter", mode: "markers", name: "probe", x: [], y: [], hoverinfo: "skip",
    marker: { size: 16, symbol: "x", color: HIGHLIGHT } };
  await Plotly.newPlot(plot, [corpus, probe], baseLayout({ height: 560, hovermode: "closest", showlegend: false, dragmode: false,
    xaxis: { title: "PC1", range: pad(xs), zeroline: false }, yaxis: { title: "PC2", range: pad(ys), zeroline: false } }), CONFIG);

  async function speak(px, py) {
    const x = +px.toPrecision(6), y = +py.toPrecision(6); // what the URL keeps
    ctx.setParams({ x: String(x), y: String(y) });
    Plotly.restyle(plot, { x: [[x]], y: [[y]] }, [1]);
    said.textContent = "…";
    try {
      const g = await post("/api/csc/generate", { point: [x, y] });
      said.textContent = g.utterance || "(silence)";
      info.textContent = `PC1 ${fmt(x)}, PC2 ${fmt(y)} · nearest recording ${g.nearest.id} (says "${g.nearest.utterance}")`;
      history.prepend(h("li", {}, `(${fmt(x, 2)}, ${fmt(y, 2)}): ${g.utterance || "(silence)"}`));
    } catch (e) {
      said.textContent = "";
      info.replaceChildren(errorBox(e.message));
    }
  }
  // Clicks anywhere in the plotting area, not only on points: pixel -> data coordinates.
  plot.addEventListener("click", (ev) => {
    const layout = plot._fullLayout;
    const area = plot.querySelector(".nsewdrag") || plot.querySelector(".draglayer");
    if (!layout || !area) return;
    const r = area.getBoundingClientRect();
    const px = ev.clientX - r.left, py = ev.clientY - r.top;
    if (px < 0 || py < 0 || px > r.width || py > r.height) return;
    speak(layout.xaxis.p2c(px), layout.yaxis.p2c(py));
  });
  if (ctx.params.x !== undefined && ctx.params.y !== undefined) speak(Number(ctx.params.x), Number(ctx.params.y));
}
