// Hosts the lessons page on its own at /lessons/ (same URL state as inside the app: #/lessons?...).

import { render } from "./lessons.js";

let cleanup = null;

function parse() {
  const raw = location.hash.replace(/^#\/?/, "");
  const [, query = ""] = raw.split("?");
  return Object.fromEntries(new URLSearchParams(query));
}

async function show() {
  const route = location.hash.replace(/^#\/?/, "").split(/[/?]/)[0];
  if (route && route !== "lessons") { // e.g. a "?" button's glossary link: the app's own pages
    location.href = `/${location.hash}`;
    return;
  }
  if (cleanup) { try { cleanup(); } catch (e) { console.error(e); } cleanup = null; }
  const root = document.getElementById("app");
  root.replaceChildren();
  const params = parse();
  const ctx = {
    route: "lessons", arg: null, params,
    setParams(update) {
      Object.assign(params, update);
      const q = new URLSearchParams(Object.entries(params).filter(([, v]) => v !== undefined && v !== null && v !== ""));
      history.replaceState(null, "", `#/lessons?${q}`);
    },
  };
  cleanup = await render(root, ctx);
}

window.addEventListener("hashchange", show);
show();
