// Scenes: the 64 scenes x 4 recordings of the corpus, filterable, with train/test badges.

import { get } from "../js/api.js";
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

export async function render(root, ctx) {
  const p = ctx.params;
  const selects = {};
  const filters = h("form", { class: "filters", onsubmit: (e) => e.preventDefault() });
  for (const [key, values] of Object.entries(OPTIONS)) {
    const sel = h("select", { name: key, "aria-label": key },
      h("option", { value: "" }, "any"), values.map((v) => h("option", { value: v, selected: p[key] === v }, v)));
    sel.addEventListener("change", update);
    selects[key] = sel;
    filters.append(field(key, sel, ...HELP[key]));
  }
  const search = h("input", { type: "search", name: "q", placeholder: "search", value: p.q || "" });
  search.addEventListener("input", update);
  filters.append(field("search", search, ...HELP.q));
  const count = h("p", { class: "muted", id: "scene-count" });
  const body = h("tbody");
  const table = h("table", { class: "scenes" },
    h("thead", {}, h("tr", {},
      h("th", {}, "recording"), h("th", {}, "utterance (teacher)"), h("th", {}, "action"),
      h("th", {}, "colour"), h("th", {}, "shape"), h("th", {}, "variant"), h("th", {}, "length"),
      h("th", {}, "split ", help(HELP.split[0], "split")))),
    body);
  root.append(h("h1", {}, "Scenes"),
    h("p", { class: "lead" }, "Every scene of the grammar ", h("code", {}, "ACT the COL OBJ."),
      " recorded four times. Pick one to watch the arm, see what the robot saw and read what the model says."),
    filters, count, table);

  const answer = await answerOrError(root, get("/api/scenes"));
  if (!answer) return;
  const all = answer.scenes;
  function update() {
    const f = Object.fromEntries(Object.entries(selects).map(([k, s]) => [k, s.value]));
    const q = search.value.trim().toLowerCase();
    ctx.setParams({ ...f, q });
    const rows = all.filter((s) =>
      (!f.action || s.action === f.action) && (!f.colour || s.colour === f.colour) &&
      (!f.shape || s.shape === f.shape) && (!f.variant || String(s.variant) === f.variant) &&
      (!f.split || s.split === f.split) && (!q || s.id.includes(q) || s.utterance.includes(q)));
    count.textContent = `${rows.length} of ${all.length} recordings`;
    body.replaceChildren(...rows.map((s) => h("tr", {},
      h("td", {}, h("a", { href: `#/scene/${s.id}`, class: "scene-link" }, s.id)),
      h("td", {}, s.utterance), h("td", {}, s.action), h("td", {}, s.colour), h("td", {}, s.shape),
      h("td", {}, s.variant), h("td", {}, `${s.duration_s.toFixed(1)} s`), h("td", {}, badge(s.split)))));
  }
  update();
}
