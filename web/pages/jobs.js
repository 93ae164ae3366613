// Jobs: start a training or an evaluation, watch it live (Server-Sent Events), cancel it, and
// serve a finished model.
//
// Live view: the loss per epoch of every training stage, and the PCA of the Csc patterns the
// current stage is shaping (c_0 of MTRNN_a, c_T of the encoders), redrawn at each progress event
// so the points can be seen self-organising. Jobs are kept by the server across restarts.

import { get, post, put, subscribe } from "../js/api.js";
import { h } from "../js/dom.js";
import { ACTION_COLOURS, colourOf } from "../js/palette.js";
import { plotly, CONFIG, baseLayout, groupPoints } from "../js/plots.js";

export const meta = { route: "jobs", title: "Jobs", order: 80,
  description: "train or evaluate models, watch them learn, serve a new model" };

const PRESETS = {
  quick: { label: "quick (about a minute)", overrides: {
    "training.epochs_auditory": 150, "training.epochs_somatosensory": 60,
    "training.epochs_visual": 60, "training.epochs_assemblies": 150 } },
  paper: { label: "Table 1 defaults (several minutes)", overrides: {} },
};
const EVENTS = ["snapshot", "progress", "run", "done", "error", "cancelled"];

function progressText(job) {
  const p = job.progress;
  if (!p) return "";
  if (p.type === "run") return `${p.done}/${p.total} runs`;
  if (p.epoch !== undefined) return `${p.stage} ${p.epoch}/${p.epochs}, loss ${Number(p.loss).toFixed(4)}`;
  return "";
}

export async function render(root, ctx) {
  const Plotly = await plotly();
  let source = null;
  let watched = null;
  let refreshTimer = null;

  const kind = h("select", { name: "kind", "aria-label": "job kind" },
    h("option", { value: "train" }, "train one model"), h("option", { value: "evaluate" }, "evaluate (K folds × N inits)"));
  const mode = h("select", { name: "mode", "aria-label": "training mode" },
    ["end_to_end", "faithful", "peer"].map((m) => h("option", { value: m }, m)));
  const fold = h("input", { name: "fold", type: "number", min: 0, value: 0, size: 3 });
  const seed = h("input", { name: "seed", type: "number", min: 0, value: 0, size: 3 });
  const folds = h("input", { name: "folds", type: "number", min: 1, max: 10, value: 2, size: 3 });
  const inits = h("input", { name: "inits", type: "number", min: 1, max: 10, value: 1, size: 3 });
  const preset = h("select", { name: "preset", "aria-label": "epoch budget" },
    Object.entries(PRESETS).map(([k, v]) => h("option", { value: k }, v.label)));
  const name = h("input", { name: "name", placeholder: "model name (optional)" });
  const message = h("p", { class: "muted", id: "job-message" });
  const start = h("button", { type: "submit", id: "start-job" }, "Start");
  const trainOnly = [h("label", { class: "field" }, "fold ", fold), h("label", { class: "field" }, "name ", name)];
  const evalOnly = [h("label", { class: "field" }, "folds ", folds), h("label", { class: "field" }, "inits ", inits)];
  function syncKind() {
    trainOnly.forEach((el) => { el.hidden = kind.value !== "train"; });
    evalOnly.forEach((el) => { el.hidden = kind.value !== "evaluate"; });
    [...mode.options].forEach((o) => { o.disabled = kind.value === "train" && o.value === "peer"; });
    if (mode.selectedOptions[0].disabled) mode.value = "end_to_end";
  }
  kind.addEventListener("change", syncKind);
  const form = h("form", { class: "controls", id: "job-form" },
    h("label", { class: "field" }, "job ", kind), h("label", { class: "field" }, "mode ", mode),
    ...trainOnly, ...evalOnly, h("label", { class: "field" }, "seed ", seed),
    h("label", { class: "field" }, "epochs ", preset), start);
  syncKind();
  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const body = { kind: kind.value, mode: mode.value, seed: Number(seed.value),
      overrides: { ...PRESETS[preset.value].overrides, "training.progress_every": 5 } };
    if (mode.value === "peer") body.overrides = preset.value === "quick" ? { epochs: 100, progress_every: 5 } : {};
    if (kind.value === "train") { body.fold = Number(fold.value); if (name.value) body.name = name.value; }
    else { body.folds = Number(folds.value); body.inits = Number(inits.value); }
    try {
      const job = await post("/api/jobs", body);
      message.textContent = `Started ${job.id}.`;
      await refresh();
      watch(job.id);
    } catch (e) { message.textContent = `Could not start: ${e.message}`; }
  });

  const tbody = h("tbody", { id: "job-rows" });
  const table = h("table", { class: "scenes", id: "jobs" }, h("thead", {}, h("tr", {},
    ["job", "kind", "mode", "status", "progress", ""].map((t) => h("th", {}, t)))), tbody);

  const status = h("p", { id: "live-status", class: "muted" }, "Pick a job to watch it.");
  const lossPlot = h("div", { id: "loss-plot", class: "plot" });
  const cscPlot = h("div", { id: "csc-plot", class: "plot" });
  const resultBox = h("div", { id: "job-result" });
  const live = h("section", { class: "panel" }, h("h2", {}, "Live"), status,
    h("div", { class: "grid2" }, lossPlot, cscPlot), resultBox);

  root.append(h("h1", {}, "Jobs"),
    h("p", { class: "lead" }, "Train a MultiMTRNN on one 50:50 scene split and watch its Csc patterns ",
      "self-organise, or run the paper's protocol (K folds × N initialisations). Jobs and finished models ",
      "survive a server restart; a finished model can be made the one the app serves."),
    form, message, table, live);

  async function refresh() {
    let jobs;
    try { jobs = await get("/api/jobs"); } catch (e) { message.textContent = e.message; return; }
    tbody.replaceChildren(...jobs.map((job) => {
      const actions = [h("button", { type: "button", onclick: () => watch(job.id) }, "watch")];
      if (job.status === "running" || job.status === "queued")
        actions.push(h("button", { type: "button", class: "cancel", onclick: () => cancel(job.id) }, "cancel"));
      if (job.kind === "train" && job.status === "done")
        actions.push(h("button", { type: "button", class: "serve", onclick: () => serve(job) }, "serve this model"));
      return h("tr", { dataset: { job: job.id, status: job.status } },
        h("td", {}, job.id), h("td", {}, job.kind), h("td", {}, job.params.mode),
        h("td", { class: "job-status" }, job.status), h("td", {}, progressText(job)), h("td", {}, actions));
    }));
  }

  async function cancel(id) {
    try { await post(`/api/jobs/${id}/cancel`); } catch (e) { message.textContent = e.message; }
    await refresh();
  }

  async function serve(job) {
    try {
      // The app's model registry: a finished job's model is listed by /api/models.
      const r = await put("/api/models/selected", { name: job.result.model });
      message.textContent = `The app now serves ${r.selected}.`;
      await ctx.modelsChanged();
    } catch (e) { message.textContent = `Could not serve it: ${e.message}`; }
  }

  const losses = new Map();  // stage -> {x: [], y: []}
  function drawLoss() {
    const traces = [...losses.entries()].map(([stage, s]) => ({ x: s.x, y: s.y, name: stage, mode: "lines" }));
    Plotly.react(lossPlot, traces, baseLayout({ title: "loss per epoch", yaxis: { type: "log" },
      xaxis: { title: "epoch" }, margin: { t: 40, r: 10 }, height: 340 }), CONFIG);
  }
  function drawCsc(event) {
    const labels = event.labels || event.points.map(() => "?");
    const traces = [...groupPoints(event.points, labels).entries()].map(([label, g]) => ({ x: g.x, y: g.y,
      name: label, mode: "markers", type: "scatter", marker: { color: colourOf(ACTION_COLOURS, label), size: 7 } }));
    Plotly.react(cscPlot, traces, baseLayout({ title: `Csc PCA (${event.stage}, epoch ${event.epoch})`,
      xaxis: { title: "PC1" }, yaxis: { title: "PC2" }, margin: { t: 40, r: 10 }, height: 340,
      legend: { title: { text: "action" } } }), CONFIG);
    cscPlot.dataset.epoch = String(event.epoch);
  }

  function handle(event) {
    if (event.type === "snapshot") {
      const job = event.job;
      status.textContent = `${job.id}: ${job.status} ${progressText(job)}`;
      status.dataset.status = job.status;
      if (job.progress?.points) drawCsc(job.progress);
      if (job.result) showResult(job);
      if (job.error) resultBox.replaceChildren(h("pre", { class: "error" }, job.error));
    } else if (event.type === "progress") {
      const s = losses.get(event.stage) || { x: [], y: [] };
      s.x.push(event.epoch); s.y.push(event.loss); losses.set(event.stage, s);
      status.textContent = `${watched}: running, ${event.stage} epoch ${event.epoch}/${event.epochs}`;
      status.dataset.status = "running";
      drawLoss();
      if (event.points) drawCsc(event);
    } else if (event.type === "run") {
      status.textContent = `${watched}: ${event.done}/${event.total} runs done`;
      status.dataset.status = "running";
    } else if (["done", "error", "cancelled"].includes(event.type)) {
      status.textContent = `${watched}: ${event.status || event.type}`;
      status.dataset.status = event.status || event.type;
      if (event.type === "error") resultBox.replaceChildren(h("pre", { class: "error" }, event.error));
      if (source) { source.close(); source = null; }
      get(`/api/jobs/${watched}`).then(showResult).catch(() => {});
      refresh();
    }
  }

  function showResult(job) {
    if (!job.result) return;
    const rows = [];
    const m = job.result.metrics || job.result.summary;
    for (const split of ["train", "test", "mixed"]) {
      const s = m?.[split];
      if (!s) continue;
      const v = (k) => (typeof s[k] === "number" ? s[k] : s[k]?.mean);
      rows.push(h("tr", {}, h("td", {}, split), ["sentence_exact", "f1", "edit_distance"].map((k) =>
        h("td", {}, v(k) === undefined ? "–" : Number(v(k)).toFixed(3)))));
    }
    resultBox.replaceChildren(
      job.result.model ? h("p", {}, "Model ", h("code", {}, job.result.model), " saved.") : "",
      h("table", { class: "scenes", id: "result-table" }, h("thead", {}, h("tr", {},
        ["split", "sentence exact", "phoneme F1", "edit distance"].map((t) => h("th", {}, t)))), h("tbody", {}, rows)));
  }

  function watch(id) {
    if (source) source.close();
    watched = id;
    losses.clear();
    lossPlot.replaceChildren(); cscPlot.replaceChildren(); resultBox.replaceChildren();
    delete cscPlot.dataset.epoch;
    source = subscribe(`/api/jobs/${id}/events`, EVENTS, handle, (closed) => { if (source === closed) source = null; });
  }

  await refresh();
  refreshTimer = setInterval(refresh, 3000);
  return () => { clearInterval(refreshTimer); if (source) source.close(); };
}
