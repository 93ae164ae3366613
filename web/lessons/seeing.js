// Lesson 3: seeing. The vision pipeline (Fig. 7) step by step on a corpus frame or an uploaded
// picture: original, mean shift, saturation, edges, object, contour, centre and 16 rays, features.

import { get, upload } from "../js/api.js";
import { h, errorBox } from "../js/dom.js";
import { ACCENT, COLOUR_COLOURS, NEUTRAL } from "../js/palette.js";
import { plotly, chart } from "../js/plots.js";
import { control, controls, tryThis, latest, slider, num, sceneSelect } from "./common.js";

export const intro = [
  "The robot does not see pixels the way we do: its camera frame is reduced to 19 numbers. Mean shift (Comaniciu & Meer) flattens the picture into patches of similar colour; the most saturated sizeable patch is taken for the object (patches touching the border, where the arm enters, count for less); Canny edges cut it from its neighbours; the contour finder traces its outline. From the centre of mass, the largest distance to the contour in each of 16 sectors of 22.5° describes the shape (scaled by the square root of the area, largest first: invariant to size and roughly to rotation), and the mean R, G, B inside it the colour. The centroid is kept apart.",
  "Move through the frames of a recording, change the mean-shift colour window, or upload a picture of your own.",
];

export async function render(root, ctx, index) {
  await plotly();
  const scene = sceneSelect(ctx, index);
  const frame = slider("frame", 0, 400, 1, Number(ctx.params.frame || 0));
  const frameValue = h("span", { class: "value", id: "frame-value" }, frame.value);
  const radius = slider("colour-radius", 4, 64, 2, Number(ctx.params.radius || 24));
  const radiusValue = h("span", { class: "value", id: "radius-value" }, radius.value);
  const file = h("input", { type: "file", id: "image-file", accept: "image/*" });
  const info = h("div", { class: "readout", id: "seeing-info" });
  const error = h("div", { id: "seeing-error" });
  const stages = h("div", { class: "stages", id: "stages" });
  const bars = h("div", { class: "plot", id: "feature-plot", style: "height:300px" });
  let seen = null;
  let uploaded = null;

  root.append(
    controls(
      control(ctx, "scene", "recording", scene, "A corpus recording; its camera frames are re-rendered from their seed.", "vision features"),
      control(ctx, "frame", "frame", frame, "Which camera frame (20 per second).", null), frameValue,
      control(ctx, "radius", "colour window", radius, "Mean-shift colour radius: larger merges more colours into one patch (the pipeline's default is 24).", "vision features"), radiusValue,
      control(ctx, "upload", "or your picture", file, "A PNG or JPEG: the same pipeline runs on it.", null)),
    error, info, stages, bars,
    tryThis(ctx, "Compare an apple and a banana of the same colour (pick the two recordings, same frame). Which of the 19 bars change, and which stay the same? Then compare a red and a blue apple.",
      () => {
        if (!seen) return [h("p", {}, "Wait for the pipeline to run.")];
        const f = seen.features;
        return [
          h("p", {}, `For the frame shown (${seen.source}), the 16 shape bars range from ${num(Math.max(...f.slice(0, 16)))} down to ${num(Math.min(...f.slice(0, 16)))}, starting at the longest ray (or one within 8 % of it); the colour is R ${num(f[16])}, G ${num(f[17])}, B ${num(f[18])}.`),
          h("p", {}, "Shape and colour live in separate bars: a banana's long, curved outline gives a steep fall-off from its longest ray, an apple's round one a flat profile, whatever their colour; a red and a blue apple share the shape bars and differ only in R, G, B. Nothing here says what the arm is doing: the vision features are static on purpose, so vision alone cannot tell a push from a pull (lesson 4 shows the other side)."),
        ];
      }));

  function draw() {
    info.replaceChildren(
      h("span", {}, "source: ", h("b", { id: "seeing-source" }, seen.source)),
      h("span", {}, "object found: ", h("b", { class: seen.found ? "ok" : "bad" }, seen.found ? "yes" : "no")),
      h("span", {}, "pipeline: ", h("b", { id: "pipeline-ms" }, `${num(seen.pipeline_ms, 1)} ms`)));
    stages.replaceChildren(...seen.stages.map((s, k) => h("figure", {},
      h("img", { src: s.image, alt: s.title, dataset: { stage: s.key } }), h("figcaption", {}, `${k + 1}. ${s.title}`))));
    const n = seen.feature_names.length;
    chart(bars, [{
      x: seen.feature_names, y: seen.features, type: "bar", name: "feature value",
      marker: { color: seen.feature_names.map((name, i) => (i < 16 ? ACCENT : i < 19 ? COLOUR_COLOURS[["red", "green", "blue"][i - 16]] : NEUTRAL)) },
    }], { title: { text: `the ${seen.paper_features} features MTRNN_v reads (blue: shape, R G B: colour, grey: centroid, kept apart)`, font: { size: 13 } },
      yaxis: { title: "value (scaled to 0-1)", range: [0, 1] }, xaxis: { title: "feature (d1-d16: contour distances)", tickangle: -45, range: [-0.5, n - 0.5] },
      margin: { l: 55, r: 10, t: 40, b: 95 } });
  }

  const load = latest(async () => {
    frameValue.textContent = frame.value;
    radiusValue.textContent = radius.value;
    ctx.setParams({ scene: scene.value, frame: frame.value, radius: radius.value });
    try {
      if (uploaded) {
        seen = await upload("/api/lessons/seeing", "image", uploaded, { colour_radius: radius.value });
      } else {
        seen = await get("/api/lessons/seeing", { scene: scene.value, frame: frame.value, colour_radius: radius.value });
        frame.max = seen.frames - 1;
      }
      error.replaceChildren();
    } catch (e) { error.replaceChildren(errorBox(e.message)); return; }
    draw();
  }, 80);

  const backToCorpus = () => { uploaded = null; file.value = ""; };
  scene.addEventListener("change", () => { backToCorpus(); frame.value = 0; load(); });
  frame.addEventListener("input", () => { backToCorpus(); load(); });
  radius.addEventListener("input", load);
  file.addEventListener("change", () => { if (file.files.length) { uploaded = file.files[0]; load(); } });
  load();
  return null;
}
