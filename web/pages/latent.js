// Latent explorer: click anywhere on the auditory Csc plane and read what the robot would say there.

import { get, post } from "../js/api.js";
import { h, field, help, errorBox, fmt, answerOrError } from "../js/dom.js";
import { ACTION_SYMBOLS, COLOUR_COLOURS, HIGHLIGHT, NEUTRAL, WHITE } from "../js/palette.js";
import { plotly, chart } from "../js/plots.js";

export const meta = { route: "latent", title: "Latent explorer", order: 40,
  description: "what would the robot say here? generate from any point of the auditory Csc plane" };

export async function render(root, ctx) {
  const plot = h("div", { class: "plot square", id: "latent-plot" });
  const said = h("q", { id: "latent-utterance" }, "click the plane");
  const info = h("div", { class: "muted small", id: "latent-info" });
  const history = h("ol", { class: "history", id: "latent-history", tabindex: 0, "aria-label": "points clicked so far" });
  const px = h("input", { type: "number", id: "latent-x", step: "any", "aria-label": "PC1" });
  const py = h("input", { type: "number", id: "latent-y", step: "any", "aria-label": "PC2" });
  const go = h("button", { type: "submit", id: "latent-go" }, "say it");
  const typed = h("form", { class: "controls", id: "latent-form" },
    field("PC1", px, "Type a point instead of clicking: its first principal component.", "PCA"),
    field("PC2", py, "Its second principal component; then press Enter or “say it”.", "PCA"), go);
  root.append(h("h1", {}, "Latent explorer ", help("The auditory Csc space c_a,0 reduced to its first two principal components. A click maps the point back to a full c_a,0 (the other components at the corpus mean: inverse PCA) and lets MTRNN_a speak from it.", "Csc")),
    h("p", { class: "lead" }, "The points are the corpus recordings (colour = object colour, symbol = manipulation). Click anywhere, also between the clusters, to hear what the generator composes there."),
    h("div", { class: "grid-plot" }, plot,
      h("div", { class: "side" }, h("h2", {}, "The robot says ", help("Decoded from MTRNN_a's output: phonemes -> nearest words of the lexicon.", "phoneme")),
        h("p", { class: "said big" }, said), info, typed, h("h2", {}, "Clicked so far"), history)));
  const data = await answerOrError(root, get("/api/csc", { space: "a" }));
  if (!data) return;
  const Plotly = await plotly();
  const xs = data.points.map((p) => p.x), ys = data.points.map((p) => p.y);
  const pad = (a) => { const lo = Math.min(...a), hi = Math.max(...a), d = (hi - lo || 1) * 0.25; return [lo - d, hi + d]; };
  const corpus = { type: "scatter", mode: "markers", name: "corpus", x: xs, y: ys,
    text: data.points.map((p) => `${p.id}<br>model: ${p.generated}`), hovertemplate: "%{text}<extra></extra>",
    marker: { size: 8, opacity: 0.55, color: data.points.map((p) => COLOUR_COLOURS[p.colour]), symbol: data.points.map((p) => ACTION_SYMBOLS[p.action]) } };
  const probe = { type: "scatter", mode: "markers", name: "probe", x: [], y: [], hoverinfo: "skip", showlegend: false,
    marker: { size: 16, symbol: "x", color: HIGHLIGHT } };
  // legend entries only: colour = object colour, symbol = manipulation
  const key = [...Object.entries(COLOUR_COLOURS).map(([name, color]) => ({ name, marker: { color, symbol: "circle", size: 9 } })),
    ...Object.entries(ACTION_SYMBOLS).map(([name, symbol]) => ({ name, marker: { color: NEUTRAL, symbol, size: 9 } }))]
    .map((t) => ({ type: "scatter", mode: "markers", x: [null], y: [null], hoverinfo: "skip", ...t }));
  await chart(plot, [{ ...corpus, showlegend: false }, probe, ...key], { height: 560, hovermode: "closest", dragmode: false,
    title: `auditory c_a,0 of ${data.points.length} recordings (PCA): click to generate`,
    legend: { title: { text: "colour: object colour · symbol: action" }, itemclick: false, itemdoubleclick: false, bgcolor: WHITE },
    xaxis: { title: "PC1 of c_a,0", range: pad(xs), zeroline: false }, yaxis: { title: "PC2 of c_a,0", range: pad(ys), zeroline: false } });

  async function speak(pcx, pcy) {
    const x = +pcx.toPrecision(6), y = +pcy.toPrecision(6); // what the URL keeps
    px.value = x; py.value = y;
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
    const cx = ev.clientX - r.left, cy = ev.clientY - r.top;
    if (cx < 0 || cy < 0 || cx > r.width || cy > r.height) return;
    speak(layout.xaxis.p2c(cx), layout.yaxis.p2c(cy));
  });
  typed.addEventListener("submit", (ev) => {
    ev.preventDefault();
    if (px.value !== "" && py.value !== "") speak(Number(px.value), Number(py.value));
  });
  if (ctx.params.x !== undefined && ctx.params.y !== undefined) speak(Number(ctx.params.x), Number(ctx.params.y));
}
