// Jobs: start a training or an evaluation, watch it live (Server-Sent Events), cancel it, and
// serve a finished model.
//
// Live view: a progress bar with the time left in the stage (and which attempt a restarting stage
// is on), the loss per epoch of every training stage, and the PCA of the Csc patterns the current
// stage is shaping (c_0 of MTRNN_a, c_T of the encoders), redrawn at each progress event so the
// points can be seen self-organising. The server runs a few jobs at once and queues the others
// (their position is shown). The epoch presets come from the server with the minutes each took per
// mode (GET /api/jobs/presets). Jobs are kept by the server across restarts. A job runs on one
// protocol split (model/experiments/splits.py): the paper's 50:50 by scene, held-out objects or
// action x shape pairs (Latin squares, folds 0..3), or a training size (how many scenes it trains on).

import { get, post, put, subscribe } from "../js/api.js";
import { h } from "../js/dom.js";
import { ACTION_COLOURS, colourOf } from "../js/palette.js";
import { plotly, CONFIG, baseLayout, groupPoints } from "../js/plots.js";

export const meta = { route: "jobs", title: "Jobs", order: 80,
  description: "train or evaluate models, watch them learn, serve a new model" };

const EVENTS = ["snapshot", "progress", "run", "done", "error", "cancelled"];
const SPLITS = [  // value, label; the server checks each (server/jobs/bounds.py: check_split)
  ["scenes", "scenes: the paper's 50:50 by scene"],
  ["objects", "objects: colour × shape pairs never seen (4 folds)"],
  ["action-object", "action-object: action × shape pairs never seen (4 folds)"],
  ["size", "size: train on fewer scenes, test on 16 novel ones"],
];
const SQUARE_FOLDS = 4;  // folds of a Latin-square split
const PROGRESS_EVERY = 5;  // epochs between two live updates

function duration(seconds) {
  if (seconds < 90) return `${Math.max(1, Math.round(seconds))} s`;
  return `${Math.round(seconds / 60)} min`;
}

// "auditory, attempt 2 of 3: epoch 30/1500, loss 0.1234, about 2 min left" (a training job), "3/8 runs, ..."
// (an evaluation), "queued, position 2" (waiting for a slot).
export function progressText(job) {
  if (job.status === "queued") return job.position ? `queued, position ${job.position}` : "queued";
  const p = job.progress;
  if (!p) return "";
  const left = typeof p.eta === "number" ? `, about ${duration(p.eta)} left` : "";
  if (p.type === "run") return `${p.done}/${p.total} runs${left}`;
  if (p.epoch === undefined) return "";
  const attempt = p.attempt ? `, attempt ${p.attempt} of ${p.attempts}` : "";
  const loss = typeof p.loss === "number" ? `, loss ${p.loss.toFixed(4)}` : "";
  return `${p.stage}${attempt}: epoch ${p.epoch}/${p.epochs}${loss}${left}`;
}

// Share of the current stage (training) or of the runs (evaluation) done, in [0, 1].
function fraction(p) {
  if (!p) return 0;
  if (p.type === "run") return p.total ? p.done / p.total : 0;
  return p.epochs ? p.epoch / p.epochs : 0;
}

function progressBar(p, attrs = {}) {
  const text = p ? `${Math.round(100 * fraction(p))} %` : "not started";
  return h("progress", { max: 1, value: fraction(p), "aria-label": `progress: ${text}`, ...attrs });
}

// The form that starts a job; `submit(body)` posts it. Each preset's label says how long it took
// in the chosen mode (measured by the server's benchmarks/presets.py).
function jobForm(presets, submit) {
  const kind = h("select", { name: "kind", "aria-label": "job kind" },
    h("option", { value: "train" }, "train one model"), h("option", { value: "evaluate" }, "evaluate (K folds × N inits)"));
  const mode = h("select", { name: "mode", "aria-label": "training mode" },
    ["end_to_end", "faithful", "peer"].map((m) => h("option", { value: m }, m)));
  const fold = h("input", { name: "fold", type: "number", min: 0, max: 999, value: 0, size: 3 });
  const seed = h("input", { name: "seed", type: "number", min: 0, max: 1000000, value: 0, size: 3 });
  const folds = h("input", { name: "folds", type: "number", min: 1, max: 10, value: 2, size: 3 });
  const inits = h("input", { name: "inits", type: "number", min: 1, max: 10, value: 1, size: 3 });
  const split = h("select", { name: "split", id: "job-split" }, SPLITS.map(([v, label]) => h("option", { value: v }, label)));
  const trainScenes = h("input", { name: "train_scenes", id: "job-train-scenes", type: "number", min: 1, max: 48, value: 16, size: 3 });
  const preset = h("select", { name: "preset", "aria-label": "epoch budget" },
    Object.keys(presets).map((k) => h("option", { value: k })));
  const name = h("input", { name: "name", placeholder: "model name (optional)", pattern: "[a-z0-9\\-]{1,64}",
    maxlength: 64, title: "a-z, 0-9 and '-', at most 64 characters" });
  const field = (label, control) => h("label", { class: "field" }, `${label} `, control);
  const trainOnly = [field("fold", fold), field("name", name)];
  const evalOnly = [field("folds", folds), field("inits", inits)];
  const sizeOnly = field("training scenes", trainScenes);
  function sync() {
    trainOnly.forEach((el) => { el.hidden = kind.value !== "train"; });
    evalOnly.forEach((el) => { el.hidden = kind.value !== "evaluate"; });
    sizeOnly.hidden = split.value !== "size";
    const square = split.value === "objects" || split.value === "action-object";
    fold.max = square ? SQUARE_FOLDS - 1 : 999;
    folds.max = square ? SQUARE_FOLDS : 10;
    [...mode.options].forEach((o) => { o.disabled = kind.value === "train" && o.value === "peer"; });
    if (mode.selectedOptions[0].disabled) mode.value = "end_to_end";
    [...preset.options].forEach((o) => { o.textContent = presets[o.value].labels[mode.value]; });
  }
  kind.addEventListener("change", sync);
  mode.addEventListener("change", sync);
  split.addEventListener("change", sync);
  const form = h("form", { class: "controls", id: "job-form" }, field("job", kind), field("mode", mode),
    field("split", split), sizeOnly, ...trainOnly, ...evalOnly, field("seed", seed), field("epochs", preset),
    h("button", { type: "submit", id: "start-job" }, "Start"));
  sync();
  form.addEventListener("submit", (ev) => {
    ev.preventDefault();
    const every = mode.value === "peer" ? "progress_every" : "training.progress_every";
    const body = { kind: kind.value, mode: mode.value, seed: Number(seed.value), preset: preset.value,
      split: split.value, overrides: { [every]: PROGRESS_EVERY } };
    if (split.value === "size") body.train_scenes = Number(trainScenes.value);
    if (kind.value === "train") { body.fold = Number(fold.value); if (name.value) body.name = name.value; }
    else { body.folds = Number(folds.value); body.inits = Number(inits.value); }
    submit(body);
  });
  return form;
}

// "end_to_end" (the paper's split), "end_to_end, objects split", "peer, size split (16 scenes)".
function splitText(params) {
  const split = params.split || "scenes";
  if (split === "scenes") return params.mode;
  return `${params.mode}, ${split} split${params.train_scenes ? ` (${params.train_scenes} scenes)` : ""}`;
}

// One row of the jobs table: its status (or place in the queue), a progress bar while it runs, actions.
function jobRow(job, { watch, cancel, serve }) {
  const actions = [h("button", { type: "button", onclick: () => watch(job.id) }, "watch")];
  if (job.status === "running" || job.status === "queued")
    actions.push(h("button", { type: "button", class: "cancel", onclick: () => cancel(job.id) }, "cancel"));
  if (job.kind === "train" && job.status === "done")
    actions.push(h("button", { type: "button", class: "serve", onclick: () => serve(job) }, "serve this model"));
  const shown = job.status === "queued" ? progressText(job) : job.status;
  const progress = job.status === "running" ? [progressBar(job.progress), " ", progressText(job)] : [];
  return h("tr", { dataset: { job: job.id, status: job.status } },
    h("td", {}, job.id), h("td", {}, job.kind), h("td", {}, splitText(job.params)),
    h("td", { class: "job-status" }, shown), h("td", { class: "job-progress" }, progress), h("td", {}, actions));
}

function resultTable(job) {
  const rows = [];
  const m = job.result.metrics || job.result.summary;
  for (const split of ["train", "test", "mixed"]) {
    const s = m?.[split];
    if (!s) continue;
    const v = (k) => (typeof s[k] === "number" ? s[k] : s[k]?.mean);
    rows.push(h("tr", {}, h("td", {}, split), ["sentence_exact", "f1", "edit_distance"].map((k) =>
      h("td", {}, v(k) === undefined ? "–" : Number(v(k)).toFixed(3)))));
  }
  return [job.result.model ? h("p", {}, "Model ", h("code", {}, job.result.model), " saved.") : "",
    h("table", { class: "scenes", id: "result-table" }, h("thead", {}, h("tr", {},
      ["split", "sentence exact", "phoneme F1", "edit distance"].map((t) => h("th", {}, t)))), h("tbody", {}, rows))];
}

// The live panel of the watched job: status line and progress bar, loss curves, Csc PCA, result.
class LiveView {
  constructor(Plotly) {
    this.Plotly = Plotly;
    this.status = h("p", { id: "live-status", class: "muted" }, "Pick a job to watch it.");
    this.bar = progressBar(null, { id: "live-progress" });
    this.lossPlot = h("div", { id: "loss-plot", class: "plot" });
    this.cscPlot = h("div", { id: "csc-plot", class: "plot" });
    this.resultBox = h("div", { id: "job-result" });
    this.losses = new Map();  // "stage" or "stage (attempt n)" -> {x: [], y: []}
    this.element = h("section", { class: "panel" }, h("h2", {}, "Live"), this.status, this.bar,
      h("div", { class: "grid2" }, this.lossPlot, this.cscPlot), this.resultBox);
  }

  reset() {
    this.losses.clear();
    this.lossPlot.replaceChildren(); this.cscPlot.replaceChildren(); this.resultBox.replaceChildren();
    delete this.cscPlot.dataset.epoch;
  }

  progress(job) {
    this.status.textContent = `${job.id}: ${job.status === "queued" ? "" : `${job.status} `}${progressText(job)}`;
    this.status.dataset.status = job.status;
    this.bar.value = fraction(job.progress);
    this.bar.setAttribute("aria-label", `progress of ${job.id}: ${Math.round(100 * this.bar.value)} %`);
  }

  ended(id, status) {
    this.status.textContent = `${id}: ${status}`;
    this.status.dataset.status = status;
    if (status === "done") this.bar.value = 1;
  }

  loss(event) {
    const key = event.attempt ? `${event.stage} (attempt ${event.attempt})` : event.stage;
    const s = this.losses.get(key) || { x: [], y: [] };
    s.x.push(event.epoch); s.y.push(event.loss); this.losses.set(key, s);
    const traces = [...this.losses.entries()].map(([stage, t]) => ({ x: t.x, y: t.y, name: stage, mode: "lines" }));
    this.Plotly.react(this.lossPlot, traces, baseLayout({ title: { text: "Training loss per epoch, by stage" },
      yaxis: { type: "log", title: { text: "loss of the stage (log scale)" } },
      xaxis: { title: { text: "epoch of the stage" } }, legend: { title: { text: "stage" } },
      margin: { t: 40, r: 10 }, height: 340 }), CONFIG);
  }

  csc(event) {
    const labels = event.labels || event.points.map(() => "?");
    const traces = [...groupPoints(event.points, labels).entries()].map(([label, g]) => ({ x: g.x, y: g.y,
      name: label, mode: "markers", type: "scatter", marker: { color: colourOf(ACTION_COLOURS, label), size: 7 } }));
    this.Plotly.react(this.cscPlot, traces, baseLayout({
      title: { text: `Csc patterns, PCA (${event.stage}, epoch ${event.epoch})` },
      xaxis: { title: { text: "PC1 of the Csc patterns" } }, yaxis: { title: { text: "PC2 of the Csc patterns" } },
      margin: { t: 40, r: 10 }, height: 340, legend: { title: { text: "action" } } }), CONFIG);
    this.cscPlot.dataset.epoch = String(event.epoch);
  }

  // Show one event of job `id`'s stream; true once the job has ended.
  show(event, id) {
    if (event.type === "snapshot") {
      this.progress(event.job);
      if (event.job.progress?.points) this.csc(event.job.progress);
      this.result(event.job);
    } else if (event.type === "progress" || event.type === "run") {
      this.progress({ id, status: "running", progress: event });
      if (event.type === "progress") this.loss(event);
      if (event.points) this.csc(event);
    } else if (["done", "error", "cancelled"].includes(event.type)) {
      this.ended(id, event.status || event.type);
      return true;
    }
    return false;
  }

  result(job) {
    if (job.result) this.resultBox.replaceChildren(...resultTable(job));
    else if (job.error) this.resultBox.replaceChildren(h("pre", { class: "error" }, job.error));
  }
}

const LEAD = "Train a MultiMTRNN on one 50:50 scene split and watch its Csc patterns self-organise, or run the "
  + "paper's protocol (K folds × N initialisations). The server runs a few jobs at once and queues the others. "
  + "Jobs and finished models survive a server restart; a finished model can be made the one the app serves.";

// Serve a finished job's model (the app's model registry lists it: /api/models).
async function serveModel(job, message, ctx) {
  try {
    const r = await put("/api/models/selected", { name: job.result.model });
    message.textContent = `The app now serves ${r.selected}.`;
    await ctx.modelsChanged();
  } catch (e) { message.textContent = `Could not serve it: ${e.message}`; }
}

export async function render(root, ctx) {
  const Plotly = await plotly();
  const presets = await get("/api/jobs/presets");
  const live = new LiveView(Plotly);
  const message = h("p", { class: "muted", id: "job-message" });
  const tbody = h("tbody", { id: "job-rows" });
  const table = h("table", { class: "scenes", id: "jobs" }, h("thead", {}, h("tr", {},
    ["job", "kind", "mode and split", "status", "progress", ""].map((t) => h("th", {}, t)))), tbody);
  let source = null;
  let watched = null;

  async function start(body) {
    try {
      const job = await post("/api/jobs", body);
      message.textContent = job.status === "queued"
        ? `Queued ${job.id} (position ${job.position}); it starts as soon as a slot is free.`
        : `Started ${job.id}.`;
      await refresh();
      watch(job.id);
    } catch (e) { message.textContent = `Could not start: ${e.message}`; }
  }

  async function refresh() {
    let jobs;
    try { jobs = await get("/api/jobs"); } catch (e) { message.textContent = e.message; return; }
    tbody.replaceChildren(...jobs.map((job) => jobRow(job, { watch, cancel, serve })));
  }

  async function cancel(id) {
    try { await post(`/api/jobs/${id}/cancel`); } catch (e) { message.textContent = e.message; }
    await refresh();
  }

  const serve = (job) => serveModel(job, message, ctx);

  function handle(event) {
    if (!live.show(event, watched)) return;
    if (source) { source.close(); source = null; }  // the job has ended
    get(`/api/jobs/${watched}`).then((job) => live.result(job)).catch(() => {});
    refresh();
  }

  function watch(id) {
    if (source) source.close();
    watched = id;
    live.reset();
    source = subscribe(`/api/jobs/${id}/events`, EVENTS, handle, (closed) => { if (source === closed) source = null; });
  }

  root.append(h("h1", {}, "Jobs"), h("p", { class: "lead" }, LEAD), jobForm(presets, start), message, table,
    live.element);
  await refresh();
  const refreshTimer = setInterval(refresh, 3000);
  return () => { clearInterval(refreshTimer); if (source) source.close(); };
}
