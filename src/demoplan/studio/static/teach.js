// The Teach view: demonstrations recorded step by step, saved in the project's format; the work folder's files.

import { get, post } from "./api.js";
import { $, SHAPES_IN_SCENES, alarm, clone, fmt, plural, say, state } from "./common.js";
import { refreshFiles } from "./files.js";
import { keepSource, renderThings, showSource } from "./objects.js";
import { cover, corners, redraw, registerView, sameObjects, sceneChanged, table, tableRoom } from "./stage.js";

// --- teach ----------------------------------------------------------------

export function renderSteps() {
  const list = $("steps");
  list.replaceChildren();
  for (const step of state.teach.steps) {
    const li = document.createElement("li");
    li.dataset.moved = step.object; // not data-object: that names the table's elements only
    const [x, y, z] = step.position;
    li.textContent = `${step.object} → (${fmt(x, 4)}, ${fmt(y, 4)}, ${fmt(z, 4)}) yaw ${fmt(step.yaw, 1)}°` +
      (step.on ? ` on ${step.on}` : "");
    list.appendChild(li);
  }
  $("undo").disabled = state.teach.steps.length === 0;
}

export function startDemonstration(layout, note) {
  if (state.layout && sameObjects(state.layout, layout)) {
    layout.table = cover(layout.table, corners(state.layout.table), 0);
  }
  layout.table = cover(layout.table, layout.poses);
  state.layout = layout;
  state.teach.initial = clone(layout.poses);
  state.teach.poses = clone(layout.poses);
  state.teach.steps = [];
  state.teach.saved = false;
  state.teach.edited = false;
  state.plan.poses = null;
  state.plan.landmarks = null;
  state.plan.extras = null;
  state.clutter = [];
  state.selected = null;
  sceneChanged();
  table.setLayout(layout, tableRoom());
  renderSteps();
  renderThings();
  redraw();
  say(note);
}

// Each New demonstration is numbered: only the latest one's answer is shown
// (a template chosen while the last one loads must not show the old objects).
let asked = 0;

export async function newDemonstration() {
  const ticket = ++asked;
  const source = clone(state.source);
  const randomise = $("randomise").checked;
  const seed = Number($("seed").value) || 0;
  let layout;
  if (source.kind === "template") {
    const query = randomise ? `?seed=${seed}` : "";
    layout = await get(`/api/templates/${encodeURIComponent(source.id)}${query}`);
  } else {
    layout = (await get(`/api/files/${encodeURIComponent(source.name)}`)).layout;
    if (randomise && Object.keys(layout.objects).length) layout = await post("/api/scramble", { layout, seed });
  }
  if (ticket !== asked) return; // a later New demonstration (another template) is on its way
  if (randomise) $("seed").value = String(seed + 1);
  const unsaved = state.teach.steps.length && !state.teach.saved ? ` (${plural(state.teach.steps.length, "unsaved step")} discarded)` : "";
  const from = source.kind === "template" ? `template ${source.id}` : source.name;
  startDemonstration(layout, `New demonstration from ${from}${randomise ? `, randomised (seed ${seed})` : ""}${unsaved}.`);
}

// A template chosen: the Teach view starts from it (also after a reload).
export async function useTemplate(id) {
  state.source = { kind: "template", id };
  showSource();
  await newDemonstration();
  await keepSource();
}

export function undo() {
  const step = state.teach.steps.pop();
  if (!step) return;
  state.teach.poses[step.object] = step.before;
  state.teach.saved = false;
  renderSteps();
  redraw();
  say(`undone: ${step.object} is back at x ${fmt(step.before.position[0])}, y ${fmt(step.before.position[1])} m`);
}

export function poseDocument(pose) {
  return { position: pose.position.map((v) => Math.round(v * 1e6) / 1e6), yaw: Math.round((pose.yaw || 0) * 1000) / 1000 };
}

export function landmarksDocument(marks = null) {
  const out = {};
  for (const [name, mark] of Object.entries(marks || state.layout.landmarks || {})) {
    out[name] = { ...poseDocument(mark), shape: mark.shape || "box" };
    if (mark.size) out[name].size = mark.size;
    if (mark.colour) out[name].colour = mark.colour; // every figure of the task draws it
  }
  return out;
}

export function demonstrationDocument() {
  const objects = {};
  for (const [name, geometry] of Object.entries(state.layout.objects)) {
    if (state.clutter.includes(name)) continue;
    objects[name] = { shape: geometry.shape, size: geometry.size };
    for (const key of ["type", "mass", "density", "colour"]) if (geometry[key] != null) objects[name][key] = geometry[key];
  }
  const initial = {};
  for (const [name, pose] of Object.entries(state.teach.initial)) initial[name] = poseDocument(pose);
  const document_ = { format: "demoplan/demonstration-1", objects, initial, steps: [] };
  const landmarks = landmarksDocument();
  if (Object.keys(landmarks).length) document_.landmarks = landmarks;
  document_.steps = state.teach.steps.map((s) => ({ object: s.object, ...poseDocument(s) }));
  return document_;
}

export async function save() {
  if (!state.teach.steps.length) {
    alarm("nothing to save: move at least one object first (each release is one step)");
    return;
  }
  const name = $("save-name").value.trim() || null;
  const answer = await post("/api/demonstrations", { document: demonstrationDocument(), name });
  state.teach.saved = true;
  $("save-name").value = "";
  const marks = Object.keys(state.layout.landmarks || {});
  const next = marks.length
    ? ` Press New demonstration, then move the ${marks.join(" or ")} between demonstrations (moving it is not a step).`
    : "";
  say(`Saved ${answer.file} (${plural(state.teach.steps.length, "step")}).${next}`);
  await refreshFiles();
}

export async function loadFile() {
  const name = $("file").value;
  if (!name) {
    alarm("choose a file of the work folder first");
    return;
  }
  const answer = await get(`/api/files/${encodeURIComponent(name)}`);
  if (!answer.layout) {
    alarm(`${name}: not a demonstration or a scene; a model is chosen in the Plan view`);
    return;
  }
  state.source = { kind: "file", name };
  startDemonstration(answer.layout, `Loaded ${name}: its initial layout is on the table.`);
  await keepSource();
}

// The table as it stands in the Teach view, as a scene (the Learn view draws
// the learned targets in it: where the landmarks stand now).
export function teachSceneDocument() {
  const objects = {};
  for (const [name, geometry] of Object.entries(state.layout.objects)) {
    const pose = state.teach.poses[name];
    if (!pose || state.clutter.includes(name)) continue;
    objects[name] = { ...poseDocument(pose), size: geometry.size };
    if (SHAPES_IN_SCENES.has(geometry.shape)) objects[name].shape = geometry.shape;
    if (geometry.type != null) objects[name].type = geometry.type;
    if (geometry.colour) objects[name].colour = geometry.colour;
  }
  const scene = { objects };
  const landmarks = landmarksDocument();
  if (Object.keys(landmarks).length) scene.landmarks = landmarks;
  return scene;
}

registerView("teach", { stepsChanged: renderSteps });
