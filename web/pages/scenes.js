// Scenes: the 64 scenes x 4 recordings of the corpus as pictures (the camera's first and last
// frame, what the served model says, right or wrong, the split) or as a table; filterable.

import { get, withQuery } from "../js/api.js";
import { h, field, badge, help, answerOrError } from "../js/dom.js";
import { ACTIONS, OBJECT_COLOURS, SHAPES } from "../js/palette.js";

export const meta = { route: "scenes", title: "Scenes", order: 10,
  description: "the corpus: 64 scenes, each recorded 4 times" };

const OPTIONS = {
  action: ACTIONS,
  colour: OBJECT_COLOURS,
  shape: SHAPES,
  variant: ["0", "1", "2", "3"],
  split: ["train", "test"],
};
const HELP = {
  action: ["Manipulation the teacher guided the arm through (Fig. 5b). Proprioception mostly tells these apart.", "proprioception"],
  colour: ["Colour of the object; only vision can tell it.", "vision features"],
  shape: ["Shape of the object; only vision can tell it.", "vision features"],
  variant: ["Each scene was recorded four times by different (simulated) teachers: speed, path, placement vary.", null],
  split: ["Train: the served model learned from this recording. Test: a scene it never saw (generalisation).", "split"],
  q: ["Search the recording id or the utterance, e.g. 'red apple'.", null],
};
const VIEWS = { grid: "pictures", table: "table" };
const THUMB_WIDTH = 128;
const WARM_UP_POLL_MS = 3000; // while the server's survey has not described every recording yet

// Thumbnails load when their card comes near the screen (each is a render of the recording on the
// server): closer than the browser's own loading="lazy", which fetches several screens ahead.
const nearScreen = new IntersectionObserver((entries) => entries.forEach((e) => {
  if (!e.isIntersecting) return;
  nearScreen.unobserve(e.target);
  e.target.src = e.target.dataset.src;
}), { rootMargin: "150px" });

// The served model's answer: its words and a right / wrong badge (nothing while it is computed).
function verdict(s) {
  if (s.said === undefined) return null;
  if (s.said === null) return h("span", { class: "muted small" }, "the model is still listening…");
  const mark = s.correct === null ? null : h("span", { class: `verdict ${s.correct ? "right" : "wrong"}`,
    title: s.correct ? "the model says what the teacher said" : "the model's words differ from the teacher's" },
  s.correct ? "✓ right" : "✗ wrong");
  return h("span", { class: "said-small" }, mark, " ", h("q", {}, s.said || "(silence)"));
}

// A card: the first frame, then (once it is there: one render per recording) the last.
function card(s) {
  const frame = (i) => withQuery(`/api/scenes/${s.id}/frames/${i}.jpg`, { width: THUMB_WIDTH });
  const last = h("img", { alt: "", width: THUMB_WIDTH, height: THUMB_WIDTH * 0.75, class: "thumb" });
  const first = h("img", { alt: "", width: THUMB_WIDTH, height: THUMB_WIDTH * 0.75, class: "thumb",
    dataset: { src: frame(0) }, onload: () => { if (!last.src) last.src = frame(s.frames - 1); } });
  nearScreen.observe(first);
  const answer = h("div", { class: "card-said" }, verdict(s));
  const el = h("li", { class: "scene-card", dataset: { id: s.id } },
    h("a", { href: `#/scene/${s.id}`, class: "scene-link", title: `first and last camera frame of ${s.id}` },
      h("span", { class: "thumbs" }, first, last), s.id),
    h("div", { class: "card-meta" }, badge(s.split), ` ${s.duration_s.toFixed(1)} s · teacher: “${s.utterance}”`),
    answer);
  return { el, answer };
}

function tableRow(s) {
  return h("tr", {},
    h("td", {}, h("a", { href: `#/scene/${s.id}`, class: "scene-link" }, s.id)),
    h("td", {}, s.utterance), h("td", { class: "said-cell" }, verdict(s)), h("td", {}, s.action), h("td", {}, s.colour),
    h("td", {}, s.shape), h("td", {}, s.variant), h("td", {}, `${s.duration_s.toFixed(1)} s`), h("td", {}, badge(s.split)));
}

function filterForm(p, onChange) {
  const selects = {};
  const form = h("form", { class: "filters", onsubmit: (e) => e.preventDefault() });
  for (const [key, values] of Object.entries(OPTIONS)) {
    const sel = h("select", { name: key, "aria-label": key },
      h("option", { value: "" }, "any"), values.map((v) => h("option", { value: v, selected: p[key] === v }, v)));
    sel.addEventListener("change", onChange);
    selects[key] = sel;
    form.append(field(key, sel, ...HELP[key]));
  }
  const search = h("input", { type: "search", name: "q", placeholder: "search", value: p.q || "" });
  search.addEventListener("input", onChange);
  form.append(field("search", search, ...HELP.q));
  const read = () => ({ ...Object.fromEntries(Object.entries(selects).map(([k, s]) => [k, s.value])),
    q: search.value.trim().toLowerCase() });
  return { form, read };
}

const matches = (s, f) =>
  (!f.action || s.action === f.action) && (!f.colour || s.colour === f.colour) &&
  (!f.shape || s.shape === f.shape) && (!f.variant || String(s.variant) === f.variant) &&
  (!f.split || s.split === f.split) && (!f.q || s.id.includes(f.q) || s.utterance.includes(f.q));

export async function render(root, ctx) {
  let view = VIEWS[ctx.params.view] ? ctx.params.view : "grid";
  const filters = filterForm(ctx.params, update);
  const toggles = Object.entries(VIEWS).map(([key, label]) => h("button", { type: "button", class: "view-toggle",
    dataset: { view: key }, "aria-pressed": String(key === view), onclick: () => { view = key; update(); } }, label));
  const count = h("p", { class: "muted", id: "scene-count" });
  const grid = h("ul", { class: "scene-grid", id: "scene-grid", "aria-label": "recordings" });
  const body = h("tbody");
  const table = h("table", { class: "scenes", id: "scene-table" },
    h("thead", {}, h("tr", {},
      h("th", {}, "recording"), h("th", {}, "utterance (teacher)"), h("th", {}, "model says"), h("th", {}, "action"),
      h("th", {}, "colour"), h("th", {}, "shape"), h("th", {}, "variant"), h("th", {}, "length"),
      h("th", {}, "split ", help(HELP.split[0], "split")))),
    body);
  root.append(h("h1", {}, "Scenes"),
    h("p", { class: "lead" }, "Every scene of the grammar ", h("code", {}, "ACT the COL OBJ."),
      " recorded four times. Each picture is the camera's first and last frame; below it, what the served model says. Pick one to watch the arm, see what the robot saw and read what the model says."),
    filters.form, h("div", { class: "controls" }, h("span", { class: "field-label", id: "view-label" }, "show as"),
      h("span", { class: "toggle-group", role: "group", "aria-labelledby": "view-label" }, toggles), count),
    grid, table);

  const answer = await answerOrError(root, get("/api/scenes"));
  if (!answer) return null;
  let all = answer.scenes;
  const cards = new Map(all.map((s) => [s.id, card(s)]));
  grid.replaceChildren(...[...cards.values()].map((c) => c.el));

  function update() {
    const f = filters.read();
    ctx.setParams({ ...f, view: view === "grid" ? "" : view });
    const shown = all.filter((s) => matches(s, f));
    const ids = new Set(shown.map((s) => s.id));
    count.textContent = `${shown.length} of ${all.length} recordings`;
    toggles.forEach((b) => b.setAttribute("aria-pressed", String(b.dataset.view === view)));
    grid.hidden = view !== "grid";
    table.hidden = view !== "table";
    cards.forEach((c, id) => { c.el.hidden = !ids.has(id); });
    body.replaceChildren(...(view === "table" ? shown.map(tableRow) : []));
  }
  update();

  // While the server's survey warms up `said` is null: ask again until every answer is there.
  let timer = null;
  const poll = () => {
    if (!all.some((s) => s.said === null)) return;
    timer = setTimeout(async () => {
      const again = await get("/api/scenes").catch(() => null);
      if (again) {
        all = again.scenes;
        all.forEach((s) => cards.get(s.id)?.answer.replaceChildren(verdict(s) ?? ""));
        update();
      }
      poll();
    }, WARM_UP_POLL_MS);
  };
  poll();
  return () => clearTimeout(timer);
}
