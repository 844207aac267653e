// The table shared by the four views: what it shows, and where a released object comes to rest (POST /api/drop).

import { post } from "./api.js";
import { $, alarm, clone, fmt, guarded, say, state } from "./common.js";
import { TableView, ridersOf, snap, turned } from "./table.js";

// --- the views ------------------------------------------------------------

// What the table asks of each view, registered by the view: the views import
// the stage, never the reverse. A view may register
//   posesAt(step), held(step): the poses drawn (the object in the hand) after its step `step`;
//   steps(), setStep(step): how many steps it plays, and show one (Play);
//   stepsChanged(): the Teach view's steps were changed on the table;
//   sceneChanged(): the scene it worked from changed (the plan is forgotten).
const views = {};

export function registerView(name, hooks) {
  views[name] = hooks;
}

function ask(view, hook, ...args) {
  const hooks = views[view];
  return hooks && hooks[hook] ? hooks[hook](...args) : undefined;
}

// The scene changed under the views: each forgets what it computed from it.
export function sceneChanged() {
  for (const hooks of Object.values(views)) if (hooks.sceneChanged) hooks.sceneChanged();
}

// --- the table ------------------------------------------------------------

export const table = new TableView($("table"), $("heights"), {
  canPickUp: (name) => {
    const poses = currentPoses();
    const riders = ridersOf(name, state.layout, poses);
    if (riders.length) {
      alarm(`${name} cannot be picked up: ${riders.join(", ")} ${riders.length === 1 ? "stands" : "stand"} on it (move ${riders.join(", ")} first)`);
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
    const mark = currentLandmarks()[name];
    if (mark) {
      if (landmarksMovable()) guarded(() => placeLandmark(name, mark.position.slice(0, 2), turned(mark.yaw || 0, degrees)));
      else alarm(landmarkHint(name));
      return;
    }
    const pose = currentPoses()[name];
    if (!pose) return;
    guarded(() => place(name, pose.position.slice(0, 2), turned(pose.yaw || 0, degrees), true));
  },
  nudge: (name, dx, dy) => {
    const mark = currentLandmarks()[name];
    if (mark) {
      if (landmarksMovable()) guarded(() => placeLandmark(name, [snap(mark.position[0] + dx), snap(mark.position[1] + dy)], mark.yaw || 0));
      else alarm(landmarkHint(name));
      return;
    }
    const pose = currentPoses()[name];
    if (!pose || !table.handlers.canPickUp(name)) return;
    guarded(() => place(name, [snap(pose.position[0] + dx), snap(pose.position[1] + dy)], pose.yaw || 0, true));
  },
  landmarkDropped: (name, xy, yaw) => guarded(() => placeLandmark(name, xy, yaw)),
});

// The landmarks as they stand now: the Plan view's start has its own.
export function currentLandmarks() {
  if ((state.view === "plan" || state.view === "run") && state.plan.landmarks) return state.plan.landmarks;
  return state.layout ? state.layout.landmarks || {} : {};
}

// Landmarks move before the first step of a demonstration (between
// demonstrations: moving one is not a step) and in the Plan view's start.
export function landmarksMovable() {
  if (state.view === "teach") return state.teach.steps.length === 0;
  return state.view === "plan" && state.plan.step === 0;
}

function landmarkHint(name) {
  return `${name} is a landmark: it moves before the first step of a demonstration (press New demonstration, or Undo) and in the Plan view`;
}

// Put landmark `name` down at xy with yaw: the server refuses a place on objects.
export async function placeLandmark(name, xy, yaw) {
  const marks = currentLandmarks();
  try {
    const answer = await post("/api/landmark", { layout: layoutWith(currentPoses()), landmark: name, position: xy, yaw });
    marks[name] = { ...marks[name], position: answer.pose.position, yaw: answer.pose.yaw };
    keepInView(marks); // dragged past the table's edge: still drawn (and in the Run view)
  } finally {
    redraw(); // refused: it is drawn where it stood
  }
  if (state.view !== "teach") sceneChanged();
  const p = marks[name];
  say(`landmark ${name} placed at x ${fmt(p.position[0])}, y ${fmt(p.position[1])} m, yaw ${fmt(p.yaw, 1)}°`);
}

export function interactive() {
  return (state.view === "teach" || state.view === "plan") && !state.plan.timer && !state.run.timer;
}

export function currentPoses() {
  if (state.view === "plan" || state.view === "run") return state.plan.poses || state.teach.poses;
  return state.teach.poses;
}

export function shownPoses() {
  if (state.view === "plan" && state.plan.result && state.plan.step > 0) return ask("plan", "posesAt", state.plan.step);
  if (state.view === "run" && state.run.status && state.run.step > 0) return ask("run", "posesAt", state.run.step);
  return currentPoses();
}

export function redraw() {
  if (!state.layout) return;
  const options = {
    selected: state.selected,
    interactive: interactive() && !(state.view === "plan" && state.plan.step > 0),
    landmarksMovable: landmarksMovable(),
    landmarks: currentLandmarks(),
    outlines: state.view === "learn" && state.learn.result ? state.learn.result.targets : [],
    held: state.view === "plan" ? ask("plan", "held", state.plan.step) : null,
  };
  table.draw(shownPoses(), options);
  const captions = {
    teach: arranging()
      ? "Teach: drag your objects where the task starts (not steps); then Save objects and teach."
      : "Teach: move the objects as the task should be done; each release is one step.",
    learn: "Learn: the learned targets are drawn as outlines.",
    plan: state.plan.step > 0 ? `Plan: after action ${state.plan.step}.` : "Plan: the start scene.",
    run: state.run.step > 0 ? `Run: the world observed at event ${state.run.step}.` : "Run: the start scene.",
  };
  $("stage-caption").textContent = captions[state.view];
}

// Room for the table at this window size: beside the panel and the height strip.
export function tableRoom() {
  return [window.innerWidth - 560 - 90 - 56, window.innerHeight - 150];
}

// The layout with these poses: its objects that have one (a clutter object
// added in the Plan view has none on the taught table).
export function layoutWith(poses) {
  const objects = Object.fromEntries(Object.entries(state.layout.objects).filter(([name]) => poses[name]));
  return { ...state.layout, objects, poses, landmarks: currentLandmarks() };
}

// Objects made or changed in the page and not yet saved, before the first
// step: a drop arranges where the task starts (Save objects keeps it), it is
// not a step (docs/studio.md "Your own objects").
export function arranging() {
  return state.view === "teach" && state.teach.edited && state.teach.steps.length === 0;
}

// Drop `name` at xy (metres) with `yaw`: the server says where it comes to rest.
// amend: a turn or a nudge right after placing the same object changes that step.
export async function place(name, xy, yaw, amend) {
  const poses = currentPoses();
  const before = clone(poses[name]);
  const answer = await post("/api/drop", { layout: layoutWith(poses), object: name, position: xy, yaw });
  const pose = { position: answer.pose.position, yaw: answer.pose.yaw };
  if (state.view === "teach" && arranging()) {
    state.teach.poses[name] = pose;
    state.teach.initial[name] = clone(pose);
    keepInView(state.teach.poses);
    say(`${name} starts at x ${fmt(pose.position[0])}, y ${fmt(pose.position[1])}, z ${fmt(pose.position[2])} m` +
      (answer.on ? ` on ${answer.on}` : "") + ": not a step (the objects are not saved yet: Save objects, then teach)");
  } else if (state.view === "teach") {
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
    ask("teach", "stepsChanged");
    say(`${name} put down at x ${fmt(pose.position[0])}, y ${fmt(pose.position[1])}, z ${fmt(pose.position[2])} m` +
      (answer.on ? ` on ${answer.on}` : ""));
  } else {
    state.plan.poses[name] = pose;
    keepInView(state.plan.poses);
    sceneChanged();
    say(`${name} now starts at x ${fmt(pose.position[0])}, y ${fmt(pose.position[1])}, z ${fmt(pose.position[2])} m` +
      (answer.on ? ` on ${answer.on}` : ""));
  }
  redraw();
}

// The drawn table: the layout's, grown to cover every object shown (a file's
// layout may be drawn around its start only) and, for the same objects, the
// table drawn before (so that the view does not jump between demonstrations).
export function cover(table_, poses, margin = 0.05) {
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

export function sameObjects(a, b) {
  const names = (l) => Object.keys(l.objects).filter((n) => !state.clutter.includes(n)).sort().join(" ");
  return names(a) === names(b);
}

// Whether layout `b` holds the things of layout `a`: the same objects, each
// the same in `keys` (a size that `b` leaves to the model, null, matches any).
// A scene loaded for planning must be planned with its own sizes and masses,
// not with those of same-named objects on the table before.
export const PLANNED_KEYS = ["shape", "size", "type"];
export const DRAWN_KEYS = [...PLANNED_KEYS, "mass", "density", "colour"];

export function sameThings(a, b, keys) {
  if (!sameObjects(a, b)) return false;
  const same = (u, v) => JSON.stringify(u ?? null) === JSON.stringify(v ?? null);
  return Object.entries(b.objects).every(([name, geometry]) => {
    const known = a.objects[name];
    if (state.clutter.includes(name) || !known) return true;
    return keys.every((key) => (key === "size" && geometry.size == null) || same(known[key], geometry[key]));
  });
}

// A scene's colours on the table: a colour its file gives (the page's Save
// scene writes every thing's) is the thing's, the objects' on the table too;
// a landmark the file gives none is drawn in the colour of the table's
// landmark of that name (a scene written elsewhere names no colours).
export function inTableColours(layout, document_) {
  const given = (group, name) => Boolean(document_ && document_[group] && document_[group][name] && document_[group][name].colour);
  const known = (state.layout && state.layout.landmarks) || {};
  const out = clone(layout.landmarks || {});
  for (const [name, mark] of Object.entries(out)) {
    if (!given("landmarks", name) && known[name] && known[name].colour) mark.colour = known[name].colour;
  }
  for (const [name, geometry] of Object.entries(layout.objects || {})) {
    if (given("objects", name) && state.layout && state.layout.objects[name]) state.layout.objects[name].colour = geometry.colour;
  }
  return out;
}

export function corners(table_) {
  const [x0, y0] = table_.origin;
  return {
    a: { position: [x0, y0] },
    b: { position: [x0 + table_.size[0], y0 + table_.size[1]] },
  };
}

// Grow the drawn table when an object has left it.
export function keepInView(poses) {
  const grown = cover(state.layout.table, poses);
  const [w0, h0] = state.layout.table.size;
  if (grown.size[0] > w0 + 1e-9 || grown.size[1] > h0 + 1e-9) {
    state.layout.table = grown;
    table.setLayout(state.layout, tableRoom());
  }
}

// --- playing a view's steps -----------------------------------------------

export function stopAnimation(which) {
  const holder = state[which];
  if (holder.timer) {
    clearInterval(holder.timer);
    holder.timer = null;
    $(which === "plan" ? "play-plan" : "play-run").textContent = "▶ Play";
  }
}

export function play(which) {
  const holder = state[which];
  if (holder.timer) {
    stopAnimation(which);
    redraw();
    return;
  }
  const total = ask(which, "steps");
  if (!total) return;
  const set = (step) => ask(which, "setStep", step);
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
