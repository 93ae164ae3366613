// Shared pieces of the lessons: their text and equations, hideable controls (?hide=a,b), "try this"
// boxes, debounced live requests. Every lesson keeps its state in the URL through ctx.setParams.

import { h, help } from "../js/dom.js";

// The names listed in ?hide=... (comma separated): a teacher's trimmed link.
export function hiddenSet(ctx) {
  return new Set(String(ctx.params.hide || "").split(",").map((s) => s.trim()).filter(Boolean));
}

// A labelled live control: data-control=name lets ?hide=name remove it.
export function control(ctx, name, label, element, helpText, term) {
  const wrap = h("label", { class: "field", dataset: { control: name } },
    h("span", { class: "field-label" }, label), element, helpText ? help(helpText, term) : null);
  if (hiddenSet(ctx).has(name)) wrap.hidden = true;
  return wrap;
}

export function controls(...items) {
  return h("div", { class: "controls" }, ...items);
}

function equation(text, tag) {
  return h("div", { class: "eq" }, tag ? h("span", { class: "tag" }, tag) : null, text);
}

// A lesson's text: strings are paragraphs, { equation, tag } an equation with its number.
export function prose(items) {
  return h("div", { class: "lesson-text" },
    items.map((x) => (typeof x === "string" ? h("p", {}, x) : equation(x.equation, x.tag))));
}

// "Try this": the question, and the answer (built when asked, from the live numbers) on demand;
// ?hide=answer removes the button (a test for the class).
export function tryThis(ctx, question, answer) {
  const box = h("div", { class: "answer", hidden: true });
  const button = h("button", { type: "button", class: "reveal", hidden: hiddenSet(ctx).has("answer") }, "Show the answer");
  button.addEventListener("click", () => {
    const open = box.hidden;
    box.replaceChildren(...[].concat(open ? answer() : []));
    box.hidden = !open;
    button.textContent = open ? "Hide the answer" : "Show the answer";
  });
  return h("section", { class: "try" }, h("h3", {}, "Try this"), h("p", {}, question), button, box);
}

// Run `fn` at most once at a time, always ending with the latest request.
export function latest(fn, delay = 60) {
  let timer = null;
  let running = false;
  let pending = null;
  const run = async () => {
    if (running) return;
    running = true;
    while (pending) {
      const args = pending;
      pending = null;
      try { await fn(...args); } catch (e) { console.error(e); }
    }
    running = false;
  };
  return (...args) => {
    pending = args;
    clearTimeout(timer);
    timer = setTimeout(run, delay);
  };
}

export function slider(id, min, max, step, value) {
  return h("input", { type: "range", id, min, max, step, value });
}

export function select(id, options, value) {
  return h("select", { id }, options.map((o) => {
    const [v, label] = Array.isArray(o) ? o : [o, o];
    return h("option", { value: v, selected: String(v) === String(value) }, label);
  }));
}

export function num(x, digits = 3) {
  if (x === null || x === undefined) return "–";
  const v = Number(x);
  if (v !== 0 && (Math.abs(v) < 1e-3 || Math.abs(v) >= 1e4)) return v.toExponential(2);
  return v.toFixed(digits);
}

// The corpus recordings to pick from (#scene): the URL's ?scene= if it is one, else the first.
export function sceneSelect(ctx, index) {
  const scenes = index.scenes.map((s) => [s.id, `${s.utterance} (${s.split})`]);
  return select("scene", scenes, scenes.some(([id]) => id === ctx.params.scene) ? ctx.params.scene : scenes[0][0]);
}
