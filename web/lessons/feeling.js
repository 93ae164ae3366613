// Lesson 4: feeling. Proprioception of one action on the four objects overlaid, the hand's path
// beside the joint angles, one time cursor shared with the 3D arm (the app's viser view) and both
// plots, and why touch alone cannot tell objects apart.

import { get } from "../js/api.js";
import { h, errorBox } from "../js/dom.js";
import { Cursor, viserSrc } from "../js/cursor.js";
import { ACTIONS, OBJECT_COLOURS, SHAPE_COLOURS } from "../js/palette.js";
import { plotly, chart, cursorShape } from "../js/plots.js";
import { control, controls, tryThis, latest, slider, select, num } from "./common.js";

export const intro = [
  "Proprioception is the body's sense of itself: here the five joint angles of the NAO's right arm, 20 times a second, scaled to [0, 1] by the joint limits. It is what the paper's MTRNN_s reads. Pick an action and a colour: the plots overlay the same action on the four shapes. The 3D arm replays one of them; the red line in both plots is one time cursor shared with it, and this page's controls are the only ones that move it.",
  "The paper's MTRNN_s reads these joint angles. But the arm has five joints for the three coordinates of the hand, so the same hand path can be reached with other joint angles: another teacher, robot or simulator holds the arm differently for the same movement. The training option hand_path (end_to_end) gives MTRNN_s the hand's path instead, or beside the angles, computed from the angles by forward kinematics in the torso frame, which does not depend on how the arm was held. The second plot shows that path; the note above it says which of the two the served model reads.",
  "All the objects have about the same mass and friction (paper 4.1), so the arm moves much the same whatever it is moving. The table below measures it: how different the joint trajectories are, and how far apart the model's abstracted contexts c_s,T (touch) and c_v,T (vision) land.",
];

// The hand path's three panels (torso frame, Aldebaran's convention) and what MTRNN_s reads.
const HAND_AXES = [{ label: "forward x (cm)" }, { label: "left y (cm)" }, { label: "up z (cm)" }];
const READS = {
  joints: "The served model's MTRNN_s reads the joint angles, as in the paper (option hand_path = joints).",
  "joints+hand": "The served model's MTRNN_s reads the joint angles and, beside them, this hand path (option hand_path = joints+hand).",
  hand: "The served model's MTRNN_s reads this hand path instead of the joint angles (option hand_path = hand).",
};
const MOTION = {
  none: "",
  visual: " Its MTRNN_v reads the object's motion in the image (its centroid relative to the first frame's) instead of where the object lies (option object_motion = visual).",
  somatosensory: " Beside it, MTRNN_s reads the object's motion in the image (its centroid relative to the first frame's): a pull brings the object nearer, a push sends it away, whatever the arm's posture (option object_motion = somatosensory).",
};

const axis = (k) => (k ? String(k + 1) : "");

// The shared time cursor at t on each of n stacked panels.
function cursorShapes(n, t) {
  return [...Array(n).keys()].map((k) => ({ ...cursorShape(t, `y${axis(k)} domain`), xref: `x${axis(k)}` }));
}

// One line per recording and panel: series[i][key] is [panels][T], sampled at series[i].fps.
function stackedTraces(series, key, panels) {
  const traces = [];
  for (let k = 0; k < panels; k += 1) {
    series.forEach((s) => {
      traces.push({ x: s[key][k].map((_, i) => i / s.fps), y: s[key][k], xaxis: `x${axis(k)}`, yaxis: `y${axis(k)}`, mode: "lines",
        name: s.shape, legendgroup: s.shape, showlegend: k === 0, line: { color: SHAPE_COLOURS[s.shape], width: 2 } });
    });
  }
  return traces;
}

// Panels stacked over one shared time axis; panels[k] = { label, range? }.
function stackedLayout(title, panels) {
  const last = panels.length - 1;
  const layout = { grid: { rows: panels.length, columns: 1, shared_xaxes: true, pattern: "independent" }, title,
    legend: { orientation: "h", y: 1.06, title: { text: "object shape" } }, margin: { l: 110, r: 10, t: 70, b: 45 } };
  panels.forEach((p, k) => {
    layout[`yaxis${axis(k)}`] = { title: { text: p.label, font: { size: 10 } }, range: p.range };
    layout[`xaxis${axis(k)}`] = { matches: k ? "x" : undefined, showticklabels: k === last, title: k === last ? { text: "time (s)" } : undefined };
  });
  return layout;
}

export async function render(root, ctx) {
  const Plotly = await plotly();
  const action = select("action", ACTIONS, ACTIONS.includes(ctx.params.action) ? ctx.params.action : "push");
  const colour = select("colour", OBJECT_COLOURS, OBJECT_COLOURS.includes(ctx.params.colour) ? ctx.params.colour : "red");
  const shown = select("shown", [], "");
  const time = slider("time", 0, 1, 0.05, Number(ctx.params.t || 0));
  const timeValue = h("span", { class: "value time", id: "time-value" }, "0.00 s");
  const error = h("div", { id: "feeling-error" });
  const plot = h("div", { class: "plot", id: "joint-plot", style: "height:560px" });
  const handPlot = h("div", { class: "plot", id: "hand-plot", style: "height:420px" });
  const readsNote = h("p", { class: "muted", id: "reads-note" });
  const table = h("div", { id: "touch-table" });
  const viewer = await get("/api/viewer").catch(() => ({ available: false }));
  const iframe = viewer.available
    ? h("iframe", { src: viserSrc(), class: "viser", title: "3D view of the NAO arm (viser)", id: "viser-frame" })
    : h("p", { class: "muted" }, "The 3D viewer is not running in this server (started with MTRNN_VISER=0).");
  const viewerNote = h("p", { class: "muted small", id: "viewer-note" });
  let data = null;
  let cursor = null;

  root.append(
    controls(
      control(ctx, "action", "action", action, "The manipulation the teacher guided the arm through (Fig. 5b).", "proprioception"),
      control(ctx, "colour", "colour", colour, "The colour of the four objects overlaid.", null),
      control(ctx, "shown", "3D shows", shown, "Which of the four recordings the 3D arm replays.", null),
      control(ctx, "time", "time", time, "The shared time cursor, in seconds: the red line here and the arm in 3D.", null), timeValue),
    error,
    h("div", { class: "grid-plot" }, plot, h("section", { class: "panel" }, h("h2", {}, "3D arm"), iframe, viewerNote)),
    readsNote,
    handPlot,
    table,
    tryThis(ctx, "For the chosen action: is it on the red apple closer, for the arm, to the same action on the blue phone, or to another action on the same red apple? And for the eyes?",
      () => {
        if (!data || !data.comparison) return [h("p", {}, "This needs the red apple and the blue phone in the corpus.")];
        const [same, other] = data.comparison.rows;
        return [
          h("p", {}, `Comparing ${same.pair} with ${other.pair}: for the joints the two objects under the same action differ by ${num(same.joints_rms)} (RMS, joint units in [0, 1]) while the two actions on the same object differ by ${num(other.joints_rms)}; in the somatosensory context c_s,T the distances are ${num(same.c_s)} and ${num(other.c_s)}. For vision it is the other way round: c_v,T distances ${num(same.c_v)} (different object) and ${num(other.c_v)} (same object).`),
          h("p", {}, `The hand paths differ by ${num(same.hand_rms)} cm (RMS) between the two objects and by ${num(other.hand_rms)} cm between the two actions: ${same.hand_rms < other.hand_rms ? "for the hand, too, the action matters more than the object" : "here the object changes the hand's path more than the action does"}.`),
          h("p", {}, "Touch tells the action, not the object; sight tells the object, not the action. Neither sense alone can say “push the red apple”; lesson 6 shows the cell assemblies putting the two halves together."),
        ];
      }));

  function drawCursor() {
    const t = Number(time.value);
    timeValue.textContent = `${t.toFixed(2)} s`;
    ctx.setParams({ t: t.toFixed(2) });
    if (!data) return;
    Plotly.relayout(plot, { shapes: cursorShapes(data.joint_names.length, t) });
    Plotly.relayout(handPlot, { shapes: cursorShapes(HAND_AXES.length, t) });
  }

  function connectViewer() {
    if (cursor) cursor.close();
    const series = data.series.find((s) => s.id === shown.value) || data.series[0];
    const duration = (series.proprioception[0].length - 1) / series.fps;
    cursor = new Cursor(series.id, duration, series.fps, (s) => {
      if (Math.abs(Number(time.value) - s.t) > 1e-3) { time.value = s.t; drawCursor(); }
    });
    const t0 = Math.min(Number(time.value), duration);
    cursor.connect(t0).then((live) => {
      if (live) cursor.seek(t0); // keep the page's cursor when the 3D view switches recordings
      viewerNote.textContent = live ? `replaying ${series.id}; the time control above moves the arm (the 3D panel has no controls of its own)` : cursor.reason ? `${cursor.reason}: the cursor is local` : "the 3D viewer is not running in this server (MTRNN_VISER=0): the cursor is local";
    });
  }

  function draw() {
    const what = `“${action.value} the ${colour.value} …” on the four shapes`;
    const joints = data.joint_names.map((joint) => ({ label: joint, range: [0, 1] }));
    chart(plot, stackedTraces(data.series, "proprioception", joints.length),
      stackedLayout(`joint angles of ${what} (scaled to 0-1 by the joint limits)`, joints));
    chart(handPlot, stackedTraces(data.series, "hand_path", HAND_AXES.length),
      stackedLayout(`hand path of ${what} (cm from where the hand started, torso frame)`, HAND_AXES));
    readsNote.textContent = READS[data.reads] + MOTION[data.object_motion];
    const longest = Math.max(...data.series.map((s) => (s.proprioception[0].length - 1) / s.fps));
    time.max = longest.toFixed(2);
    drawCursor();
    if (!data.comparison) {
      table.replaceChildren(h("p", { class: "muted" }, "The corpus lacks the red apple or the blue phone for this action."));
      return;
    }
    table.replaceChildren(h("h2", {}, `Why touch alone cannot tell a red apple from a blue phone (model ${data.comparison.model})`),
      h("table", { class: "lesson-table", id: "touch-distances" },
        h("thead", {}, h("tr", {}, h("th", {}, "pair"), h("th", {}, "what differs"), h("th", {}, "joints RMS"), h("th", {}, "hand path RMS (cm)"), h("th", {}, "d(c_s,T) touch"), h("th", {}, "d(c_v,T) vision"))),
        h("tbody", {}, data.comparison.rows.map((r) => h("tr", {}, h("td", {}, r.pair), h("td", {}, r.what),
          h("td", { class: "num" }, num(r.joints_rms)), h("td", { class: "num" }, num(r.hand_rms)), h("td", { class: "num" }, num(r.c_s)), h("td", { class: "num" }, num(r.c_v)))))));
  }

  const load = latest(async () => {
    ctx.setParams({ action: action.value, colour: colour.value });
    try {
      data = await get("/api/lessons/feeling", { action: action.value, colour: colour.value });
      error.replaceChildren();
    } catch (e) { error.replaceChildren(errorBox(e.message)); return; }
    const wanted = ctx.params.shown && data.series.some((s) => s.id === ctx.params.shown) ? ctx.params.shown : data.series[0].id;
    shown.replaceChildren(...data.series.map((s) => h("option", { value: s.id, selected: s.id === wanted }, s.shape)));
    draw();
    connectViewer();
  });

  action.addEventListener("change", load);
  colour.addEventListener("change", load);
  shown.addEventListener("change", () => { ctx.setParams({ shown: shown.value }); connectViewer(); });
  time.addEventListener("input", () => { drawCursor(); if (cursor) cursor.seek(Number(time.value)); });
  load();
  return () => { if (cursor) cursor.close(); };
}
