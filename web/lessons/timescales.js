// Lesson 1: timescales. A leaky integrator (eq. 3) answering a pulse, then MTRNN_a's real IO, Cf
// and Cs activity over time for one utterance, with one time cursor shared by the three layers.

import { get } from "../js/api.js";
import { h, errorBox } from "../js/dom.js";
import { NEUTRAL, OKABE_ITO, SEQUENTIAL } from "../js/palette.js";
import { plotly, chart, cursorShape } from "../js/plots.js";
import { control, controls, prose, tryThis, latest, slider, num, sceneSelect } from "./common.js";

export const intro = [
  "Every neuron of an MTRNN is a leaky integrator: at each step its internal state z moves only a fraction 1/τ of the way towards its new input. A unit with a small timescale τ follows its input almost at once; a unit with a large τ changes slowly and remembers what happened long ago.",
  { equation: "z_t,i = (1 − 1/τ_i) · z_t−1,i + (1/τ_i) · ( Σ_j w_ij x_t,j + b_i )", tag: "eq. (3)" },
  "Below, one unit gets a pulse of input (10 steps of 1). Move τ and watch how fast it charges and how long it takes to forget. The faint curves are MTRNN_a's three layers (Table 1): IO τ = 2, Cf τ = 5, Cs τ = 70.",
];

export async function render(root, ctx, index) {
  const Plotly = await plotly();
  const tau = slider("tau", 1, 100, 1, Number(ctx.params.tau || 5));
  const tauValue = h("span", { class: "value", id: "tau-value" }, tau.value);
  const scene = sceneSelect(ctx, index);
  const time = slider("time", 0, 59, 1, Number(ctx.params.t || 0));
  const timeValue = h("span", { class: "value", id: "time-value" }, time.value);
  const phonemeNow = h("span", { class: "phoneme-now", id: "phoneme-now" }, "–");
  const pulseReadout = h("div", { class: "readout", id: "pulse-readout" });
  const saidReadout = h("div", { class: "readout", id: "said" });
  const speedReadout = h("div", { class: "readout", id: "speeds" });
  const error = h("div");
  const pulsePlot = h("div", { class: "plot", id: "pulse-plot", style: "height:300px" });
  const layerPlots = ["IO", "Cf", "Cs"].map((name) => h("div", { class: "plot", id: `layer-${name}`, style: "height:300px" }));
  let pulse = null;
  let activity = null;

  root.append(
    controls(control(ctx, "tau", "τ", tau, "The unit's timescale. τ = 1: no memory at all, the state is the input. Large τ: slow, long memory.", "timescale"), tauValue),
    pulseReadout, pulsePlot,
    prose(["The same rule runs in the trained auditory network MTRNN_a while it speaks. Pick a scene: the model perceives it, the cell assemblies set the slow context c_a,0, and MTRNN_a produces phonemes. The IO layer (τ = 2) flickers with every phoneme, Cf (τ = 5) carries syllables and words, Cs (τ = 70) barely moves: it holds the whole sentence."]),
    controls(
      control(ctx, "scene", "scene", scene, "The recording the model describes. Its perception sets c_a,0; the heatmaps show MTRNN_a producing the utterance.", "Csc"),
      control(ctx, "time", "time step", time, "The shared time cursor: the red line in all three layers and the phoneme being produced at that step.", "phoneme"),
      timeValue, h("span", { class: "field" }, "producing ", phonemeNow)),
    saidReadout, speedReadout, error,
    h("div", { class: "grid3" }, layerPlots),
    tryThis(ctx, "Set τ to 70, the timescale of MTRNN_a's Cs layer. How many steps does the unit need to forget half of the pulse, and how does that compare with the length of an utterance? Then compare how fast the three real layers change.",
      () => {
        if (!pulse || !activity) return [h("p", {}, "Wait for the plots to load.")];
        const L = activity.layers;
        return [
          h("p", {}, `At τ = ${pulse.tau} the half-life is ${num(pulse.half_life_steps, 1)} steps and ${num(100 * pulse.left_after_20_steps, 0)} % of the charge is still there 20 steps after the pulse. An utterance here lasts ${activity.steps} steps, so a τ = 70 unit keeps what it was set to for the whole sentence: it is a context, not a detail.`),
          h("p", {}, `In the model served now (${activity.model}) the mean change per step is IO ${num(L.IO.speed, 4)}, Cf ${num(L.Cf.speed, 4)}, Cs ${num(L.Cs.speed, 4)}; from fastest to slowest: ${["IO", "Cf", "Cs"].sort((a, b) => L[b].speed - L[a].speed).join(", ")}. Whatever the weights, eq. (3) caps how fast a unit can move: at most 1/τ of the way per step. In a trained network the layers use that room as the paper describes: IO switches with every phoneme, Cs holds the concept of the sentence. (An untrained network barely moves at all, so its order says little.)`),
        ];
      }));

  function drawPulse() {
    const x = pulse.z.map((_, i) => i);
    const refs = Object.entries(pulse.references).map(([name, z]) => ({
      x, y: z, name: `${name} τ=${{ IO: 2, Cf: 5, Cs: 70 }[name]}`, mode: "lines", line: { width: 1, dash: "dot" }, opacity: 0.6 }));
    chart(pulsePlot, [
      { x, y: pulse.input, name: "input x", mode: "lines", line: { color: NEUTRAL, shape: "hv" } },
      ...refs,
      { x, y: pulse.z, name: `z (τ = ${pulse.tau})`, mode: "lines", line: { color: OKABE_ITO.vermillion, width: 3 } },
    ], { title: `a leaky unit with τ = ${pulse.tau} answering a 10-step pulse (eq. 3)`, xaxis: { title: "time step" },
      yaxis: { title: "internal state z", range: [0, 1.05] }, legend: { orientation: "h", y: -0.25 }, margin: { l: 60, r: 10, t: 40, b: 80 } });
    pulseReadout.replaceChildren(
      h("span", {}, "half-life: ", h("b", { id: "half-life" }, pulse.half_life_steps === null ? "none (τ = 1 forgets at once)" : `${num(pulse.half_life_steps, 1)} steps`)),
      h("span", {}, "peak: ", h("b", {}, num(pulse.peak))),
      h("span", {}, "left 20 steps after the pulse: ", h("b", {}, `${num(100 * pulse.left_after_20_steps, 1)} %`)));
  }

  function drawLayers() {
    const t = Number(time.value);
    ["IO", "Cf", "Cs"].forEach((name, k) => {
      const layer = activity.layers[name];
      const trace = { z: layer.y, type: "heatmap", colorscale: SEQUENTIAL, zmin: name === "IO" ? 0 : -0.36, zmax: name === "IO" ? 1 : 1.36, showscale: k === 2,
        colorbar: { title: "activity y" } };
      if (name === "IO") trace.y = activity.phoneme_labels;
      chart(layerPlots[k], [trace], {
        title: { text: `${name} (τ = ${layer.tau}), change/step ${num(layer.speed, 4)}`, font: { size: 13 } },
        xaxis: { title: "time step" }, yaxis: { title: name === "IO" ? "phoneme neuron" : `${name} unit`, tickfont: { size: 8 } },
        shapes: [cursorShape(t)], margin: { l: 50, r: 10, t: 40, b: 45 } });
    });
  }

  function moveCursor() {
    const t = Number(time.value);
    timeValue.textContent = t;
    ctx.setParams({ t });
    if (!activity) return;
    phonemeNow.textContent = activity.phoneme_at[t] || "–";
    layerPlots.forEach((p) => Plotly.relayout(p, { shapes: [cursorShape(t)] }));
  }

  const loadPulse = latest(async () => {
    tauValue.textContent = tau.value;
    ctx.setParams({ tau: tau.value });
    try {
      pulse = await get("/api/lessons/timescales/pulse", { tau: tau.value });
      drawPulse();
    } catch (e) { error.replaceChildren(errorBox(e.message)); }
  });

  const loadActivity = latest(async () => {
    ctx.setParams({ scene: scene.value });
    try {
      activity = await get("/api/lessons/timescales/activity", { scene: scene.value });
      error.replaceChildren();
    } catch (e) { error.replaceChildren(errorBox(e.message)); return; }
    time.max = activity.steps - 1;
    if (Number(time.value) > activity.steps - 1) time.value = activity.steps - 1;
    saidReadout.replaceChildren(
      h("span", {}, "teacher said: ", h("q", {}, activity.expected)),
      h("span", {}, "model says: ", h("q", { id: "said-text" }, activity.said || "(silence)")));
    speedReadout.replaceChildren(h("span", { class: "muted" }, `model ${activity.model} · phonemes: `, h("span", { class: "mono" }, activity.phonemes.join(" ") || "(none)")));
    drawLayers();
    moveCursor();
  });

  tau.addEventListener("input", loadPulse);
  scene.addEventListener("change", loadActivity);
  time.addEventListener("input", moveCursor);
  loadPulse();
  loadActivity();
  return null;
}
