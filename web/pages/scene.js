// Scene view: the arm in 3D, the camera frames, proprioception, and what the model says (Fig. 8a).

import { get, post, withQuery } from "../js/api.js";
import { h, field, help, badge, errorBox, fmt } from "../js/dom.js";
import { Cursor, viserSrc } from "../js/cursor.js";
import { mountTimeline } from "../js/timeline.js";
import { CATEGORICAL } from "../js/palette.js";
import { plotly, chart, cursorShape } from "../js/plots.js";

export const meta = { route: "scene", title: "Scene", nav: false };

const STRIP = 10; // thumbnails in the frame strip

export async function render(root, ctx) {
  const id = ctx.arg;
  if (!id) {
    root.append(errorBox("No recording given: open one from the Scenes page."));
    return;
  }
  const upload = id.startsWith("upload-");
  root.append(h("p", { class: "muted" }, `Loading ${id}…`));
  let detail, description;
  try {
    detail = await get(upload ? `/api/uploads/${id}` : `/api/scenes/${id}`);
    description = upload ? await get(`/api/uploads/${id}/description`)
      : await post(`/api/scenes/${id}/describe`);
  } catch (e) {
    root.replaceChildren(errorBox(e.message));
    return;
  }
  root.replaceChildren();
  const s = detail.summary;
  const frameUrl = (i, overlay, width) =>
    withQuery(`/api/scenes/${id}/frames/${i}.jpg`, { overlay: overlay ? "true" : null, width });

  // header: what the model said against what the teacher said
  const verdict = description.correct === null ? null
    : h("span", { class: description.correct ? "ok" : "bad" }, description.correct ? "✓ correct" : "✗ differs");
  root.append(
    h("h1", {}, upload ? `Upload ${id}` : id, " ", s ? badge(s.split) : null),
    h("div", { class: "utterances" },
      h("div", { class: "said" }, h("span", { class: "label" }, "model says ",
        help("The utterance the MultiMTRNN generated: MTRNN_s and MTRNN_v abstract the recording into c_s,T and c_v,T, the cell assemblies map them to c_a,0, and MTRNN_a produces phonemes from it, decoded to words.", "cell assembly")),
        h("q", { id: "generated" }, description.utterance || "(silence)"), " ", verdict),
      h("div", { class: "said" }, h("span", { class: "label" }, "teacher said ",
        help("What the human teacher said during the recording (absent for uploads without an utterance).", null)),
        h("q", { id: "expected" }, description.expected ?? "—")),
      h("div", { class: "muted small" }, `phonemes: ${description.phonemes.join(" ")}`),
      h("div", { class: "muted small" },
        `model ${description.model} · ${fmt(description.timings.total_ms, 1)} ms (model ${fmt(description.timings.model_ms, 1)} ms)`,
        " · ", h("a", { href: withQuery("#/csc", { space: "a", highlight: id }) }, "see it in the Csc spaces"))));

  // controls of the page's cursor
  const t0 = Math.min(Number(ctx.params.t || 0), detail.duration_s);
  const playBtn = h("button", { type: "button", id: "play" }, "▶ play");
  const slider = h("input", { type: "range", id: "time", min: 0, max: detail.duration_s, step: 1 / detail.fps, value: t0 });
  const timeLabel = h("span", { class: "time", id: "time-label" }, "0.00 s");
  const speed = h("select", { id: "speed" }, [0.25, 0.5, 1, 2, 4].map((x) => h("option", { value: x, selected: x === 1 }, `${x}×`)));
  const overlay = h("input", { type: "checkbox", id: "overlay", checked: ctx.params.overlay === "1" });
  const phonemeNow = h("span", { class: "phoneme-now", id: "phoneme-now" }, "–");
  const controls = h("div", { class: "controls" },
    h("span", { class: "field" }, playBtn, help("Play or pause the recording. The 3D arm, the camera frame, the plots and the phoneme follow one time cursor, this page's own: these controls are the only ones that move it (add view=<id> to the page's address to share one 3D view between tabs).", null)),
    field("time", slider, "Scrub through the recording (seconds at 20 frames per second).", null),
    timeLabel,
    field("speed", speed, "Replay speed.", null),
    field("vision pipeline", overlay, "Draw what the vision encoder extracts from the camera frame (Fig. 7): the object's contour, its centre of mass and the 16 salient distances.", "vision features"),
    h("span", { class: "field" }, "producing ", phonemeNow, help("The phoneme MTRNN_a produces at the cursor. The utterance is generated after perception; here its time is stretched over the recording's so both can be scanned together.", "phoneme")));

  // 3D view and camera
  const iframe = h("iframe", { src: viserSrc(), class: "viser", title: "3D view of the NAO arm (viser)", id: "viser-frame" });
  const frameImg = h("img", { class: "camera", id: "camera-frame", alt: "camera frame", src: frameUrl(0, overlay.checked) });
  const strip = h("div", { class: "strip", id: "frame-strip" });
  for (let k = 0; k < STRIP; k++) {
    const i = Math.round((k * (detail.frames - 1)) / (STRIP - 1));
    strip.append(h("img", { src: frameUrl(i, false, 96), alt: `frame ${i}`, title: `t = ${(i / detail.fps).toFixed(2)} s`,
      onclick: () => cursor.seek(i / detail.fps) }));
  }
  const timelineBox = h("section", { class: "panel", id: "timeline" });
  root.append(controls, timelineBox,
    h("div", { class: "grid2" },
      h("section", { class: "panel" }, h("h2", {}, "3D ", help("The NAO's right arm replaying the recorded joint angles over the table, with the object in its colour and shape. Drag to orbit, scroll to zoom.", "proprioception")), iframe),
      h("section", { class: "panel" }, h("h2", {}, "Camera ", help("What the robot's camera saw at the cursor; the strip below shows the whole recording (click a thumbnail to jump there).", "vision features")), frameImg, strip)));

  const timelineReady = mountTimeline(timelineBox, id, (t) => cursor.seek(t), t0);

  // plots
  const propPlot = h("div", { class: "plot", id: "prop-plot" });
  const visPlot = h("div", { class: "plot", id: "vis-plot" });
  const outPlot = h("div", { class: "plot tall", id: "activity-plot" });
  const targetPlot = h("div", { class: "plot tall", id: "target-plot" });
  root.append(
    h("div", { class: "grid2" },
      h("section", { class: "panel" }, h("h2", {}, "Proprioception ", help("The five joint angles scaled to [0, 1] by the NAO's joint limits: MTRNN_s's input, one step per frame.", "proprioception")), propPlot),
      h("section", { class: "panel" }, h("h2", {}, "Vision features ", help("Per frame: 16 shape distances, mean R, G, B (MTRNN_v's 19 inputs) and the centroid.", "vision features")), visPlot)),
    h("div", { class: "grid2" },
      h("section", { class: "panel" }, h("h2", {}, "Output activity ", help("Softmax activity of MTRNN_a's 43 output neurons (one per phoneme or sign) over its time steps, as in the paper's Fig. 8a.", "phoneme")), outPlot),
      h("section", { class: "panel" }, h("h2", {}, "Target ", help("The ideal activity of the teacher's utterance: a Gaussian spike per phoneme, softmax-normalised (eqs. 18-21).", "phoneme")), targetPlot)));

  const Plotly = await plotly();
  const times = detail.joints.map((_, i) => i / detail.fps);
  await chart(propPlot, detail.joint_names.map((name, j) => ({
    x: times, y: detail.proprioception.map((r) => r[j]), name, mode: "lines", line: { color: CATEGORICAL[j] },
  })), { height: 280, title: "Proprioception: joint angles scaled by the joint limits",
    xaxis: { title: "time (s)" }, yaxis: { title: "scaled angle (0-1)", range: [0, 1] }, shapes: [cursorShape(t0)],
    legend: { orientation: "h", y: -0.35, title: "joint" } });
  await chart(visPlot, [{ type: "heatmap", x: times, y: detail.vision_feature_names,
    z: detail.vision_feature_names.map((_, f) => detail.vision.map((r) => r[f])), colorscale: "Viridis", showscale: false }],
  { height: 280, title: "Vision features per frame (16 distances, mean RGB, centroid)", shapes: [cursorShape(t0)],
    xaxis: { title: "time (s)" }, yaxis: { title: "feature", autorange: "reversed" } });
  const labels = description.phoneme_labels;
  const steps = description.activity.length;
  const heat = (act) => [{ type: "heatmap", y: labels, z: labels.map((_, k) => act.map((r) => r[k])),
    colorscale: "Greys", reversescale: true, zmin: 0, zmax: 1, showscale: false }];
  const heatLayout = (title) => ({ height: 520, title, xaxis: { title: "time step of MTRNN_a" },
    yaxis: { title: "output neuron (phoneme)", autorange: "reversed", dtick: 1, tickfont: { size: 9 } },
    shapes: [cursorShape(0)] });
  await chart(outPlot, heat(description.activity), heatLayout("What the model says: MTRNN_a's softmax output"));
  if (description.target_activity) {
    await chart(targetPlot, heat(description.target_activity), heatLayout("What the teacher said: the target activity"));
  } else targetPlot.append(h("p", { class: "muted" }, "No utterance in this recording, so no target."));

  // following the cursor
  let shownFrame = -1, loading = false, lastPlot = 0, pendingFrame = null;
  const loadFrame = (i) => {
    if (loading) { pendingFrame = i; return; }
    loading = true;
    frameImg.src = frameUrl(i, overlay.checked);
  };
  frameImg.addEventListener("load", () => { loading = false; if (pendingFrame !== null) { const i = pendingFrame; pendingFrame = null; loadFrame(i); } });
  frameImg.addEventListener("error", () => { loading = false; });
  overlay.addEventListener("change", () => { ctx.setParams({ overlay: overlay.checked ? "1" : "" }); loadFrame(Math.max(shownFrame, 0)); });

  function onChange(state) {
    const t = state.t;
    const i = Math.min(Math.round(t * detail.fps), detail.frames - 1);
    slider.value = t;
    timeLabel.textContent = `${t.toFixed(2)} s`;
    playBtn.textContent = state.playing ? "❚❚ pause" : "▶ play";
    speed.value = String(state.speed);
    if (i !== shownFrame) { shownFrame = i; loadFrame(i); }
    const step = Math.min(Math.round((t / Math.max(detail.duration_s, 1e-6)) * (steps - 1)), steps - 1);
    const row = description.activity[step];
    let best = 0;
    row.forEach((v, k) => { if (v > row[best]) best = k; });
    phonemeNow.textContent = row[best] >= 0.3 ? labels[best] : "·";
    timeline.follow(t, state.playing);
    const now = performance.now();
    if (!state.playing || now - lastPlot > 150) {
      lastPlot = now;
      Plotly.relayout(propPlot, { shapes: [cursorShape(t)] });
      Plotly.relayout(visPlot, { shapes: [cursorShape(t)] });
      Plotly.relayout(outPlot, { shapes: [cursorShape(step)] });
      if (description.target_activity) Plotly.relayout(targetPlot, { shapes: [cursorShape(step)] });
    }
    if (!state.playing) ctx.setParams({ t: t > 0 ? t.toFixed(2) : "" });
  }

  const timeline = await timelineReady;
  const cursor = new Cursor(id, detail.duration_s, detail.fps, onChange);
  playBtn.addEventListener("click", () => (cursor.state.playing ? cursor.pause() : cursor.play()));
  slider.addEventListener("input", () => cursor.seek(Number(slider.value)));
  speed.addEventListener("change", () => cursor.speed(Number(speed.value)));
  const viewer = await cursor.connect(t0);
  if (!viewer) iframe.replaceWith(h("p", { class: "muted" }, cursor.reason || "The 3D viewer is not running in this server."));
  onChange({ ...cursor.state, t: t0 });
  return () => cursor.close();
}
