// Lesson 2: speaking in phonemes. Text -> ARPAbet -> Gaussian spikes -> softmax (eqs. 18-21,
// Fig. 6 and 8a), the four encoding constants on sliders, and the decoder reading it back.

import { get } from "../js/api.js";
import { h, errorBox } from "../js/dom.js";
import { plotly, chart } from "../js/plots.js";
import { SEQUENTIAL } from "../js/palette.js";
import { control, controls, tryThis, latest, slider, num } from "./common.js";

export const intro = [
  "The robot speaks in phonemes, the sounds of the ARPAbet (from the CMU pronouncing dictionary), plus SIL for a pause and PER, EXM, QUM for the end of a sentence: the alphabet B, one output neuron each. A sentence becomes a train of spikes, one phoneme every ν steps after a head margin γ; each spike is a small Gaussian of width ω and sharpness σ² that primes its neighbours in time.",
  { equation: "g(p_k, t_rel, i) = exp(−t_rel² / 2σ²)  if p_k = B_i,   t = γ + kν + t_rel,   t_rel ∈ [−ω/2, ω/2]", tag: "eqs. (18)-(19)" },
  { equation: "y*_t,i = exp(λ·g_t,i) / Σ_j exp(λ·g_t,j),   λ = ln( 0.9/(1 − 0.9) · (|B| − 1) )", tag: "eqs. (20)-(21)" },
  "Type a sentence (any words the CMU dictionary knows), move the four constants and watch both the spikes and the softmax activity that MTRNN_a learns to produce. The decoder reads the activity back: one phoneme per run of steps where the same neuron wins with activity ≥ 0.3.",
];

export async function render(root, ctx) {
  await plotly();
  const text = h("input", { type: "text", id: "utterance", value: ctx.params.text || "slide the red apple." });
  const params = {
    gamma: slider("gamma", 0, 12, 1, ctx.params.gamma ?? 4),
    omega: slider("omega", 0, 12, 2, ctx.params.omega ?? 4),
    sigma2: slider("sigma2", 0.05, 4, 0.05, ctx.params.sigma2 ?? 0.3),
    nu: slider("nu", 1, 8, 1, ctx.params.nu ?? 2),
  };
  const values = Object.fromEntries(Object.entries(params).map(([k, el]) => [k, h("span", { class: "value", id: `${k}-value` }, el.value)]));
  const out = h("div", { class: "readout", id: "speech-readout" });
  const error = h("div", { id: "speech-error" });
  const spikePlot = h("div", { class: "plot", id: "spike-plot", style: "height:340px" });
  const softPlot = h("div", { class: "plot", id: "softmax-plot", style: "height:340px" });
  let speech = null;

  root.append(
    controls(
      control(ctx, "text", "sentence", text, "Words the CMU pronouncing dictionary knows; . ! ? end a sentence.", "phoneme"),
      control(ctx, "gamma", "γ", params.gamma, "Head margin: empty steps before the first phoneme slot.", null), values.gamma,
      control(ctx, "omega", "ω", params.omega, "Filter width: each spike spreads over ω+1 steps (ω even).", null), values.omega,
      control(ctx, "sigma2", "σ²", params.sigma2, "Filter sharpness: a larger σ² gives wider, flatter spikes that overlap their neighbours.", null), values.sigma2,
      control(ctx, "nu", "ν", params.nu, "Steps between two phonemes.", null), values.nu),
    error, out,
    h("div", { class: "grid2" }, spikePlot, softPlot),
    tryThis(ctx, "Type “the bookkeeper.”: its K K is the same phoneme twice in a row. With the paper's constants (γ = 4, ω = 4, σ² = 0.3, ν = 2) the decoder reads both K's. Now set ν to 1, or σ² to 2. What happens, and why?",
      () => {
        if (!speech) return [h("p", {}, "Wait for the plots to load.")];
        const p = speech.params;
        return [
          h("p", {}, `Now (γ = ${p.gamma}, ω = ${p.omega}, σ² = ${num(p.sigma2, 2)}, ν = ${p.nu}) ${speech.phonemes.length} phonemes are encoded and the decoder reads back ${speech.decoded.length}: “${speech.read_back || "(nothing)"}” ${speech.exact ? "(exact)" : "(phonemes lost)"}; the strongest activity is ${num(speech.peak)}.`),
          h("p", {}, "The decoder counts one phoneme per run of steps in which the same neuron wins above 0.3. Two different phonemes always separate, because the winner changes; the same phoneme twice only separates if the activity dips below 0.3 between its peaks. With ν = 2 and the sharp σ² = 0.3 the step between two slots is nearly empty, so it dips; with ν = 1 there is no step between, and with a wide σ² the two Gaussians fill the gap, so the two K's merge into one. Wide spikes also lower every peak below the 0.9 that λ (eq. 20) gives a lone spike: a softer target for MTRNN_a to learn."),
        ];
      }));

  function heat(el, z, title, zmax) {
    chart(el, [{ z, y: speech.labels, type: "heatmap", colorscale: SEQUENTIAL, zmin: 0, zmax, colorbar: { title: "activity" } }],
      { title: { text: title, font: { size: 13 } }, xaxis: { title: "time step of MTRNN_a" },
        yaxis: { title: "phoneme neuron", tickfont: { size: 10 }, autorange: "reversed" }, margin: { l: 60, r: 10, t: 40, b: 45 } });
  }

  const load = latest(async () => {
    const q = Object.fromEntries(Object.entries(params).map(([k, el]) => [k, el.value]));
    Object.entries(values).forEach(([k, el]) => { el.textContent = q[k]; });
    ctx.setParams({ text: text.value, ...q });
    try {
      speech = await get("/api/lessons/speaking", { text: text.value, ...q });
      error.replaceChildren();
    } catch (e) { error.replaceChildren(errorBox(e.message)); return; }
    out.replaceChildren(
      h("div", {}, "ARPAbet: ", h("span", { class: "mono", id: "arpabet" }, speech.phonemes.join(" "))),
      h("div", {}, "decoded: ", h("span", { class: "mono", id: "decoded" }, speech.decoded.join(" ") || "(nothing)")),
      h("div", {}, "read back: ", h("q", { id: "read-back" }, speech.read_back || "(nothing)"), " ",
        h("span", { class: speech.exact ? "ok" : "bad", id: "exact" }, speech.exact ? "✓ exact" : "✗ lost phonemes")),
      h("div", { class: "muted" }, `T_a = ${speech.steps} steps · λ = ${num(speech.lambda)} · peak activity ${num(speech.peak)}`));
    heat(spikePlot, speech.spikes, "Gaussian spikes g (eqs. 18-19)", 1);
    heat(softPlot, speech.activity, "softmax activity y* (eq. 21, Fig. 8a)", 1);
  }, 150);

  text.addEventListener("input", load);
  Object.values(params).forEach((el) => el.addEventListener("input", load));
  load();
  return null;
}
