// Lesson 5: abstracting. The cosine experiment of 3.2.2 (Fig. 3) run live for one psi: the Csc
// points of the four sequences move as they self-organise; d_avg, d_rel; the stored psi_s sweep.

import { get, post } from "../js/api.js";
import { h, errorBox } from "../js/dom.js";
import { CATEGORICAL, TRANSPARENT } from "../js/palette.js";
import { plotly, chart } from "../js/plots.js";
import { control, controls, tryThis, slider, select, num, hiddenSet } from "./common.js";

const PSIS = [0, 1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2];
const SEQ_COLOURS = CATEGORICAL.slice(0, 4); // the four phases

export const intro = [
  "How can a network find a concept for a sequence without being told what the concept is? The paper's MTRNN with context abstraction reads a sequence and ends with a pattern c_T in its slowest (Csc) units. Training pulls the network towards target patterns, but the targets themselves move too: a small share ψ of the error moves the targets, the rest (1 − ψ) trains the weights. This is self-organisation forcing.",
  { equation: "∂E/∂z_T,i = (1 − ψ) (y_T,i − f(c_T,i + b_i)) f′(z_T,i)     c_T,i ← c_T,i − ψ ζ_i ∂E/∂c_T,i", tag: "eqs. (11)-(12)" },
  "The test of 3.2.2: four sequences of two contrary cosines (33 steps) that differ only in phase; two Csc units, so the four concepts are points in a plane. Run it for a ψ: filled dots are the network's abstraction of each sequence (its Csc internal states at the last step), rings are the moving targets c_T (the network is pulled towards c_T plus its bias b, so dots settle near, not on, the rings). How well spread they end up is measured by d_avg (mean distance) and d_rel (geometric mean of distance / d_avg: 1 when all distances are equal; four points in a plane can reach at most 0.986).",
  { equation: "d_avg = mean over pairs of ‖c_k − c_l‖,     d_rel = ( Π_pairs ‖c_k − c_l‖ / d_avg )^(1 / #pairs)", tag: "eqs. (13)-(15)" },
  "The run learns by the paper's own rule: every weight by its adapted rate times its gradient (eqs. 7-9), and the targets at ζ = 30 × the mean rate of their unit's weights (eq. 10; 30 is the constant calibrated on this very figure). What ψ really does there, over 100 runs per ψ: it draws the four patterns together (d_avg 1.050 without forcing, 1.009 at ψ = 1e-5, 0.845 at 5e-5, 0.454 at 2e-4, the paper’s “degrading”), but it does not spread them more evenly (d_rel 0.882, 0.881, 0.880, 0.879, each within its standard error of 0.008), so the paper’s “good” peak is not reproduced. (10 runs per ψ had shown one, 0.901 → 0.914 at 5e-5: that was noise.) The same constant leaves the psi_s sweep of the full model flat (Fig. 9, docs/RESULTS.md). It is slow: 12,000-16,000 epochs to converge; the live run stops after 2,500, so it shows the first part of that self-organisation.",
];

export async function render(root, ctx) {
  await plotly();
  const start = PSIS.indexOf(Number(ctx.params.psi ?? 5e-5));
  const psi = slider("psi", 0, PSIS.length - 1, 1, start >= 0 ? start : 3);
  const psiValue = h("span", { class: "value", id: "psi-value" });
  const seed = h("input", { type: "number", id: "seed", min: 0, max: 10000, step: 1, value: Number(ctx.params.seed || 0) });
  const run = h("button", { type: "button", id: "run" }, "▶ run");
  const bar = h("div", {});
  const progress = h("span", { class: "progress", id: "progress", title: "epochs run / the live run's limit" }, bar);
  const status = h("span", { id: "run-status", class: "muted" }, "not run yet");
  const readout = h("div", { class: "readout", id: "cosine-readout" });
  const error = h("div", { id: "cosine-error" });
  const plot = h("div", { class: "plot square", id: "csc-plot", style: "min-height:440px" },
    h("p", { class: "muted", style: "padding:1rem" }, "Press run: the four sequences' Csc points will appear here and move as the network trains."));
  const history = h("tbody", { id: "run-history" });
  const sweepBox = h("section", { class: "panel", id: "sweep" });
  let job = null;
  let timer = null;
  const done = [];

  root.append(
    controls(
      control(ctx, "psi", "ψ", psi, "Self-organisation forcing: the share of the error that moves the targets c_T. The paper finds 5e-5 best for this task.", "psi"), psiValue,
      control(ctx, "seed", "seed", seed, "Initialisation of the network and the random starting targets (same seed, same start).", null),
      h("span", { class: "field", dataset: { control: "run" }, hidden: hiddenSet(ctx).has("run") }, run), progress, status),
    error, readout,
    h("div", { class: "grid2" }, plot,
      h("section", { class: "panel" }, h("h2", {}, "Your runs"),
        h("table", { class: "lesson-table" }, h("thead", {}, h("tr", {}, ["ψ", "seed", "epochs", "d_avg", "d_rel", "targets d_rel"].map((x) => h("th", {}, x)))), history))),
    sweepBox,
    tryThis(ctx, "Run ψ = 0 and then ψ = 1e-2 with the same seed. Which ends with the targets better spread (targets d_rel), and which needed fewer epochs? What does ψ = 0 mean for the targets?",
      () => {
        if (!done.length) return [h("p", {}, "Run the experiment at least once first.")];
        const rows = done.map((r) => `ψ = ${num(r.psi)}: ${r.result.epochs} epochs, d_rel ${num(r.result.d_rel)}, targets d_rel ${num(r.result.target_d_rel)}`);
        return [
          h("p", {}, "Your runs so far: ", rows.join("; "), "."),
          h("p", {}, "With ψ = 0 the targets never move: the random starting points are the concepts and the weights must fit them. With a small ψ the targets drift a little towards what the network can produce, which the paper found to spread the concepts better (its best, 5e-5); with a large ψ the targets chase the network's output and all sequences drift towards similar patterns (d_avg shrinks). On this easy task random targets are often already good (the paper says so too); the effect matters more with many sequences that share primitives, as in the robot corpus (see the ψ_s sweep)."),
        ];
      }));

  function showPsi() {
    psiValue.textContent = num(PSIS[Number(psi.value)]);
  }

  function drawFrames(frames, result) {
    const last = frames[frames.length - 1];
    if (!last) return;
    const all = frames.flatMap((f) => [...f.points, ...f.targets]).flat();
    const lo = Math.min(...all), hi = Math.max(...all), pad = 0.1 * (hi - lo || 1);
    const range = [lo - pad, hi + pad];
    const trails = [0, 1, 2, 3].map((k) => ({
      x: frames.map((f) => f.points[k][0]), y: frames.map((f) => f.points[k][1]), mode: "lines", showlegend: false,
      line: { color: SEQ_COLOURS[k], width: 1 }, opacity: 0.5, hoverinfo: "skip" }));
    const targets = { x: last.targets.map((p) => p[0]), y: last.targets.map((p) => p[1]), mode: "markers", name: "targets c_T (the net aims at c_T + b, eq. 11)",
      marker: { size: 16, color: TRANSPARENT, line: { width: 2, color: SEQ_COLOURS } } };
    const points = { x: last.points.map((p) => p[0]), y: last.points.map((p) => p[1]), mode: "markers+text", name: "abstracted c_T",
      text: ["phase 0", "phase π/2", "phase π", "phase 3π/2"], textposition: "top center",
      marker: { size: 11, color: SEQ_COLOURS } };
    if (!plot.classList.contains("js-plotly-plot")) plot.replaceChildren();
    chart(plot, [...trails, targets, points], {
      title: { text: `Csc space, epoch ${last.epoch}`, font: { size: 13 } },
      xaxis: { title: { text: "Csc unit 1 (internal state)" }, range }, yaxis: { title: { text: "Csc unit 2" }, range, scaleanchor: "x" },
      legend: { orientation: "h", y: -0.15 } });
    // while running: the latest snapshot; when done: the final abstraction (after the last epoch)
    const m = result ? { epoch: result.epochs, d_avg: result.d_avg, d_rel: result.d_rel, target_d_avg: result.target_d_avg, target_d_rel: result.target_d_rel } : last;
    readout.replaceChildren(...[
      h("span", {}, result ? "final, epoch " : "epoch ", h("b", { id: "epoch" }, m.epoch)),
      result ? null : h("span", {}, "error ", h("b", {}, num(last.error, 6))),
      h("span", {}, "d_avg ", h("b", { id: "d-avg" }, num(m.d_avg, 4))),
      h("span", {}, "d_rel ", h("b", { id: "d-rel" }, num(m.d_rel, 4))),
      h("span", {}, "targets: d_avg ", h("b", {}, num(m.target_d_avg, 4)), ", d_rel ", h("b", {}, num(m.target_d_rel, 4))),
      result ? h("span", { class: result.converged ? "ok" : "bad" }, result.converged ? `converged after ${result.epochs} epochs` : `stopped at the live limit of ${result.epochs} epochs before converging`) : null,
    ].filter(Boolean));
  }

  async function poll() {
    let frames = [];
    const tick = async () => {
      try {
        const s = await get(`/api/lessons/abstracting/runs/${job.id}`, { since: frames.length });
        frames = frames.concat(s.frames);
        bar.style.width = `${Math.round(100 * s.progress)}%`;
        status.textContent = s.status === "done" ? `done in ${num(s.seconds, 1)} s` : s.status === "failed" ? `failed: ${s.error}` : `${s.status}… epoch ${s.epoch} (${num(s.seconds, 1)} s)`;
        if (frames.length) drawFrames(frames, s.status === "done" ? s.result : null);
        if (s.status === "done" || s.status === "failed") {
          run.disabled = false;
          if (s.status === "done" && !done.some((r) => r.id === s.id)) {
            done.push(s);
            history.append(h("tr", {}, [num(s.psi), s.seed, s.result.epochs, num(s.result.d_avg, 4), num(s.result.d_rel, 4), num(s.result.target_d_rel, 4)].map((x) => h("td", { class: "num" }, x))));
          }
          return;
        }
      } catch (e) { error.replaceChildren(errorBox(e.message)); run.disabled = false; return; }
      timer = setTimeout(tick, 250);
    };
    await tick();
  }

  run.addEventListener("click", async () => {
    clearTimeout(timer);
    error.replaceChildren();
    const p = PSIS[Number(psi.value)];
    ctx.setParams({ psi: p, seed: seed.value });
    try {
      job = await post("/api/lessons/abstracting/runs", { psi: p, seed: Number(seed.value) });
    } catch (e) { error.replaceChildren(errorBox(e.message)); return; }
    run.disabled = true;
    bar.style.width = "0%";
    status.textContent = "starting…";
    poll();
  });
  psi.addEventListener("input", () => { showPsi(); ctx.setParams({ psi: PSIS[Number(psi.value)] }); });
  seed.addEventListener("change", () => ctx.setParams({ seed: seed.value }));
  showPsi();

  // The stored sweeps (model.sweep via the protocol's run store), if they have been run.
  try {
    const sweep = await get("/api/lessons/abstracting/sweep");
    sweepBox.append(h("h2", {}, "Stored sweeps: ψ_s on the robot corpus (Fig. 9) and ψ on the cosines (Fig. 3)"));
    const curve = (el, rows, xKey, name, title) => chart(el, [{ name,
      x: rows.map((r) => r[xKey] || 1e-6), y: rows.map((r) => r[name]), mode: "lines+markers",
      error_y: { type: "data", array: rows.map((r) => r[`${name}_sem`] ?? 0) } }],
    { title: { text: title, font: { size: 13 } }, xaxis: { title: `${xKey === "psi" ? "ψ" : "ψ_s"}${rows.some((r) => !r[xKey]) ? " (0 drawn at 1e-6)" : ""}`, type: "log" }, yaxis: { title: name } });
    if (sweep.psi_s.length) {
      // the measures with a standard error (not the paired comparisons with psi_s = 0)
      const row = sweep.psi_s[0];
      const names = Object.keys(row).filter((k) => `${k}_sem` in row && !k.includes("_vs_0"));
      const wanted = names.includes(ctx.params.metric) ? ctx.params.metric : names[0];
      const pick = select("sweep-metric", names, wanted);
      const sweepPlot = h("div", { class: "plot", id: "sweep-plot", style: "height:300px" });
      const runs = sweep.psi_s.reduce((n, r) => n + r.runs, 0);
      const draw = () => { ctx.setParams({ metric: pick.value }); curve(sweepPlot, sweep.psi_s, "psi_s", pick.value, `ψ_s sweep, ${runs} stored runs (mean ± standard error)`); };
      sweepBox.append(control(ctx, "metric", "measure", pick, "A measure of the stored ψ_s sweep: F1 and edit distance mixed over training and test, and the somatosensory Csc distances (Fig. 9).", "psi"), sweepPlot);
      pick.addEventListener("change", draw);
      draw();
    } else {
      sweepBox.append(h("p", { class: "muted", id: "sweep-missing" }, `ψ_s sweep: not there yet (${sweep.reason}; run the psi_s sweep).`));
    }
    if (sweep.cosine.length) {
      const cosPlot = h("div", { class: "plot", id: "cosine-sweep-plot", style: "height:300px" });
      sweepBox.append(cosPlot);
      curve(cosPlot, sweep.cosine, "psi", "d_rel", "cosine sweep: d_rel of the abstracted contexts over ψ (Fig. 3b)");
    } else {
      sweepBox.append(h("p", { class: "muted" }, "Cosine sweep (Fig. 3): not stored yet; the live run above is one run of it."));
    }
  } catch (e) { sweepBox.append(errorBox(e.message)); }
  return () => clearTimeout(timer);
}
