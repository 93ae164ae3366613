// Upload: describe your own recording (format v1: .zip or .npz) by drag and drop or file picker, or
// try one of the server's examples (GET /api/examples) in one click; the format explained in place.

import { upload, get, download } from "../js/api.js";
import { h, help, errorBox, fmt } from "../js/dom.js";

export const meta = { route: "upload", title: "Upload", order: 20,
  description: "describe your own recording (.zip or .npz, format v1), or try an example" };

const FORMAT_HELP = "Format v1: a .zip with joints.csv (t + the five right-arm joints in radians), camera frames as video.mp4 or frames/*.png and an optional meta.json with the utterance; or a .npz with 'joints' (T x 5) and 'frames' (T x H x W x 3, RGB). `mtrnn corpus export` writes examples.";

// Format v1 in short (docs/recording-format.md has it all: limits, timing, errors).
function formatSection() {
  const code = (t) => h("code", {}, t);
  return h("details", { class: "panel format", id: "format-v1" },
    h("summary", {}, h("h2", { class: "inline" }, "What a recording is: format v1")),
    h("p", {}, "One interaction of the NAO's right arm with an object on a table: the arm's five joint angles over time, the robot camera's frames over the same time, and optionally the sentence a teacher said. Two containers, whichever is easier:"),
    h("ul", {},
      h("li", {}, h("b", {}, "a .zip"), " holding ", code("joints.csv"), " (header ", code("t,RShoulderPitch,RShoulderRoll,RElbowYaw,RElbowRoll,RWristYaw"),
        "; t in seconds, strictly increasing, angles in radians within the NAO's limits), the frames as ", code("video.mp4"), " / ", code("video.avi"),
        " or ", code("frames/0000.png"), ", ", code("frames/0001.png"), " … (not both), and optionally ", code('meta.json: {"utterance": "slide the red apple.", "fps": 20}'), ";"),
      h("li", {}, h("b", {}, "a .npz"), " (", code("np.savez"), ") with ", code("joints"), " (T × 5 float, radians, the order above) and ",
        code("frames"), " (T × H × W × 3 uint8, RGB), optionally ", code("utterance"), ".")),
    h("p", {}, "Any joint rate works: the joints are interpolated onto the model's 20 Hz grid and each step takes the nearest frame (frames spread evenly over the joints' time span unless meta.json gives their fps). Frames are colour images from 32 pixels a side up to 1920 × 1080; the corpus uses 320 × 240 from a camera looking down at a plain table. Download an example below to see one."),
    h("p", {}, "The full specification, with every limit and error message: ",
      h("a", { href: "/docs/recording-format.md", id: "format-link" }, "docs/recording-format.md"), "."));
}

function exampleItem(ex, onTry) {
  const tryIt = h("button", { type: "button", class: "try-example", dataset: { example: ex.name } }, "try this one");
  tryIt.addEventListener("click", () => onTry(ex, tryIt));
  return h("li", { class: "example", dataset: { example: ex.name } },
    h("div", {}, h("b", {}, ex.title), " ", h("span", { class: `badge badge-${ex.kind}` }, ex.kind === "corpus" ? "from the corpus" : "unlike the corpus")),
    h("p", { class: "small" }, ex.description),
    h("div", { class: "example-actions" }, tryIt,
      h("a", { href: ex.url, download: `${ex.name}.zip`, class: "download" }, `download ${ex.name}.zip`)));
}

const FAMILIARITY_HELP = "How far this recording lies from the recordings the model learned from, per sense: the share of the model's own training recordings that lie at least as far from their nearest neighbour (of another scene). 100 % is like a training recording, about 50 % like a new scene of the corpus, near 0 % farther than all of them: the description is then a guess.";
const SENSES = [["proprioception", "arm (proprioception)"], ["vision", "camera (vision)"]];

// How familiar the recording is to the model (its meters carry the number as text too), and the
// warnings of the answer (unlike what the model learned from, words it cannot say).
function familiaritySection(d) {
  const meters = d.familiarity === null ? [h("p", { class: "muted small" }, "The served model has no familiarity: its training recordings are not at hand.")]
    : SENSES.map(([key, label]) => {
      const value = d.familiarity[key];
      const id = `familiarity-${key}`;
      return h("div", { class: "familiarity-row" },
        h("label", { for: id }, `${label} `),
        h("meter", { id, min: 0, max: 1, low: 0.05, high: 0.5, optimum: 1, value }),
        h("span", { class: "familiarity-value", dataset: { sense: key } }, ` ${Math.round(100 * value)} %`));
    });
  const warnings = d.warnings.length
    ? h("ul", { id: "upload-warnings", class: "warnings", "aria-label": "warnings" }, d.warnings.map((w) => h("li", {}, `⚠ ${w}`)))
    : null;
  return h("div", { class: "familiarity", id: "upload-familiarity" },
    h("h3", {}, "How familiar this recording is to the model ", help(FAMILIARITY_HELP, null)), ...meters, warnings);
}

function preview(name, d, detail) {
  const thumbs = [0, Math.floor(detail.frames / 2), detail.frames - 1].map((i) =>
    h("img", { src: `/api/scenes/${d.id}/frames/${i}.jpg?width=160`, alt: `camera frame ${i} of ${name}` }));
  return h("section", { class: "panel preview", id: "upload-preview" },
    h("h2", {}, name),
    h("div", { class: "strip" }, thumbs),
    h("p", {}, `${detail.frames} frames at ${detail.fps} fps (${detail.duration_s.toFixed(1)} s)`),
    h("p", { class: "said" }, h("span", { class: "label" }, "model says "), h("q", { id: "upload-utterance" }, d.utterance || "(silence)"),
      d.correct === null ? null : h("span", { class: d.correct ? "ok" : "bad" }, d.correct ? " ✓ right" : " ✗ wrong")),
    d.expected ? h("p", { class: "said" }, h("span", { class: "label" }, "teacher said "), h("q", { id: "upload-expected" }, d.expected)) : null,
    familiaritySection(d),
    h("p", { class: "muted small" }, `read ${fmt(d.timings.read_ms, 0)} ms · encode ${fmt(d.timings.encode_ms, 0)} ms · model ${fmt(d.timings.model_ms, 0)} ms`),
    h("a", { class: "button", href: `#/scene/${d.id}`, id: "open-upload" }, "Open in the scene view"));
}

export async function render(root) {
  const input = h("input", { type: "file", id: "recording-file", accept: ".zip,.npz", name: "recording" });
  const drop = h("div", { class: "dropzone", id: "dropzone" },
    h("p", {}, "Drop a recording here (.zip or .npz, format v1)"),
    h("p", {}, h("label", { for: "recording-file", class: "field-label" }, "or choose a file: "), input, " ", help(FORMAT_HELP, null)));
  const status = h("div", { id: "upload-status", "aria-live": "polite" });
  const examples = h("ul", { class: "examples", id: "examples" });
  root.append(h("h1", {}, "Upload a recording"),
    h("p", { class: "lead" }, "The recording goes through the same encoders as the corpus (proprioception, the vision pipeline) and the served model describes it. No robot at hand? Try one of the examples below."),
    drop, status,
    h("section", { class: "examples-box" }, h("h2", {}, "Examples to try ",
      help("Recordings the server makes for you: corpus recordings of each action, and some made outside what the corpus samples (another camera, lighting, teacher tempo, resolution). “try this one” uploads it here and shows what the model says; the link downloads the .zip to look inside.", null)),
    examples),
    formatSection());

  async function send(file) {
    status.replaceChildren(h("p", { class: "muted" }, `Uploading ${file.name} (${(file.size / 2 ** 20).toFixed(1)} MiB)…`));
    try {
      const d = await upload("/api/describe", "recording", file);
      const detail = await get(`/api/uploads/${d.id}`);
      status.replaceChildren(preview(file.name, d, detail));
    } catch (e) {
      status.replaceChildren(errorBox(`${file.name}: ${e.message}`));
    }
  }

  async function tryExample(ex, button) {
    button.disabled = true;
    status.replaceChildren(h("p", { class: "muted" }, `Fetching ${ex.name}.zip (made on its first request: a second or two)…`));
    try {
      await send(await download(ex.url, `${ex.name}.zip`));
      status.scrollIntoView({ block: "nearest" });
    } catch (e) {
      status.replaceChildren(errorBox(`${ex.name}: ${e.message}`));
    } finally {
      button.disabled = false;
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

  try {
    const { examples: list } = await get("/api/examples");
    examples.replaceChildren(...list.map((ex) => exampleItem(ex, tryExample)));
  } catch (e) {
    examples.replaceChildren(h("li", {}, errorBox(`The examples are not available: ${e.message}`)));
  }
}
