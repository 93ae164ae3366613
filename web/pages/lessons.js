// The lessons page: seven interactive lessons that walk through the model stage by stage, under
// tabs. A lesson is a module of web/lessons/ exporting `intro` (its opening text, shown first) and
// `render(root, ctx, index)` (its live part; index is GET /api/lessons).
// URL: #/lessons?lesson=timescales&tau=5&hide=tau  (state in the URL, ?hide= trims controls).

import { get, withQuery } from "../js/api.js";
import { h, answerOrError } from "../js/dom.js";
import { prose } from "../lessons/common.js";

export const meta = { route: "lessons", title: "Lessons", order: 50, description: "seven interactive lessons on the model" };

const LESSONS = ["timescales", "speaking", "seeing", "feeling", "abstracting", "associating", "generalising"];

export async function render(root, ctx) {
  const index = await answerOrError(root, get("/api/lessons"));
  if (!index) return null;
  const current = LESSONS.includes(ctx.params.lesson) ? ctx.params.lesson : LESSONS[0];
  const tabs = h("nav", { class: "lesson-tabs", "aria-label": "lessons" },
    index.lessons.map((l) => h("a", {
      href: withQuery(`#/${ctx.route}`, { lesson: l.id, hide: ctx.params.hide }),
      class: l.id === current ? "active" : null, dataset: { lesson: l.id } }, l.title)));
  const body = h("div", { class: "lesson", id: `lesson-${current}` });
  root.append(h("h1", {}, "Lessons"), tabs, body);
  const module = await import(`../lessons/${current}.js`);
  body.append(prose(module.intro));
  const lessonCtx = {
    ...ctx,
    setParams(update) { ctx.setParams({ lesson: current, ...update }); },
  };
  return (await module.render(body, lessonCtx, index)) || null;
}
