// The Plan view: the start scene, the plan in the CLI's words and its animation (POST /api/plan).

import { ApiError, get, post } from "./api.js";
import { $, SHAPES_IN_SCENES, alarm, clone, plural, say, state } from "./common.js";
import { DRAWN_KEYS, PLANNED_KEYS, inTableColours, keepInView, layoutWith, place, redraw, registerView, sameThings, stopAnimation } from "./stage.js";
import { snap } from "./table.js";
import { refreshFiles } from "./files.js";
import { landmarksDocument, poseDocument, startDemonstration } from "./teach.js";

// --- plan -----------------------------------------------------------------

export function ensurePlanStart() {
  if (!state.plan.poses && state.layout) state.plan.poses = clone(state.teach.poses);
  if (!state.plan.landmarks && state.layout) state.plan.landmarks = clone(state.layout.landmarks || {});
}

export function sceneDocument() {
  ensurePlanStart();
  const objects = {};
  for (const [name, geometry] of Object.entries(state.layout.objects)) {
    const pose = state.plan.poses[name];
    if (!pose) continue;
    objects[name] = { ...poseDocument(pose), size: geometry.size };
    if (SHAPES_IN_SCENES.has(geometry.shape)) objects[name].shape = geometry.shape;
    if (geometry.colour) objects[name].colour = geometry.colour; // every renderer draws it
    // a loaded scene file's masses are its own (its extras, below), not the table's
    for (const key of state.plan.extras ? ["type"] : ["mass", "density", "type"]) {
      if (geometry[key] != null) objects[name][key] = geometry[key];
    }
  }
  const extras = state.plan.extras || { scene: {}, objects: {} };
  for (const [name, fields] of Object.entries(extras.objects)) {
    if (objects[name]) Object.assign(objects[name], fields);
  }
  const scene = { format: "demoplan/scene-1", objects, ...extras.scene };
  if (!state.plan.extras) {
    // free space is generated on the table the page draws; a scene file loaded
    // is planned as the command line plans it (with its own table, or none)
    const [x0, y0] = state.layout.table.origin;
    const [w, h] = state.layout.table.size;
    const r4 = (v) => Math.round(v * 1e4) / 1e4;
    scene.table = { min: [r4(x0), r4(y0)], max: [r4(x0 + w), r4(y0 + h)] };
  }
  const landmarks = landmarksDocument(state.plan.landmarks);
  if (Object.keys(landmarks).length) scene.landmarks = landmarks;
  return scene;
}

// What a loaded scene file says beyond the poses (free space, gripper, table,
// robot; per object grasps and mass), kept for planning it; only for files in
// the default units, the page's own.
export const SCENE_EXTRAS = ["freespace", "gripper", "table", "robot"];
export const OBJECT_EXTRAS = ["grasps", "mass", "density"];

export function sceneExtras(document_) {
  const extras = { scene: {}, objects: {} };
  if (!document_ || document_.units) return extras;
  for (const key of SCENE_EXTRAS) if (document_[key] !== undefined && document_[key] !== null) extras.scene[key] = document_[key];
  for (const [name, object] of Object.entries(document_.objects || {})) {
    const fields = {};
    for (const key of OBJECT_EXTRAS) if (object[key] !== undefined && object[key] !== null) fields[key] = object[key];
    if (Object.keys(fields).length) extras.objects[name] = fields;
  }
  return extras;
}

export async function loadPlanScene() {
  const name = $("plan-file").value;
  if (!name) {
    alarm("choose a scene or demonstration of the work folder first");
    return;
  }
  const answer = await get(`/api/files/${encodeURIComponent(name)}`);
  if (!answer.layout) {
    alarm(`${name}: not a scene or a demonstration`);
    return;
  }
  // a scene file gives its masses beside the poses (kept as its extras); an
  // objects file or a demonstration gives them, and its colours, in its layout
  const scene = answer.document && answer.document.format === "demoplan/scene-1";
  if (!state.layout || !sameThings(state.layout, answer.layout, scene ? PLANNED_KEYS : DRAWN_KEYS)) {
    startDemonstration(clone(answer.layout), `Loaded ${name}; the Teach view starts there too.`);
  }
  state.plan.poses = clone(answer.layout.poses);
  state.plan.landmarks = scene ? inTableColours(answer.layout, answer.document) : clone(answer.layout.landmarks || {});
  keepInView(state.plan.poses);
  state.plan.extras = scene ? sceneExtras(answer.document) : null;
  clearPlan();
  redraw();
  say(`The plan starts from ${name}.`);
}

export function chosenModel() {
  const model = $("plan-model").value;
  if (!model) throw new ApiError(0, "no model in the work folder yet: learn one in the Learn view");
  return model;
}

export function clearPlan() {
  stopAnimation("plan");
  state.plan.result = null;
  state.plan.step = 0;
  $("plan-result").hidden = true;
  $("plan-list").replaceChildren();
  $("no-plan").hidden = true;
  $("candidates-box").hidden = true;
}

export async function scramble() {
  ensurePlanStart();
  const seed = Number($("scramble-seed").value) || 0;
  const layout = await post("/api/scramble", { layout: layoutWith(state.plan.poses), seed });
  $("scramble-seed").value = String(seed + 1);
  state.plan.poses = clone(layout.poses);
  keepInView(state.plan.poses);
  clearPlan();
  redraw();
  say(`Scrambled (seed ${seed}).`);
}

// A clutter object: a box the model never saw, added to the start (the scene
// only, never a demonstration), which the plan moves only where it is in the way.
export const CLUTTER_SIZE = [0.05, 0.05, 0.05];
export const CLUTTER_COLOUR = "#7f7f7f";

export async function addClutter() {
  ensurePlanStart();
  let n = 1;
  while (state.layout.objects[`clutter${n}`]) n += 1;
  const name = `clutter${n}`;
  state.layout.objects[name] = { shape: "box", size: [...CLUTTER_SIZE], colour: CLUTTER_COLOUR };
  state.clutter.push(name);
  const [x0, y0] = state.layout.table.origin;
  const [w, h] = state.layout.table.size;
  const xy = [snap(x0 + w / 2), snap(y0 + h / 2)];
  state.plan.poses[name] = { position: [...xy, 0], yaw: 0 };
  $("clutter").checked = true;
  await place(name, xy, 0, true); // it comes to rest on whatever stands there
  say(`${name} added (a ${CLUTTER_SIZE[0] * 100} cm box the model never saw): drag it where it ` +
    "should stand; the plan moves it only where it is in the way.");
}

// The start as a scene file of the work folder, as `demoplan plan` and `run` read it.
export async function saveScene() {
  const document_ = sceneDocument();
  delete document_.format;
  const name = $("scene-name").value.trim() || null;
  const answer = await post("/api/scenes", { document: document_, name });
  $("scene-name").value = "";
  const model = $("plan-model").value || "model.json";
  say(`Saved ${answer.file}: \`demoplan plan ${model} ${answer.file}\` plans this start.`);
  await refreshFiles();
}

export async function makePlan() {
  const model = chosenModel();
  clearPlan();
  say("Planning…");
  let result;
  try {
    result = await post("/api/plan", { model, scene: sceneDocument(), clutter: $("clutter").checked });
  } catch (error) {
    say("Not planned."); // not "Planning…" under the alert that says why
    throw error;
  }
  state.plan.result = result;
  if (result.no_plan) {
    $("no-plan").hidden = false;
    $("no-plan-reason").textContent = result.no_plan.reason;
    const figure = $("no-plan-figure");
    figure.hidden = !result.no_plan.figure;
    if (result.no_plan.figure) figure.src = `data:image/svg+xml;charset=utf-8,${encodeURIComponent(result.no_plan.figure)}`;
    renderCandidates(result);
    say("No plan.");
    redraw();
    return;
  }
  $("plan-result").hidden = false;
  renderCandidates(result);
  const list = $("plan-list");
  list.replaceChildren();
  for (const line of result.plan) {
    const li = document.createElement("li");
    li.textContent = line;
    list.appendChild(li);
  }
  $("optimal").textContent = result.optimal ? "The plan is proved shortest." : "The plan is not proved shortest.";
  const slider = $("plan-step");
  slider.max = String(result.moves.length);
  setPlanStep(0);
  say(`Plan of ${plural(result.plan.length, "action")}.`);
}

export function renderCandidates(result) {
  const body = $("candidates").tBodies[0];
  body.replaceChildren();
  for (const c of result.candidates) {
    const row = body.insertRow();
    if (c.goal === result.chosen) row.className = "chosen";
    // as the CLI's table: the demonstrations sharing this goal (numbered from 1)
    const names = Array.isArray(c.demonstrations) && c.demonstrations.length ? c.demonstrations.join(", ") : String(c.goal + 1);
    row.insertCell().textContent = names;
    row.insertCell().textContent = c.length === null || c.length === undefined ? "—" : String(c.length);
    row.insertCell().textContent = c.outcome || (c.goal === result.chosen ? "chosen" : "");
  }
  $("candidates-box").hidden = !result.candidates.length;
}

export function planPosesAt(step) {
  const poses = clone(state.plan.poses);
  const moves = state.plan.result ? state.plan.result.moves : [];
  for (const move of moves.slice(0, step)) poses[move.object] = clone(move.pose);
  return poses;
}

export function heldAt(step) {
  const moves = state.plan.result ? state.plan.result.moves : [];
  const move = moves[step - 1];
  return move && /^GRASP\b/.test(move.action) ? move.object : null;
}

export function setPlanStep(step) {
  const total = state.plan.result ? state.plan.result.moves.length : 0;
  state.plan.step = Math.max(0, Math.min(step, total));
  $("plan-step").value = String(state.plan.step);
  $("plan-step-out").textContent = `${state.plan.step} / ${total}`;
  document.querySelectorAll("#plan-list li").forEach((li, i) => {
    if (i === state.plan.step - 1) li.setAttribute("aria-current", "step");
    else li.removeAttribute("aria-current");
  });
  $("panel-plan").dataset.step = String(state.plan.step);
  redraw();
}

registerView("plan", {
  posesAt: planPosesAt,
  held: heldAt,
  steps: () => (state.plan.result ? state.plan.result.moves.length : 0),
  setStep: setPlanStep,
  sceneChanged: clearPlan,
});
