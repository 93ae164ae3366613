// The live description under the shared time cursor (GET /api/scenes/{id}/timeline): what the
// model would say if asked at each step of the recording, as a strip of the utterances in turn
// ("at 1.20 s: push the red apple." … "at 2.40 s: slide the red apple."), the one at the cursor
// highlighted, and for end_to_end models each slot's word-unit probabilities as lines.
// Every utterance of the strip is a button: Enter or a click moves the cursor there.

import { get } from "./api.js";
import { h, help, errorBox } from "./dom.js";
import { ACCENT, BY, CATEGORICAL, CURSOR, WHITE } from "./palette.js";
import { chart, cursorShape, plotly } from "./plots.js";

const DASH = ["solid", "dash", "dot", "dashdot"]; // one per slot, so the lines differ without colour

// the utterance at the cursor: the page's accent, framed in the cursor's colour
const SEGMENT = "margin: .15rem; padding: .15rem .45rem; border-radius: 4px; font: inherit;";
const IDLE = `${SEGMENT} background: ${WHITE}; color: ${ACCENT}; border: 1px solid ${ACCENT};`;
const NOW = `${SEGMENT} background: ${ACCENT}; color: ${WHITE}; border: 1px solid ${CURSOR}; box-shadow: 0 0 0 2px ${CURSOR}; font-weight: 700;`;

// Runs of equal utterances: [{ step, t, text }] where each starts.
function segments(timeline) {
  const out = [];
  timeline.utterance.forEach((text, step) => {
    if (step === 0 || text !== timeline.utterance[step - 1]) out.push({ step, t: timeline.t[step], text });
  });
  return out;
}

const seconds = (t) => `${t.toFixed(2)} s`;

function settlesLine(timeline) {
  const slots = Object.entries(timeline.settles.slots);
  const parts = slots.length
    ? slots.map(([slot, s]) => `${slot} “${s.word}” at ${seconds(s.t)}`)
    : timeline.settles.words.map((s) => `“${s.word}” at ${seconds(s.t)}`);
  return h("p", { class: "small", id: "timeline-settles" }, "settles for good: ", parts.join(" · "));
}

function slotTraces(timeline) {
  return Object.entries(timeline.slots).flatMap(([slot, track], k) => track.words.map((word, j) => ({
    x: timeline.t, y: track.probability[j], name: word, mode: "lines", legendgroup: slot,
    legendgrouptitle: { text: slot }, line: { color: BY[slot]?.[word] ?? CATEGORICAL[j % CATEGORICAL.length], dash: DASH[k % DASH.length] },
  })));
}

const plotLayout = (t) => ({
  title: { text: "Word-unit probabilities at each step (what each slot would say)" },
  height: 440,
  xaxis: { title: { text: "time (s)" } },
  yaxis: { title: { text: "probability" }, range: [0, 1.02] },
  shapes: [cursorShape(t)],
  legend: { orientation: "v", tracegroupgap: 6 },
});

// Mounts the timeline of recording `id` into `box`; `seek(t)` moves the shared cursor.
// Returns { follow(t, playing) }, to be called whenever the cursor moves.
export async function mountTimeline(box, id, seek, t0 = 0) {
  box.append(h("h2", {}, "What the model would say, step by step ",
    help("At every step the model is asked what it would say if the recording ended there: the Csc states of MTRNN_s and MTRNN_v at that step go through the cell assemblies to c_a,0 and MTRNN_a speaks from it. The slow context units settle as they read; a word settles for good at the step from which it no longer changes. Click an utterance (or press Enter on it) to move the cursor there.", "cell assembly")));
  let timeline;
  try {
    timeline = await get(`/api/scenes/${id}/timeline`);
  } catch (e) {
    box.append(errorBox(`No timeline: ${e.message}`));
    return { follow() {} };
  }
  const runs = segments(timeline);
  const buttons = runs.map((run) => h("button", { type: "button", style: IDLE, "data-step": run.step,
    onclick: () => seek(run.t) }, `at ${seconds(run.t)}: ${run.text || "(silence)"}`));
  const now = h("q", { id: "timeline-now" }, "");
  box.append(
    h("p", {}, "at the cursor the model would say ", now),
    h("div", { id: "timeline-strip", role: "group", "aria-label": "what the model would say, in turn", style: "display: flex; flex-wrap: wrap;" }, buttons),
    settlesLine(timeline));
  const plot = h("div", { class: "plot", id: "timeline-plot" });
  const traces = slotTraces(timeline);
  if (traces.length) {
    box.append(plot);
    await plotly();
    await chart(plot, traces, plotLayout(t0));
  } else {
    box.append(h("p", { class: "muted small" }, "This model's cell assemblies have no word units (the paper's linear CAs), so there are no slot probabilities to draw."));
  }

  let shown = -1, lastPlot = 0;
  function follow(t, playing = false) {
    const step = Math.max(0, Math.min(Math.round(t * timeline.fps), timeline.utterance.length - 1));
    let k = runs.length - 1;
    while (k > 0 && runs[k].step > step) k--;
    if (k !== shown) {
      if (shown >= 0) { buttons[shown].style.cssText = IDLE; buttons[shown].removeAttribute("aria-current"); }
      buttons[k].style.cssText = NOW;
      buttons[k].setAttribute("aria-current", "step");
      now.textContent = timeline.utterance[step] || "(silence)";
      shown = k;
    }
    const time = performance.now();
    if (traces.length && (!playing || time - lastPlot > 150)) {
      lastPlot = time;
      window.Plotly.relayout(plot, { shapes: [cursorShape(t)] });
    }
  }
  follow(t0);
  return { follow };
}
