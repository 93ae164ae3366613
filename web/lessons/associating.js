// Lesson 6: associating. The three Csc spaces side by side (Fig. 10); mute vision or
// proprioception and read what the model says instead: the cell assemblies resolve ambiguity.

import { get } from "../js/api.js";
import { h, errorBox } from "../js/dom.js";
import { BY, CURSOR, HIGHLIGHT, WHITE } from "../js/palette.js";
import { plotly, chart } from "../js/plots.js";
import { control, controls, tryThis, latest, select, num, sceneSelect } from "./common.js";

const TITLES = { s: "somatosensory c_s,T (touch)", v: "visual c_v,T (sight)", a: "auditory c_a,0 (cell assemblies → speech)" };

export const intro = [
  "Each sense abstracts a recording into its own context: MTRNN_s into c_s,T (12 numbers), MTRNN_v into c_v,T. The cell assemblies, one layer of dense associations, map the two onto the auditory context c_a,0 that starts the utterance. Below, every corpus recording is a dot in each of the three spaces (first two principal components, Fig. 10); the star is the recording you picked. Colour the dots by action, colour or shape and see which space separates what.",
  { equation: "c_a,0,i = z_i = Σ_j w_ij f(c_s,T,j) + Σ_k w_ik f(c_v,T,k) + b_i", tag: "eq. (17)" },
  "Mute a sense: its context is replaced by its mean over the corpus, so the assemblies get nothing specific from it. The diamond shows where c_a,0 lands then, and the model says what it makes of the remaining sense.",
];

export async function render(root, ctx, index) {
  await plotly();
  const scene = sceneSelect(ctx, index);
  const mute = select("mute", [["none", "nothing"], ["vision", "vision"], ["proprioception", "proprioception"]], ctx.params.mute || "none");
  const colourBy = select("colour-by", ["action", "colour", "shape"], ctx.params.by || "action");
  const said = h("div", { class: "utterances", id: "assoc-said" });
  const error = h("div", { id: "assoc-error" });
  const plots = ["s", "v", "a"].map((s) => h("div", { class: "plot", id: `space-${s}`, style: "height:380px" }));
  let data = null;

  root.append(
    controls(
      control(ctx, "scene", "scene", scene, "The recording to follow through the three spaces.", "Csc"),
      control(ctx, "mute", "mute", mute, "Silence one sense: replace its Csc pattern by the corpus mean before the cell assemblies.", "cell assembly"),
      control(ctx, "by", "colour by", colourBy, "Colour the dots by the scene's action, object colour or shape.", "PCA")),
    error, said,
    h("div", { class: "grid3" }, plots),
    tryThis(ctx, "Pick a scene the model describes correctly, then mute vision. Which words survive? Then mute proprioception instead.",
      () => {
        if (!data) return [h("p", {}, "Wait for the spaces to load.")];
        const lost = Object.entries(data.slots).filter(([, v]) => v.said !== v.expected).map(([k]) => k);
        return [
          h("p", {}, `With ${data.mute === "none" ? "nothing" : data.mute} muted the model says “${data.said || "(silence)"}” for “${data.expected}”: ${lost.length ? `the ${lost.join(", ")} slot${lost.length > 1 ? "s are" : " is"} wrong or missing` : "every slot is right"}.`),
          h("p", {}, "What to expect from the paper (4.1, 4.4): vision carries colour and shape but no motion, proprioception carries the action but is mostly ambiguous about the object. So with vision muted the action word should survive while colour and shape become a guess, and the reverse with proprioception muted. Neither sense holds the whole sentence; only the association of both contexts in c_a,0 does. That is where the ambiguity of each sense is resolved. Check it against the slots above: a poorly trained model may not follow the script."),
        ];
      }));

  function draw() {
    const by = colourBy.value;
    const palette = BY[by];
    const groups = [...new Set(data.labels.map((l) => l[by]))];
    ["s", "v", "a"].forEach((space, k) => {
      const sp = data.spaces[space];
      const traces = groups.map((g) => {
        const idx = data.labels.map((l, i) => (l[by] === g ? i : -1)).filter((i) => i >= 0)
          .sort((i, j) => (data.labels[i].split === "test") - (data.labels[j].split === "test")); // legend shows a filled dot
        return { x: idx.map((i) => sp.x[i]), y: idx.map((i) => sp.y[i]), mode: "markers", name: g, showlegend: k === 0, legendgroup: g,
          text: idx.map((i) => `${data.labels[i].id} (${data.labels[i].split})`), hoverinfo: "text",
          marker: { size: 7, color: palette[g], opacity: 0.75, symbol: idx.map((i) => (data.labels[i].split === "test" ? "circle-open" : "circle")) } };
      });
      traces.push({ x: [sp.x[data.index]], y: [sp.y[data.index]], mode: "markers", name: "picked", showlegend: k === 0,
        marker: { size: 18, symbol: "star", color: HIGHLIGHT, line: { color: WHITE, width: 1 } }, hoverinfo: "skip" });
      if (space === "a" && data.mute !== "none") {
        traces.push({ x: [sp.x[data.index], data.point_a[0]], y: [sp.y[data.index], data.point_a[1]], mode: "lines+markers", name: `${data.mute} muted`,
          marker: { size: [0, 15], symbol: "diamond", color: CURSOR }, line: { color: CURSOR, dash: "dot" }, showlegend: true });
      }
      chart(plots[k], traces, {
        title: { text: `${TITLES[space]}`, font: { size: 13 } },
        xaxis: { title: { text: `PC1 (${(100 * sp.explained[0]).toFixed(1)} %)` }, zeroline: false },
        yaxis: { title: { text: `PC2 (${(100 * (sp.explained[1] ?? 0)).toFixed(1)} %)` }, zeroline: false },
        legend: { orientation: "h", y: -0.3, title: { text: by } }, margin: { l: 55, r: 10, t: 40, b: 50 } });
    });
  }

  function showSaid() {
    const slot = (k) => {
      const v = data.slots[k];
      return h("span", { class: v.said === v.expected ? "ok" : "bad" }, `${k}: ${v.said ?? "?"}`);
    };
    said.replaceChildren(...[
      h("div", { class: "said" }, h("span", { class: "label" }, "teacher said"), h("q", {}, data.expected)),
      h("div", { class: "said" }, h("span", { class: "label" }, "model says (both senses)"), h("q", { id: "said-unmuted" }, data.unmuted || "(silence)")),
      h("div", { class: "said big" }, h("span", { class: "label" }, data.mute === "none" ? "model says" : `model says with ${data.mute} muted`),
        h("q", { id: "said-muted" }, data.said || "(silence)"), " ", slot("action"), " ", slot("colour"), " ", slot("object")),
      data.mute === "none" ? null : h("div", { class: "small" }, "muting moved c_a,0 by ", h("b", { id: "moved" }, num(data.moved, 4)), " in the auditory Csc space"),
      h("div", { class: "muted small" }, `nearest corpus pattern in c_a,0: ${data.nearest.id} (the model says “${data.nearest.said || "(silence)"}” there) · model ${data.model} · open dots: test scenes`),
    ].filter(Boolean));
  }

  const load = latest(async () => {
    ctx.setParams({ scene: scene.value, mute: mute.value, by: colourBy.value });
    try {
      data = await get("/api/lessons/associating", { scene: scene.value, mute: mute.value });
      error.replaceChildren();
    } catch (e) { error.replaceChildren(errorBox(e.message)); return; }
    showSaid();
    draw();
  });

  scene.addEventListener("change", load);
  mute.addEventListener("change", load);
  colourBy.addEventListener("change", () => { ctx.setParams({ by: colourBy.value }); if (data) draw(); });
  load();
  return null;
}
