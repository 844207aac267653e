// demoplan studio: teach, learn, plan and run in the browser (docs/studio.md).
// Plain ES modules; every value shown comes from the studio's server, which
// calls demoplan's command layer (docs/studio-api.md).

import { ApiError, del, get, post } from "./api.js";
import { drawGraph } from "./graph.js";
import { TableView, ridersOf, snap, turned } from "./table.js";

const $ = (id) => document.getElementById(id);
const clone = (value) => JSON.parse(JSON.stringify(value));
const fmt = (v, digits = 3) => (v === null || v === undefined ? "—" : Number(v).toFixed(digits));
const mm = (v) => (v === null || v === undefined ? "—" : `${(v * 1000).toFixed(1)} mm`);
const SHAPES_IN_SCENES = new Set(["box", "cylinder", "sphere"]);

const state = {
  view: "teach",
  layout: null, // {template, objects, landmarks, poses, table}
  source: { kind: "template", id: "set_table" },
  teach: { initial: {}, poses: {}, steps: [], saved: false },
  learn: { result: null },
  plan: { poses: null, extras: null, result: null, step: 0, timer: null },
  run: { id: null, status: null, step: 0, timer: null, poll: null },
  selected: null,
  files: { demonstrations: [], models: [], scenes: [] },
};

// --- messages -------------------------------------------------------------

function say(text) {
  $("status").textContent = text;
}

function alarm(text) {
  const box = $("alert");
  box.textContent = text;
  box.hidden = !text;
}

function failed(error) {
  const text = error instanceof ApiError ? error.message : `unexpected error: ${error.message || error}`;
  alarm(text);
}

async function guarded(action) {
  try {
    alarm("");
    await action();
  } catch (error) {
    failed(error);
  }
}

// --- the table ------------------------------------------------------------

const table = new TableView($("table"), $("heights"), {
  canPickUp: (name) => {
    const poses = currentPoses();
    const riders = ridersOf(name, state.layout, poses);
    if (riders.length) {
      alarm(`${name} cannot be picked up: ${riders.join(", ")} stands on it (move ${riders.join(", ")} first)`);
      return false;
    }
    alarm("");
    return true;
  },
  select: (name) => {
    state.selected = name;
    redraw();
  },
  drop: (name, xy, yaw) => guarded(() => place(name, xy, yaw, false)),
  rotate: (name, degrees) => {
    const pose = currentPoses()[name];
    if (!pose) return;
    guarded(() => place(name, pose.position.slice(0, 2), turned(pose.yaw || 0, degrees), true));
  },
  nudge: (name, dx, dy) => {
    const pose = currentPoses()[name];
    if (!pose || !table.handlers.canPickUp(name)) return;
    guarded(() => place(name, [snap(pose.position[0] + dx), snap(pose.position[1] + dy)], pose.yaw || 0, true));
  },
  landmarkMoved: (name) => {
    const p = state.layout.landmarks[name].position;
    say(`landmark ${name} placed at x ${fmt(p[0])}, y ${fmt(p[1])} m`);
    redraw();
  },
});

function interactive() {
  return (state.view === "teach" || state.view === "plan") && !state.plan.timer && !state.run.timer;
}

function currentPoses() {
  if (state.view === "plan" || state.view === "run") return state.plan.poses || state.teach.poses;
  return state.teach.poses;
}

function shownPoses() {
  if (state.view === "plan" && state.plan.result && state.plan.step > 0) return planPosesAt(state.plan.step);
  if (state.view === "run" && state.run.status && state.run.step > 0) return runPosesAt(state.run.step);
  return currentPoses();
}

function redraw() {
  if (!state.layout) return;
  const options = {
    selected: state.selected,
    interactive: interactive() && !(state.view === "plan" && state.plan.step > 0),
    landmarksMovable: state.view === "teach" && state.teach.steps.length === 0,
    outlines: state.view === "learn" && state.learn.result ? state.learn.result.targets : [],
    held: state.view === "plan" ? heldAt(state.plan.step) : null,
  };
  table.draw(shownPoses(), options);
  const captions = {
    teach: "Teach: move the objects as the task should be done; each release is one step.",
    learn: "Learn: the learned targets are drawn as outlines.",
    plan: state.plan.step > 0 ? `Plan: after action ${state.plan.step}.` : "Plan: the start scene.",
    run: state.run.step > 0 ? `Run: after event ${state.run.step}.` : "Run: the start scene.",
  };
  $("stage-caption").textContent = captions[state.view];
}

// Room for the table at this window size: beside the panel and the height strip.
function tableRoom() {
  return [window.innerWidth - 440 - 90 - 56, window.innerHeight - 150];
}

function layoutWith(poses) {
  return { ...state.layout, poses };
}

// Drop `name` at xy (metres) with `yaw`: the server says where it comes to rest.
// amend: a turn or a nudge right after placing the same object changes that step.
async function place(name, xy, yaw, amend) {
  const poses = currentPoses();
  const before = clone(poses[name]);
  const answer = await post("/api/drop", { layout: layoutWith(poses), object: name, position: xy, yaw });
  const pose = { position: answer.pose.position, yaw: answer.pose.yaw };
  if (state.view === "teach") {
    const steps = state.teach.steps;
    const last = steps[steps.length - 1];
    const step = { object: name, position: pose.position, yaw: pose.yaw, on: answer.on };
    if (amend && last && last.object === name) {
      steps[steps.length - 1] = { ...step, before: last.before };
    } else {
      steps.push({ ...step, before });
    }
    state.teach.poses[name] = pose;
    keepInView(state.teach.poses);
    state.teach.saved = false;
    renderSteps();
    say(`${name} put down at x ${fmt(pose.position[0])}, y ${fmt(pose.position[1])}, z ${fmt(pose.position[2])} m` +
      (answer.on ? ` on ${answer.on}` : ""));
  } else {
    state.plan.poses[name] = pose;
    keepInView(state.plan.poses);
    clearPlan();
    say(`${name} now starts at x ${fmt(pose.position[0])}, y ${fmt(pose.position[1])}, z ${fmt(pose.position[2])} m` +
      (answer.on ? ` on ${answer.on}` : ""));
  }
  redraw();
}

// --- teach ----------------------------------------------------------------

function renderSteps() {
  const list = $("steps");
  list.replaceChildren();
  for (const step of state.teach.steps) {
    const li = document.createElement("li");
    li.dataset.object = step.object;
    const [x, y, z] = step.position;
    li.textContent = `${step.object} → (${fmt(x, 4)}, ${fmt(y, 4)}, ${fmt(z, 4)}) yaw ${fmt(step.yaw, 1)}°` +
      (step.on ? ` on ${step.on}` : "");
    list.appendChild(li);
  }
  $("undo").disabled = state.teach.steps.length === 0;
}

// The drawn table: the layout's, grown to cover every object shown (a file's
// layout may be drawn around its start only) and, for the same objects, the
// table drawn before (so that the view does not jump between demonstrations).
function cover(table_, poses, margin = 0.05) {
  let [x0, y0] = table_.origin;
  let [x1, y1] = [x0 + table_.size[0], y0 + table_.size[1]];
  for (const pose of Object.values(poses)) {
    const [x, y] = pose.position;
    x0 = Math.min(x0, x - margin);
    y0 = Math.min(y0, y - margin);
    x1 = Math.max(x1, x + margin);
    y1 = Math.max(y1, y + margin);
  }
  return { origin: [x0, y0], size: [x1 - x0, y1 - y0] };
}

function sameObjects(a, b) {
  const names = (l) => Object.keys(l.objects).sort().join(" ");
  return names(a) === names(b);
}

function corners(table_) {
  const [x0, y0] = table_.origin;
  return {
    a: { position: [x0, y0] },
    b: { position: [x0 + table_.size[0], y0 + table_.size[1]] },
  };
}

// Grow the drawn table when an object has left it.
function keepInView(poses) {
  const grown = cover(state.layout.table, poses);
  const [w0, h0] = state.layout.table.size;
  if (grown.size[0] > w0 + 1e-9 || grown.size[1] > h0 + 1e-9) {
    state.layout.table = grown;
    table.setLayout(state.layout, tableRoom());
  }
}

function startDemonstration(layout, note) {
  if (state.layout && sameObjects(state.layout, layout)) {
    layout.table = cover(layout.table, corners(state.layout.table), 0);
  }
  layout.table = cover(layout.table, layout.poses);
  state.layout = layout;
  state.teach.initial = clone(layout.poses);
  state.teach.poses = clone(layout.poses);
  state.teach.steps = [];
  state.teach.saved = false;
  state.plan.poses = null;
  state.plan.extras = null;
  state.selected = null;
  clearPlan();
  table.setLayout(layout, tableRoom());
  renderSteps();
  redraw();
  say(note);
}

async function newDemonstration() {
  const randomise = $("randomise").checked;
  const seed = Number($("seed").value) || 0;
  let layout;
  if (state.source.kind === "template") {
    const query = randomise ? `?seed=${seed}` : "";
    layout = await get(`/api/templates/${encodeURIComponent(state.source.id)}${query}`);
  } else {
    layout = (await get(`/api/files/${encodeURIComponent(state.source.name)}`)).layout;
    if (randomise) layout = await post("/api/scramble", { layout, seed });
  }
  if (randomise) $("seed").value = String(seed + 1);
  const unsaved = state.teach.steps.length && !state.teach.saved ? ` (${state.teach.steps.length} unsaved steps discarded)` : "";
  const from = state.source.kind === "template" ? `template ${state.source.id}` : state.source.name;
  startDemonstration(layout, `New demonstration from ${from}${randomise ? `, randomised (seed ${seed})` : ""}${unsaved}.`);
}

function undo() {
  const step = state.teach.steps.pop();
  if (!step) return;
  state.teach.poses[step.object] = step.before;
  state.teach.saved = false;
  renderSteps();
  redraw();
  say(`undone: ${step.object} is back at x ${fmt(step.before.position[0])}, y ${fmt(step.before.position[1])} m`);
}

function poseDocument(pose) {
  return { position: pose.position.map((v) => Math.round(v * 1e6) / 1e6), yaw: Math.round((pose.yaw || 0) * 1000) / 1000 };
}

function landmarksDocument() {
  const out = {};
  for (const [name, mark] of Object.entries(state.layout.landmarks || {})) {
    out[name] = { ...poseDocument(mark), shape: mark.shape || "box" };
    if (mark.size) out[name].size = mark.size;
  }
  return out;
}

function demonstrationDocument() {
  const objects = {};
  for (const [name, geometry] of Object.entries(state.layout.objects)) {
    objects[name] = { shape: geometry.shape, size: geometry.size };
  }
  const initial = {};
  for (const [name, pose] of Object.entries(state.teach.initial)) initial[name] = poseDocument(pose);
  const document_ = { format: "demoplan/demonstration-1", objects, initial, steps: [] };
  const landmarks = landmarksDocument();
  if (Object.keys(landmarks).length) document_.landmarks = landmarks;
  document_.steps = state.teach.steps.map((s) => ({ object: s.object, ...poseDocument(s) }));
  return document_;
}

async function save() {
  if (!state.teach.steps.length) {
    alarm("nothing to save: move at least one object first (each release is one step)");
    return;
  }
  const name = $("save-name").value.trim() || null;
  const answer = await post("/api/demonstrations", { document: demonstrationDocument(), name });
  state.teach.saved = true;
  $("save-name").value = "";
  say(`Saved ${answer.file} (${state.teach.steps.length} steps).`);
  await refreshFiles();
}

async function loadFile() {
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
}

// --- work-folder files ----------------------------------------------------

async function refreshFiles() {
  state.files = await get("/api/files");
  const file = $("file");
  const keep = file.value;
  file.replaceChildren(new Option("(none)", ""));
  for (const kind of ["demonstrations", "scenes"]) {
    const group = document.createElement("optgroup");
    group.label = kind;
    for (const name of state.files[kind]) group.appendChild(new Option(name, name));
    if (state.files[kind].length) file.appendChild(group);
  }
  file.value = state.files.demonstrations.includes(keep) || state.files.scenes.includes(keep) ? keep : "";
  const chosen = new Set([...document.querySelectorAll("#learn-files input:not(:checked)")].map((i) => i.value));
  const box = $("learn-files");
  box.replaceChildren();
  if (!state.files.demonstrations.length) box.textContent = "No demonstrations saved yet.";
  for (const name of state.files.demonstrations) {
    const label = document.createElement("label");
    label.className = "check";
    const input = document.createElement("input");
    input.type = "checkbox";
    input.value = name;
    input.checked = !chosen.has(name);
    label.append(input, ` ${name}`);
    box.appendChild(label);
  }
  const planFile = $("plan-file");
  const keepPlan = planFile.value;
  planFile.replaceChildren(new Option("(none)", ""));
  for (const kind of ["scenes", "demonstrations"]) {
    const group = document.createElement("optgroup");
    group.label = kind;
    for (const name of state.files[kind]) group.appendChild(new Option(name, name));
    if (state.files[kind].length) planFile.appendChild(group);
  }
  planFile.value = state.files.scenes.includes(keepPlan) || state.files.demonstrations.includes(keepPlan) ? keepPlan : "";
  const models = $("plan-model");
  const current = models.value;
  models.replaceChildren();
  for (const name of state.files.models) models.appendChild(new Option(name, name));
  if (state.files.models.includes(current)) models.value = current;
  $("workfolder").textContent = `work folder: ${state.files.demonstrations.length} demonstrations, ` +
    `${state.files.models.length} models, ${state.files.scenes.length} scenes`;
}

// --- learn ----------------------------------------------------------------

async function learn() {
  const files = [...document.querySelectorAll("#learn-files input:checked")].map((i) => i.value);
  if (!files.length) {
    alarm("choose at least one demonstration to learn from (save one in the Teach view)");
    return;
  }
  const output = $("model-name").value.trim() || "model.json";
  say("Learning…");
  const result = await post("/api/learn", { files, output, scene: null });
  state.learn.result = result;
  renderLearned(result);
  await refreshFiles();
  $("plan-model").value = result.model;
  say(`Learned ${result.states.length} states from ${files.length} demonstrations; saved ${result.model}.`);
  redraw();
}

function renderLearned(result) {
  const body = $("states").tBodies[0];
  body.replaceChildren();
  for (const s of result.states) {
    const row = body.insertRow();
    row.dataset.state = s.id;
    const cells = [
      s.id, s.object, s.reference, mm(s.spread), s.margin === null || s.margin === undefined ? "—" : `${fmt(s.margin, 2)} ×`,
      s.position.map((v) => fmt(v)).join(", "), s.yaw === null ? "any" : `${fmt(s.yaw, 1)}°`,
    ];
    cells.forEach((text, i) => {
      const cell = i === 0 ? document.createElement("th") : row.insertCell();
      if (i === 0) {
        cell.scope = "row";
        row.appendChild(cell);
      }
      cell.textContent = text;
    });
  }
  const sequences = $("sequences");
  sequences.replaceChildren();
  for (const sequence of result.sequences) {
    const li = document.createElement("li");
    li.textContent = sequence.join(" → ");
    sequences.appendChild(li);
  }
  const objectOf = Object.fromEntries(result.states.map((s) => [s.id, s.object]));
  drawGraph($("graph"), result.constraints, objectOf);
  const warnings = $("warnings");
  warnings.replaceChildren();
  $("warnings-title").textContent = `Warnings (${result.warnings.length})`;
  for (const line of result.warnings) {
    const li = document.createElement("li");
    li.textContent = line;
    warnings.appendChild(li);
  }
}

// --- plan -----------------------------------------------------------------

function ensurePlanStart() {
  if (!state.plan.poses && state.layout) state.plan.poses = clone(state.teach.poses);
}

function sceneDocument() {
  ensurePlanStart();
  const objects = {};
  for (const [name, geometry] of Object.entries(state.layout.objects)) {
    const pose = state.plan.poses[name];
    if (!pose) continue;
    objects[name] = { ...poseDocument(pose), size: geometry.size };
    if (SHAPES_IN_SCENES.has(geometry.shape)) objects[name].shape = geometry.shape;
  }
  const extras = state.plan.extras || { scene: {}, objects: {} };
  for (const [name, fields] of Object.entries(extras.objects)) {
    if (objects[name]) Object.assign(objects[name], fields);
  }
  const scene = { format: "demoplan/scene-1", objects, ...extras.scene };
  const landmarks = landmarksDocument();
  if (Object.keys(landmarks).length) scene.landmarks = landmarks;
  return scene;
}

// What a loaded scene file says beyond the poses (free space, gripper, table,
// robot; per object grasps and mass), kept for planning it; only for files in
// the default units, the page's own.
const SCENE_EXTRAS = ["freespace", "gripper", "table", "robot"];
const OBJECT_EXTRAS = ["grasps", "mass", "density"];

function sceneExtras(document_) {
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

async function loadPlanScene() {
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
  if (!state.layout || !sameObjects(state.layout, answer.layout)) {
    startDemonstration(clone(answer.layout), `Loaded ${name}; the Teach view starts there too.`);
  }
  state.plan.poses = clone(answer.layout.poses);
  keepInView(state.plan.poses);
  state.plan.extras = answer.document && answer.document.format === "demoplan/scene-1" ? sceneExtras(answer.document) : null;
  clearPlan();
  redraw();
  say(`The plan starts from ${name}.`);
}

function chosenModel() {
  const model = $("plan-model").value;
  if (!model) throw new ApiError(0, "no model in the work folder yet: learn one in the Learn view");
  return model;
}

function clearPlan() {
  stopAnimation("plan");
  state.plan.result = null;
  state.plan.step = 0;
  $("plan-result").hidden = true;
  $("plan-list").replaceChildren();
  $("no-plan").hidden = true;
  $("candidates-box").hidden = true;
}

async function scramble() {
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

async function makePlan() {
  const model = chosenModel();
  clearPlan();
  say("Planning…");
  const result = await post("/api/plan", { model, scene: sceneDocument(), clutter: $("clutter").checked });
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
  say(`Plan of ${result.plan.length} actions.`);
}

function renderCandidates(result) {
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

function planPosesAt(step) {
  const poses = clone(state.plan.poses);
  const moves = state.plan.result ? state.plan.result.moves : [];
  for (const move of moves.slice(0, step)) poses[move.object] = clone(move.pose);
  return poses;
}

function heldAt(step) {
  const moves = state.plan.result ? state.plan.result.moves : [];
  const move = moves[step - 1];
  return move && /^GRASP\b/.test(move.action) ? move.object : null;
}

function setPlanStep(step) {
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

function stopAnimation(which) {
  const holder = state[which];
  if (holder.timer) {
    clearInterval(holder.timer);
    holder.timer = null;
    $(which === "plan" ? "play-plan" : "play-run").textContent = "▶ Play";
  }
}

function play(which) {
  const holder = state[which];
  if (holder.timer) {
    stopAnimation(which);
    redraw();
    return;
  }
  const total = which === "plan" ? (holder.result ? holder.result.moves.length : 0) : runEvents().length;
  if (!total) return;
  const set = which === "plan" ? setPlanStep : setRunStep;
  if (holder.step >= total) set(0);
  $(which === "plan" ? "play-plan" : "play-run").textContent = "❚❚ Pause";
  holder.timer = setInterval(() => {
    if (holder.step >= total) {
      stopAnimation(which);
      redraw();
      return;
    }
    set(holder.step + 1);
  }, 550);
}

// --- run ------------------------------------------------------------------

function runEvents() {
  return state.run.status ? state.run.status.events : [];
}

function runPosesAt(step) {
  const poses = clone(state.plan.poses || state.teach.poses);
  for (const event of runEvents().slice(0, step)) {
    if (event.poses) Object.assign(poses, clone(event.poses));
  }
  return poses;
}

function setRunStep(step) {
  const total = runEvents().length;
  state.run.step = Math.max(0, Math.min(step, total));
  $("run-step").max = String(total);
  $("run-step").value = String(state.run.step);
  $("run-step-out").textContent = `${state.run.step} / ${total}`;
  document.querySelectorAll("#timeline li").forEach((li, i) => {
    if (i === state.run.step - 1) li.setAttribute("aria-current", "step");
    else li.removeAttribute("aria-current");
  });
  redraw();
}

const MARKS = { plan: "▸", failure: "✗", replan: "↻", done: "✓", action: "•" };

function renderRun() {
  const status = state.run.status;
  const list = $("timeline");
  const events = status.events;
  while (list.children.length > events.length) list.lastChild.remove();
  for (let i = list.children.length; i < events.length; i += 1) {
    const event = events[i];
    const li = document.createElement("li");
    li.dataset.kind = event.kind;
    li.className = `event ${event.kind}`;
    const button = document.createElement("button");
    button.type = "button";
    button.className = "event-button";
    button.textContent = `${MARKS[event.kind] || "•"} ${event.text}`;
    button.setAttribute("aria-label", `${event.kind}: ${event.text}`);
    button.addEventListener("click", () => setRunStep(i + 1));
    li.appendChild(button);
    list.appendChild(li);
  }
  const badge = $("run-state");
  badge.textContent = status.state;
  badge.dataset.state = status.state;
  $("cancel").disabled = status.state !== "running";
  $("run").disabled = status.state === "running";
  const summary = $("run-summary");
  if (status.result) {
    const r = status.result;
    summary.textContent = `${r.success ? "Success" : "Not done"}: ${r.replans} replans, ` +
      `${r.failures.length} failures detected.` + (r.failures.length ? ` ${r.failures.join(" ")}` : "");
    const video = $("video");
    video.hidden = !r.video;
    if (r.video && video.getAttribute("src") !== r.video) video.src = r.video;
  } else if (status.state === "running") {
    summary.textContent = `Running: ${events.length} events so far.`;
  } else {
    summary.textContent = status.error ? `Stopped: ${status.error}` : `Run ${status.state}.`;
  }
  if (status.error) alarm(status.error);
  setRunStep(status.state === "running" ? events.length : Math.min(state.run.step || events.length, events.length));
}

async function startRun() {
  const model = chosenModel();
  stopPolling();
  stopAnimation("run");
  const body = {
    model, scene: sceneDocument(), faults: $("faults").value.trim(),
    seed: Number($("run-seed").value) || 0, sim: $("sim").value,
  };
  const answer = await post("/api/runs", body);
  state.run.id = answer.run;
  state.run.status = { state: "running", events: [], result: null, error: null };
  state.run.step = 0;
  $("timeline").replaceChildren();
  $("video").hidden = true;
  renderRun();
  say(`Run ${answer.run} started.`);
  state.run.poll = setInterval(() => guarded(pollRun), 300);
}

function stopPolling() {
  if (state.run.poll) clearInterval(state.run.poll);
  state.run.poll = null;
}

async function pollRun() {
  const id = state.run.id;
  if (!id) return;
  let status;
  try {
    status = await get(`/api/runs/${encodeURIComponent(id)}`);
  } catch (error) {
    stopPolling();
    throw error;
  }
  if (id !== state.run.id) return;
  state.run.status = status;
  renderRun();
  if (status.state !== "running") {
    stopPolling();
    say(`Run ${status.state}${status.result ? (status.result.success ? ": success" : ": not done") : ""}.`);
  }
}

async function cancelRun() {
  if (!state.run.id) return;
  await del(`/api/runs/${encodeURIComponent(state.run.id)}`);
  say("Cancelling the run…");
}

// --- views ----------------------------------------------------------------

const VIEWS = ["teach", "learn", "plan", "run"];

function show(view) {
  if (view === state.view) return;
  stopAnimation("plan");
  stopAnimation("run");
  state.view = view;
  document.body.dataset.view = view;
  for (const v of VIEWS) {
    const tab = $(`tab-${v}`);
    tab.setAttribute("aria-selected", String(v === view));
    tab.tabIndex = v === view ? 0 : -1;
    $(`panel-${v}`).hidden = v !== view;
  }
  if (view === "plan" || view === "run") ensurePlanStart();
  if (view === "learn" || view === "plan") guarded(refreshFiles);
  redraw();
}

function wireTabs() {
  VIEWS.forEach((v, i) => {
    const tab = $(`tab-${v}`);
    tab.addEventListener("click", () => show(v));
    tab.addEventListener("keydown", (e) => {
      const next = { ArrowRight: 1, ArrowLeft: -1 }[e.key];
      if (!next) return;
      const target = VIEWS[(i + next + VIEWS.length) % VIEWS.length];
      show(target);
      $(`tab-${target}`).focus();
    });
  });
}

function wire() {
  wireTabs();
  $("template").addEventListener("change", () => {
    state.source = { kind: "template", id: $("template").value };
    guarded(newDemonstration);
  });
  $("new").addEventListener("click", () => guarded(newDemonstration));
  $("save").addEventListener("click", () => guarded(save));
  $("load").addEventListener("click", () => guarded(loadFile));
  $("undo").addEventListener("click", undo);
  $("learn").addEventListener("click", () => guarded(learn));
  $("scramble").addEventListener("click", () => guarded(scramble));
  $("load-plan-file").addEventListener("click", () => guarded(loadPlanScene));
  $("start-from-teach").addEventListener("click", () => {
    state.plan.poses = clone(state.teach.poses);
    state.plan.extras = null;
    clearPlan();
    redraw();
    say("The plan starts from the table as taught.");
  });
  $("plan").addEventListener("click", () => guarded(makePlan));
  $("plan-step").addEventListener("input", () => {
    stopAnimation("plan");
    setPlanStep(Number($("plan-step").value));
  });
  $("play-plan").addEventListener("click", () => play("plan"));
  $("run").addEventListener("click", () => guarded(startRun));
  $("cancel").addEventListener("click", () => guarded(cancelRun));
  $("run-step").addEventListener("input", () => {
    stopAnimation("run");
    setRunStep(Number($("run-step").value));
  });
  $("play-run").addEventListener("click", () => play("run"));
  document.addEventListener("keydown", (e) => {
    if ((e.ctrlKey || e.metaKey) && e.key === "z" && state.view === "teach" && !/INPUT|SELECT|TEXTAREA/.test(e.target.tagName)) {
      e.preventDefault();
      undo();
    }
  });
}

let resizing = null;
window.addEventListener("resize", () => {
  clearTimeout(resizing);
  resizing = setTimeout(() => {
    if (!state.layout || table.drag) return;
    table.setLayout(state.layout, tableRoom());
    redraw();
  }, 200);
});

async function start() {
  wire();
  await guarded(async () => {
    const templates = await get("/api/templates");
    const select = $("template");
    for (const option of select.options) {
      const known = templates.templates.find((t) => t.id === option.value);
      if (known && known.title) option.title = known.title;
    }
    await refreshFiles();
    await newDemonstration();
  });
  document.body.dataset.ready = "true";
}

start();
