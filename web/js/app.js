// The app shell, the only router: a hash router and a navigation built from the page modules the
// server lists.
//
// A page is a module in web/pages/ exporting
//   meta = { route: "scenes", title: "Scenes", order: 10, nav: true }
//   render(root, ctx) -> optional cleanup function
// where ctx.params holds the URL's query (#/route/arg?key=value), ctx.arg the path argument,
// ctx.setParams({...}) rewrites the URL without re-rendering (views stay addressable), and
// ctx.modelsChanged() refreshes the header's model selector after a page changed the served model.
// Adding a page is adding a file: GET /api/pages lists web/pages/*.js.

import { get, put, withQuery } from "./api.js";
import { h, errorBox, help } from "./dom.js";

const pages = new Map();
let cleanup = null;

function parseHash() {
  const raw = location.hash.replace(/^#\/?/, "");
  const [path, query = ""] = raw.split("?");
  const [route, ...rest] = path.split("/");
  return { route: route || "scenes", arg: rest.length ? decodeURIComponent(rest.join("/")) : null,
           params: Object.fromEntries(new URLSearchParams(query)) };
}

// The URL of a view: an empty parameter is one not set.
function hashFor(route, arg, params) {
  const set = Object.fromEntries(Object.entries(params).filter(([, v]) => v !== ""));
  return withQuery(`#/${route}${arg ? "/" + encodeURIComponent(arg) : ""}`, set);
}

async function loadPages() {
  const { pages: names } = await get("/api/pages");
  const modules = await Promise.all(names.map((n) => import(`/pages/${n}.js`)));
  modules.forEach((m) => pages.set(m.meta.route, m));
  const nav = document.getElementById("nav");
  [...pages.values()].filter((m) => m.meta.nav !== false)
    .sort((a, b) => (a.meta.order ?? 100) - (b.meta.order ?? 100))
    .forEach((m) => nav.append(h("a", { href: `#/${m.meta.route}`, dataset: { route: m.meta.route },
      title: m.meta.description || m.meta.title }, m.meta.title)));
}

async function render() {
  const { route, arg, params } = parseHash();
  if (cleanup) { try { cleanup(); } catch (e) { console.error(e); } cleanup = null; }
  const root = document.getElementById("app");
  root.replaceChildren();
  document.querySelectorAll("#nav a").forEach((a) =>
    a.classList.toggle("active", a.dataset.route === route || (route === "scene" && a.dataset.route === "scenes")));
  const page = pages.get(route);
  if (!page) {
    root.append(errorBox(`No page "${route}".`));
    return;
  }
  document.title = `${page.meta.title} · MultiMTRNN explorer`;
  const ctx = {
    route, arg, params,
    setParams(update) {
      Object.assign(params, update);
      history.replaceState(null, "", hashFor(route, arg, params));
    },
    modelsChanged: modelSelector,
  };
  try {
    cleanup = (await page.render(root, ctx)) || null;
  } catch (e) {
    console.error(e);
    root.append(errorBox(e.message || String(e)));
  }
}

// The served model, switchable: every later answer (describe, Csc, generate) comes from it.
async function modelSelector() {
  const { selected, models } = await get("/api/models");
  const select = h("select", { id: "model", "aria-label": "served model" },
    models.map((m) => h("option", { value: m.name, selected: m.name === selected },
      `${m.name}${m.meta.mode ? ` (${m.meta.mode})` : ""}`)));
  select.addEventListener("change", async () => {
    select.disabled = true;
    try {
      await put("/api/models/selected", { name: select.value });
      await render();
    } catch (e) {
      document.getElementById("app").prepend(errorBox(e.message));
    } finally {
      select.disabled = false;
    }
  });
  document.getElementById("model-badge").replaceChildren("model ", select,
    help("The trained MultiMTRNN that answers: each is a checkpoint in data/artefacts/models (weights + meta.json). Switching it changes every description, Csc plot and generation.", null));
}

async function start() {
  try {
    await loadPages();
    await modelSelector();
  } catch (e) {
    document.getElementById("app").replaceChildren(errorBox(`The server did not answer: ${e.message}`));
    return;
  }
  window.addEventListener("hashchange", render);
  await render();
}

start();
