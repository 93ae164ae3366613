// Lesson 7: generalising. Training vs novel scenes: which combinations fail and why, two served
// models (e.g. faithful vs end-to-end) side by side, computed from the models on request. Then the
// objects split: for a fold, the objects (colour x shape) a model never saw and the colour and shape
// words it said for them, from a model trained on that split (one the app has, or one trained here
// with the Jobs machinery: POST /api/jobs, its progress polled).

import { get, post } from "../js/api.js";
import { h, errorBox } from "../js/dom.js";
import { EXACT_SCALE, OBJECT_COLOURS, SHAPES, SPLIT_COLOURS } from "../js/palette.js";
import { plotly, chart } from "../js/plots.js";
import { control, controls, tryThis, select, num } from "./common.js";

export const intro = [
  "The model is trained on half of the 64 scenes (all four recordings of a scene on the same side) and asked to describe the other half: actions, colours and shapes it knows, in combinations it has never met. The paper reports an F1 of 0.98 on training and 0.64 on novel scenes for its best network, with mostly single-phoneme errors.",
  "Each grid shows, for every action (rows) and object (columns), the share of the scene's recordings the model describes exactly; boxed cells (T) are training scenes. Click a cell to read what was said. The tables split novel scenes by whether their object (colour + shape) was ever seen in training: a new pairing of known parts is what the cell assemblies must compose.",
  "The last panel asks for exactly that composition: on the objects split a fold holds out four colour × shape objects (a Latin square, so every colour and every shape is still seen with three other partners) and tests every action on them. Which colour word and which shape word does the model say for an object it never saw?",
];

const OBJECT_FOLDS = [0, 1, 2, 3];  // the objects split's folds (model/experiments/splits.py)
const POLL_MS = 2000;
const ENDED = ["done", "failed", "cancelled", "interrupted"];

function counts(said) {
  return Object.entries(said).map(([w, n]) => `${w || "(none)"} ×${n}`).join(", ");
}

// The held-out objects of one objects-split model: a colour × shape grid and a table of the words said.
function drawObjects(r, grid, table) {
  const at = Object.fromEntries(r.held_out.map((g) => [`${g.colour} ${g.shape}`, g]));
  const top = (said) => Object.keys(said)[0] || "(none)";
  const z = OBJECT_COLOURS.map((c) => SHAPES.map((s) => at[`${c} ${s}`]?.exact ?? null));
  const text = OBJECT_COLOURS.map((c) => SHAPES.map((s) => {
    const g = at[`${c} ${s}`];
    return g ? `said: ${top(g.colour_said)} ${top(g.shape_said)}` : "seen in training";
  }));
  chart(grid, [{ z, x: SHAPES, y: OBJECT_COLOURS, text, texttemplate: "%{text}", type: "heatmap", zmin: 0, zmax: 1,
    colorscale: EXACT_SCALE, colorbar: { title: "exact" }, hovertemplate: "the %{y} %{x}: %{text}, %{z:.0%} exact<extra></extra>" }],
  { title: { text: `${r.model} (fold ${r.fold}): what it said for the objects it never saw`, font: { size: 13 } },
    xaxis: { title: "shape" }, yaxis: { title: "colour", autorange: "reversed" }, margin: { l: 75, r: 10, t: 40, b: 60 } });
  table.replaceChildren(h("table", { class: "lesson-table", id: "objects-words" },
    h("thead", {}, h("tr", {}, ["held-out object", "recordings", "colour words said", "shape words said", "colour right", "shape right"].map((x) => h("th", {}, x)))),
    h("tbody", {}, r.held_out.map((g) => h("tr", {}, h("td", {}, `${g.colour} ${g.shape}`), h("td", { class: "num" }, g.recordings),
      h("td", {}, counts(g.colour_said)), h("td", {}, counts(g.shape_said)),
      h("td", { class: "num" }, `${num(100 * g.colour_right, 0)} %`), h("td", { class: "num" }, `${num(100 * g.shape_right, 0)} %`))))));
}

// The objects-split panel: a fold, the model trained on it (or a button that trains one), its grid.
function objectsPanel(ctx, listed) {
  let models = listed;
  let timer = null;
  const fold = select("objects-fold", OBJECT_FOLDS.map((k) => [k, `fold ${k}`]), OBJECT_FOLDS.includes(Number(ctx.params.ofold)) ? ctx.params.ofold : 0);
  const status = h("p", { id: "objects-status", class: "muted" });
  const bar = h("progress", { id: "objects-progress", max: 1, value: 0, hidden: true, "aria-label": "training progress" });
  const train = h("button", { type: "button", id: "objects-train", hidden: true }, "Train one (end_to_end, quick budget)");
  const grid = h("div", { class: "plot", id: "objects-grid", style: "height:330px" });
  const table = h("div", { id: "objects-table" });

  async function show() {
    const k = Number(fold.value);
    ctx.setParams({ ofold: k });
    const model = models.find((m) => m.fold === k);
    train.hidden = Boolean(model);
    grid.replaceChildren(); table.replaceChildren();
    if (!model) {
      status.textContent = `No model of the app was trained on fold ${k} of the objects split, so there is nothing to show yet: train one here: a training job like those of the Jobs page, on a quick budget (a tenth of every stage's epochs).`;
      return;
    }
    status.textContent = `${model.name} (${model.mode}), trained without the four objects below; describing them…`;
    try {
      const r = await get("/api/lessons/generalising", { model: model.name });
      status.textContent = `${model.name} (${model.mode}), trained on fold ${k} of the objects split: its four held-out objects, each in every action.`;
      drawObjects(r, grid, table);
    } catch (e) { status.replaceChildren(errorBox(e.message)); }
  }

  async function follow(id) {
    const job = await get(`/api/jobs/${id}`);
    const p = job.progress;
    bar.value = p?.epochs ? p.epoch / p.epochs : 0;
    status.textContent = `Training job ${id}: ${job.status}${p?.stage ? `, ${p.stage} epoch ${p.epoch}/${p.epochs}` : ""}${job.position ? `, queue position ${job.position}` : ""}`;
    if (!ENDED.includes(job.status)) { timer = setTimeout(() => follow(id).catch((e) => status.replaceChildren(errorBox(e.message))), POLL_MS); return; }
    bar.hidden = true; train.disabled = false;
    if (job.status !== "done") { status.replaceChildren(errorBox(`The training job ended: ${job.status}${job.error ? `: ${job.error}` : ""}`)); return; }
    models = (await get("/api/lessons/generalising", { model: job.result.model })).objects_models;
    await ctx.modelsChanged?.();
    await show();
  }

  train.addEventListener("click", async () => {
    train.disabled = true;
    try {
      const job = await post("/api/jobs", { kind: "train", mode: "end_to_end", split: "objects", fold: Number(fold.value), preset: "quick" });
      bar.hidden = false;
      await follow(job.id);
    } catch (e) { train.disabled = false; status.replaceChildren(errorBox(e.message)); }
  });
  fold.addEventListener("change", show);
  const element = h("section", { class: "panel", id: "objects-panel" }, h("h2", {}, "Objects never seen (the objects split)"),
    controls(control(ctx, "ofold", "fold", fold, "Which Latin square of held-out objects: each fold holds out one colour with each shape.", "split")),
    status, bar, train, grid, table);
  return { element, show, stop: () => clearTimeout(timer) };
}

export async function render(root, ctx, index) {
  await plotly();
  const models = index.models;
  const byMode = (mode) => models.find((m) => index.modes[m] === mode);
  const defaultA = ctx.params.a && models.includes(ctx.params.a) ? ctx.params.a : byMode("faithful") || index.model;
  const defaultB = ctx.params.b && models.includes(ctx.params.b) ? ctx.params.b
    : byMode("end_to_end") || models.find((m) => m !== defaultA) || defaultA;
  const options = models.map((m) => [m, `${m} (${index.modes[m]})`]);
  const pickers = [select("model-a", options, defaultA), select("model-b", options, defaultB)];
  const error = h("div", { id: "gen-error" });
  const columns = [0, 1].map((k) => ({
    title: h("h2", { id: `title-${k}` }), summary: h("div", { id: `summary-${k}` }),
    grid: h("div", { class: "plot", id: `grid-${k}`, style: "height:330px" }),
    detail: h("div", { class: "small", id: `detail-${k}` }),
    pick: select(`pick-${k}`, [], ""),
  }));
  const results = [null, null];

  root.append(
    controls(
      control(ctx, "a", "left model", pickers[0], "A model the app serves (its checkpoint's mode in brackets below).", "split"),
      control(ctx, "b", "right model", pickers[1], "Another model to compare, e.g. end-to-end training against the paper's faithful staged recipe.", "split")),
    error,
    h("div", { class: "grid2" }, columns.map((c, k) => h("section", { class: "panel" }, c.title, c.summary, c.grid,
      controls(control(ctx, `pick${k}`, "read a scene", c.pick, "The same as clicking a cell: what the model said for each recording of the scene.", "split")), c.detail))),
    tryThis(ctx, "On novel scenes, which slot (action, colour or object) fails most often for each model, and does having seen the object in training help?",
      () => {
        if (!results[0]) return [h("p", {}, "Wait for the grids to load.")];
        return results.filter(Boolean).map((r) => {
          const e = r.test.slot_errors || {};
          const worst = Object.entries(e).sort((x, y) => y[1] - x[1])[0];
          return h("p", {}, `${r.model} (${r.mode}): exact on training ${num(100 * (r.train.exact ?? 0), 0)} %, on novel scenes ${num(100 * (r.test.exact ?? 0), 0)} %; the most frequent novel-scene error is the ${worst ? worst[0] : "–"} slot (${worst ? num(100 * worst[1], 0) : "–"} % of recordings). Novel scenes with a known object: ${num(100 * (r.test_object_seen.exact ?? 0), 0)} % exact; with an object never seen in training: ${num(100 * (r.test_object_unseen.exact ?? 0), 0)} %.`);
        }).concat([h("p", {}, "Read the two novel rows against each other. A novel scene whose object was seen in training (with other actions) asks the cell assemblies only to compose known parts; a novel scene whose object was never seen has no learned visual context to map from, so its colour or shape word is where errors are expected. The paper's own errors on novel scenes were mostly single wrong phonemes, rarely wrong words (4.3).")]);
      }));

  function summaryTable(r) {
    const row = (label, s) => h("tr", {}, h("td", {}, label), h("td", { class: "num" }, s.recordings),
      h("td", { class: "num" }, s.recordings ? `${num(100 * s.exact, 0)} %` : "–"),
      ...["action", "colour", "object"].map((k) => h("td", { class: "num" }, s.recordings ? `${num(100 * s.slot_errors[k], 0)} %` : "–")));
    return h("table", { class: "lesson-table" },
      h("thead", {}, h("tr", {}, ["", "recordings", "exact", "action wrong", "colour wrong", "object wrong"].map((x) => h("th", {}, x)))),
      h("tbody", {}, row("training scenes", r.train), row("novel scenes", r.test), row("novel, object seen", r.test_object_seen), row("novel, object unseen", r.test_object_unseen)));
  }

  function draw(k) {
    const r = results[k];
    const c = columns[k];
    c.title.textContent = `${r.model} (${r.mode})`;
    c.summary.replaceChildren(summaryTable(r));
    const z = r.actions.map(() => r.objects.map(() => null));
    const text = r.actions.map(() => r.objects.map(() => ""));
    const cells = {};
    r.scenes.forEach((s) => {
      const i = r.actions.indexOf(s.action), j = r.objects.indexOf(`${s.colour} ${s.shape}`);
      z[i][j] = s.exact;
      text[i][j] = s.split === "train" ? "T" : "";
      cells[`${i},${j}`] = s;
    });
    const shapes = r.scenes.filter((s) => s.split === "train").map((s) => {
      const i = r.actions.indexOf(s.action), j = r.objects.indexOf(`${s.colour} ${s.shape}`);
      return { type: "rect", x0: j - 0.5, x1: j + 0.5, y0: i - 0.5, y1: i + 0.5, line: { color: SPLIT_COLOURS.train, width: 2 } };
    });
    chart(c.grid, [{ z, x: r.objects, y: r.actions, text, texttemplate: "%{text}", type: "heatmap", zmin: 0, zmax: 1,
      colorscale: EXACT_SCALE, colorbar: { title: "exact" }, hovertemplate: "%{y} the %{x}: %{z:.0%} exact<extra></extra>" }],
    { title: { text: `${r.model}: share of each scene's recordings said exactly (T: training scene)`, font: { size: 13 } },
      xaxis: { title: "object (colour shape)", tickangle: -45, tickfont: { size: 10 } }, yaxis: { title: "action", autorange: "reversed" },
      shapes, margin: { l: 75, r: 10, t: 40, b: 110 } });
    c.grid.removeAllListeners?.("plotly_click");
    const show = (s) => {
      if (!s) return;
      c.pick.value = s.scene;
      c.detail.replaceChildren(h("p", {}, h("b", {}, s.expected), ` (${s.split === "train" ? "training" : "novel"} scene; object seen in training: ${s.seen.object ? "yes" : "no"}, action with this colour: ${s.seen.action_with_colour ? "yes" : "no"}, with this shape: ${s.seen.action_with_shape ? "yes" : "no"})`),
        h("ul", {}, s.recordings.map((x) => h("li", {}, `${x.id}: “${x.said || "(silence)"}” `, h("span", { class: x.exact ? "ok" : "bad" }, x.exact ? "✓" : `✗ ${x.wrong.join(", ") || "wording"}`)))));
    };
    c.grid.on("plotly_click", (ev) => show(cells[`${r.actions.indexOf(ev.points[0].y)},${r.objects.indexOf(ev.points[0].x)}`]));
    c.pick.replaceChildren(h("option", { value: "" }, "pick a scene"),
      ...r.scenes.map((s) => h("option", { value: s.scene }, `${s.expected} (${s.split})`)));
    c.pick.onchange = () => show(r.scenes.find((s) => s.scene === c.pick.value));
  }

  async function load(k) {
    ctx.setParams({ a: pickers[0].value, b: pickers[1].value });
    columns[k].summary.replaceChildren(h("p", { class: "muted" }, "describing every recording…"));
    try {
      results[k] = await get("/api/lessons/generalising", { model: pickers[k].value });
      error.replaceChildren();
    } catch (e) { error.replaceChildren(errorBox(e.message)); return; }
    draw(k);
  }

  pickers.forEach((p, k) => p.addEventListener("change", () => load(k)));
  await Promise.all([load(0), load(1)]);
  const objects = objectsPanel(ctx, results.find(Boolean)?.objects_models || []);
  root.append(objects.element);
  await objects.show();
  return objects.stop;
}
