// Small DOM helpers shared by the pages: element builder, "?" help buttons, badges.

import { withQuery } from "./api.js";

export function h(tag, attrs = {}, ...children) {
  const el = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs || {})) {
    if (value === undefined || value === null || value === false) continue;
    if (key === "class") el.className = value;
    else if (key.startsWith("on")) el.addEventListener(key.slice(2), value);
    else if (key === "dataset") Object.assign(el.dataset, value);
    else el.setAttribute(key, value === true ? "" : value);
  }
  for (const child of children.flat(Infinity)) {
    if (child === undefined || child === null || child === false) continue;
    el.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return el;
}

let openPopover = null;
document.addEventListener("click", (ev) => {
  if (openPopover && !openPopover.contains(ev.target) && !ev.target.classList.contains("help")) {
    openPopover.remove();
    openPopover = null;
  }
});

// A "?" button that explains the control next to it; `term` links to the glossary.
export function help(text, term) {
  const button = h("button", { class: "help", type: "button", "aria-label": "help", title: text }, "?");
  button.addEventListener("click", (ev) => {
    ev.preventDefault();
    ev.stopPropagation();
    if (openPopover) openPopover.remove();
    const pop = h("div", { class: "popover", role: "dialog" }, h("p", {}, text),
      term ? h("a", { href: withQuery("#/glossary", { term }) }, `Glossary: ${term}`) : null);
    document.body.append(pop);
    const r = button.getBoundingClientRect();
    pop.style.left = `${Math.min(window.scrollX + r.left, window.scrollX + window.innerWidth - 340)}px`;
    pop.style.top = `${window.scrollY + r.bottom + 6}px`;
    openPopover = pop;
  });
  return button;
}

// A labelled control with its help button: label text, the control, "?".
export function field(label, control, helpText, term) {
  return h("label", { class: "field" }, h("span", { class: "field-label" }, label), control, help(helpText, term));
}

export function badge(split) {
  const text = { train: "train", test: "test", unknown: "–" }[split] || split;
  const tip = {
    train: "the served model was trained on this recording",
    test: "the served model never saw this scene: describing it tests generalisation",
    unknown: "not part of the served model's corpus split",
  }[split];
  return h("span", { class: `badge badge-${split}`, title: tip }, text);
}

export function errorBox(message) {
  return h("div", { class: "error", role: "alert" }, message);
}

// The answer of `request`, or null once the server's message is shown at the end of `root`.
export async function answerOrError(root, request) {
  try {
    return await request;
  } catch (e) {
    root.append(errorBox(e.message));
    return null;
  }
}

// Fixed decimals for ordinary numbers, significant digits for tiny ones (untrained Csc are ~1e-4).
export function fmt(x, digits = 3) {
  const v = Number(x);
  return v === 0 || Math.abs(v) >= 0.01 ? v.toFixed(digits) : v.toPrecision(digits);
}
