// Upload: describe your own recording (format v1: .zip or .npz) by drag and drop or file picker.

import { upload, get } from "../js/api.js";
import { h, help, errorBox, fmt } from "../js/dom.js";

export const meta = { route: "upload", title: "Upload", order: 20,
  description: "describe your own recording (.zip or .npz, format v1)" };

export async function render(root) {
  const input = h("input", { type: "file", id: "recording-file", accept: ".zip,.npz", name: "recording" });
  const drop = h("div", { class: "dropzone", id: "dropzone", tabindex: 0 },
    h("p", {}, "Drop a recording here (.zip or .npz, format v1)"),
    h("p", { class: "muted" }, "or choose a file: "), input,
    help("Format v1: a .zip with joints.csv (t + the five right-arm joints in radians), camera frames as video.mp4 or frames/*.png and an optional meta.json with the utterance; or a .npz with 'joints' (T x 5) and 'frames' (T x H x W x 3, RGB). `mtrnn corpus export` writes examples.", null));
  const status = h("div", { id: "upload-status", "aria-live": "polite" });
  root.append(h("h1", {}, "Upload a recording"),
    h("p", { class: "lead" }, "The recording goes through the same encoders as the corpus (proprioception, the vision pipeline) and the served model describes it."),
    drop, status);

  async function send(file) {
    status.replaceChildren(h("p", { class: "muted" }, `Uploading ${file.name} (${(file.size / 2 ** 20).toFixed(1)} MiB)…`));
    try {
      const d = await upload("/api/describe", "recording", file);
      const detail = await get(`/api/uploads/${d.id}`);
      const thumbs = [0, Math.floor(detail.frames / 2), detail.frames - 1].map((i) =>
        h("img", { src: `/api/scenes/${d.id}/frames/${i}.jpg?width=160`, alt: `frame ${i}` }));
      status.replaceChildren(h("section", { class: "panel preview", id: "upload-preview" },
        h("h2", {}, file.name),
        h("div", { class: "strip" }, thumbs),
        h("p", {}, `${detail.frames} frames at ${detail.fps} fps (${detail.duration_s.toFixed(1)} s)`),
        h("p", { class: "said" }, h("span", { class: "label" }, "model says "), h("q", { id: "upload-utterance" }, d.utterance || "(silence)"),
          d.correct === null ? null : h("span", { class: d.correct ? "ok" : "bad" }, d.correct ? " ✓" : " ✗")),
        d.expected ? h("p", { class: "said" }, h("span", { class: "label" }, "teacher said "), h("q", {}, d.expected)) : null,
        h("p", { class: "muted small" }, `read ${fmt(d.timings.read_ms, 0)} ms · encode ${fmt(d.timings.encode_ms, 0)} ms · model ${fmt(d.timings.model_ms, 0)} ms`),
        h("a", { class: "button", href: `#/scene/${d.id}`, id: "open-upload" }, "Open in the scene view")));
    } catch (e) {
      status.replaceChildren(errorBox(`${file.name}: ${e.message}`));
    }
  }
  input.addEventListener("change", () => input.files.length && send(input.files[0]));
  drop.addEventListener("dragover", (e) => { e.preventDefault(); drop.classList.add("over"); });
  drop.addEventListener("dragleave", () => drop.classList.remove("over"));
  drop.addEventListener("drop", (e) => {
    e.preventDefault();
    drop.classList.remove("over");
    if (e.dataTransfer.files.length) send(e.dataTransfer.files[0]);
  });
}
