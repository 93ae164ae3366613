// The lessons page: seven interactive lessons that walk through the model stage by stage.
// A page module of the app shell (meta + render); web/lessons/index.html hosts it on its own too.
// URL: #/lessons?lesson=timescales&tau=5&hide=tau  (state in the URL, ?hide= trims controls).

import { get } from "../js/api.js";
import { h, errorBox } from "../js/dom.js";

export const meta = { route: "lessons", title: "Lessons", order: 50, description: "seven interactive lessons on the model" };

const MODULES = {
  timescales: "./timescales.js",
  speaking: "./speaking.js",
  seeing: "./seeing.js",
  feeling: "./feeling.js",
  abstracting: "./abstracting.js",
  associating: "./associating.js",
  generalising: "./generalising.js",
};

function ensureCss() {
  if (document.getElementById("lessons-css")) return;
  document.head.append(h("link", { rel: "stylesheet", href: "/lessons/lessons.css", id: "lessons-css" }));
}

export async function render(root, ctx) {
  ensureCss();
  let index;
  try {
    index = await get("/api/lessons");
  } catch (e) {
    root.append(errorBox(e.message));
    return null;
  }
  const current = MODULES[ctx.params.lesson] ? ctx.params.lesson : "timescales";
  const tabs = h("nav", { class: "lesson-tabs", "aria-label": "lessons" },
    index.lessons.map((l) => h("a", {
      href: `#/${ctx.route}?lesson=${l.id}${ctx.params.hide ? `&hide=${encodeURIComponent(ctx.params.hide)}` : ""}`,
      class: l.id === current ? "active" : null, dataset: { lesson: l.id } }, l.title)));
  const body = h("div", { class: "lesson", id: `lesson-${current}` });
  root.append(h("h1", {}, "Lessons"), tabs, body);
  const module = await import(MODULES[current]);
  const lessonCtx = {
    ...ctx,
    setParams(update) { ctx.setParams({ lesson: current, ...update }); },
  };
  return (await module.render(body, lessonCtx, index)) || null;
}
