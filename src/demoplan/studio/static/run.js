// The Run view: a run in a process of its own on the server, polled, its events
// as a timeline (POST /api/runs); the table shows the world the run observed at
// each event; the run that ended last is shown again when the page is opened
// (GET /api/last-run).

import { ApiError, del, get, post } from "./api.js";
import { $, alarm, clone, guarded, plural, say, state } from "./common.js";
import { chosenModel, sceneDocument, sceneExtras } from "./plan.js";
import { PLANNED_KEYS, inTableColours, keepInView, redraw, registerView, sameThings, stopAnimation } from "./stage.js";
import { startDemonstration } from "./teach.js";

// Polls in a row that may fail (a busy server) before the run is given up as lost.
export const LOST_AFTER_FAILED_POLLS = 3;

// --- the world at each event ----------------------------------------------

export function runEvents() {
  return state.run.status ? state.run.status.events : [];
}

// The world at event `step` (1-based): the objects standing, with their poses,
// as the run observed them when the event happened (an object in the hand
// stands nowhere and is not drawn); before the first event, the start scene.
export function runWorldAt(step) {
  const events = runEvents();
  for (let i = Math.min(step, events.length) - 1; i >= 0; i -= 1) {
    if (events[i].world) return events[i].world;
  }
  return null;
}

export function runPosesAt(step) {
  const world = runWorldAt(step);
  return world ? clone(world.objects) : clone(state.plan.poses || state.teach.poses);
}

export function setRunStep(step, { follow = false } = {}) {
  const total = runEvents().length;
  state.run.step = Math.max(0, Math.min(step, total));
  state.run.follow = follow;
  $("run-step").max = String(total);
  $("run-step").value = String(state.run.step);
  $("run-step-out").textContent = `${state.run.step} / ${total}`;
  $("panel-run").dataset.step = String(state.run.step);
  document.querySelectorAll("#timeline li").forEach((li, i) => {
    if (i === state.run.step - 1) li.setAttribute("aria-current", "step");
    else li.removeAttribute("aria-current");
  });
  if (state.layout && state.run.step > 0) keepInView(runPosesAt(state.run.step));
  redraw();
}

// --- the timeline, the badge and the summary -------------------------------

export const MARKS = { plan: "▸", failure: "✗", replan: "↻", action: "•" };

// Whether the run reached its goal: true, false, or null while unknown.
export function runSucceeded(status) {
  if (status.result) return Boolean(status.result.success);
  if (status.state === "running") return null;
  return false; // failed, cancelled or lost: no goal reached
}

// How an event is shown: its mark and class. The end is ✓ (green) only when
// the run reached its goal, ✗ (red) when it did not, ■ until the result says.
export function eventLook(event, status) {
  if (event.kind !== "done") return { mark: MARKS[event.kind] || "•", look: event.kind };
  const told = event.status ? event.status === "succeeded" : runSucceeded(status);
  const success = event.success !== undefined ? event.success : told;
  if (success === true) return { mark: "✓", look: "done" };
  if (success === false) return { mark: "✗", look: "failure" };
  return { mark: "■", look: "end" };
}

// The badge: running, done (the goal reached), failed (not reached, or the
// run's process failed), cancelled, or error (the studio lost).
export function badgeState(status) {
  if (status.state === "done") return status.result && status.result.success ? "done" : "failed";
  return status.state;
}

function renderTimeline(status) {
  const list = $("timeline");
  const events = status.events;
  while (list.children.length > events.length) list.lastChild.remove();
  events.forEach((event, i) => {
    const { mark, look } = eventLook(event, status);
    const text = `${mark} ${event.text}`;
    let li = list.children[i];
    if (li && li.dataset.kind === event.kind && li.dataset.look === look && li.firstChild.textContent === text) return;
    if (!li) {
      li = document.createElement("li");
      const button = document.createElement("button");
      button.type = "button";
      button.className = "event-button";
      button.addEventListener("click", () => {
        stopAnimation("run");
        setRunStep(i + 1);
      });
      li.appendChild(button);
      list.appendChild(li);
    }
    li.dataset.kind = event.kind;
    li.dataset.look = look;
    li.className = `event ${look}`;
    li.firstChild.textContent = text;
    li.firstChild.setAttribute("aria-label", `${event.kind === "done" ? "end" : event.kind}: ${event.text}`);
  });
}

function summaryOf(status) {
  const r = status.result;
  if (r) {
    // one failure from the next by "; " (a space alone ran "… after the grasp step 2: …" together)
    const failures = `${plural(r.replans, "replan")}, ${plural(r.failures.length, "failure")} detected` +
      (r.failures.length ? `: ${r.failures.join("; ")}.` : ".");
    return `${r.success ? "Success" : "Failed"}: ${r.reason}. ${failures}`;
  }
  if (status.state === "running") return `Running: ${plural(status.events.length, "event")} so far.`;
  if (status.error) return `Stopped: ${status.error}`;
  return `Run ${status.state}.`;
}

// toEnd: show the last event (the final world) whatever was selected.
export function renderRun(toEnd = false) {
  const status = state.run.status;
  renderTimeline(status);
  const badge = $("run-state");
  const shown = badgeState(status);
  badge.textContent = shown;
  badge.dataset.state = shown;
  $("cancel").disabled = status.state !== "running";
  $("run").disabled = status.state === "running";
  $("run-summary").textContent = summaryOf(status);
  const video = $("video");
  const source = status.result ? status.result.video : null;
  video.hidden = !source;
  if (source && video.getAttribute("src") !== source) video.src = source;
  if (status.error) alarm(status.error);
  const total = status.events.length;
  const follow = status.state === "running" && state.run.follow;
  setRunStep(toEnd || follow ? total : Math.min(state.run.step, total), { follow });
}

// --- starting, following, cancelling ---------------------------------------

export async function startRun() {
  const model = chosenModel();
  stopPolling();
  stopAnimation("run");
  const body = {
    model, scene: sceneDocument(), faults: $("faults").value.trim(),
    seed: Number($("run-seed").value) || 0, sim: $("sim").value,
  };
  // From the click on, the page shows this run, not the last one: while the
  // request is answered, the badge of a run that ended green must not stand
  // for one that is starting (it read `done` then). A refused request puts the
  // last run back.
  const last = { id: state.run.id, status: state.run.status };
  state.run.id = null;
  state.run.status = { state: "running", events: [], result: null, error: null };
  $("timeline").replaceChildren();
  renderRun(true);
  let answer;
  try {
    answer = await post("/api/runs", body);
  } catch (error) {
    state.run.id = last.id;
    state.run.status = last.status;
    $("timeline").replaceChildren();
    if (last.status) renderRun(true);
    else showNoRun();
    throw error;
  }
  state.run.id = answer.run;
  state.run.follow = true;
  state.run.failedPolls = 0;
  say(`Run ${answer.run} started.`);
  state.run.poll = setInterval(() => guarded(pollRun), 300);
}

// The Run view before any run: the badge as the page starts it.
function showNoRun() {
  const badge = $("run-state");
  badge.textContent = "idle";
  badge.dataset.state = "idle";
  $("cancel").disabled = true;
  $("run").disabled = false;
  $("run-summary").textContent = "";
}

export function stopPolling() {
  if (state.run.poll) clearInterval(state.run.poll);
  state.run.poll = null;
}

export async function pollRun() {
  const id = state.run.id;
  if (!id || state.run.polling) return;
  state.run.polling = true; // one poll at a time: a slow answer is not asked for twice
  let status;
  try {
    status = await get(`/api/runs/${encodeURIComponent(id)}`);
  } catch (error) {
    if (id === state.run.id) lostTrack(error);
    return;
  } finally {
    state.run.polling = false;
  }
  if (id !== state.run.id) return;
  state.run.failedPolls = 0;
  state.run.status = status;
  const over = status.state !== "running";
  if (over) stopPolling();
  renderRun(over);
  if (over) say(`Run ${badgeState(status)}${status.result ? `: ${status.result.reason}` : ""}.`);
}

// A poll that failed: after LOST_AFTER_FAILED_POLLS in a row (the studio
// stopped, or restarted and forgot the run) the run is shown as an error.
function lostTrack(error) {
  state.run.failedPolls = (state.run.failedPolls || 0) + 1;
  const gone = error instanceof ApiError && error.status === 404;
  if (!gone && state.run.failedPolls < LOST_AFTER_FAILED_POLLS) return;
  stopPolling();
  const why = error instanceof ApiError ? error.message : String(error.message || error);
  state.run.status = {
    ...state.run.status,
    state: "error",
    error: `the run's end is unknown: ${why}`,
  };
  renderRun(true);
  say("The run was lost.");
}

export async function cancelRun() {
  if (!state.run.id) return;
  await del(`/api/runs/${encodeURIComponent(state.run.id)}`);
  say("Cancelling the run…");
}

// --- the last run, when the page is opened ----------------------------------

// The run that ended last in the work folder, shown as it ended: the start
// scene it ran from on the table (the Teach view starts there too when its
// objects are others, or differ in shape or size), its events, and its final world.
export async function restoreLastRun() {
  const record = await get("/api/last-run");
  if (!record) return; // no run has ended in this work folder yet
  const layout = record.layout;
  if (!state.layout || !sameThings(state.layout, layout, PLANNED_KEYS)) {
    startDemonstration(clone(layout), "The table of the last run.");
  }
  state.plan.poses = clone(layout.poses);
  state.plan.landmarks = inTableColours(layout, record.scene); // where the run's landmarks stood
  state.plan.extras = sceneExtras({ format: "demoplan/scene-1", ...record.scene });
  keepInView(state.plan.poses);
  for (const [id, value] of [["faults", record.faults || ""], ["run-seed", String(record.seed || 0)]]) $(id).value = value;
  if ([...$("sim").options].some((o) => o.value === record.sim)) $("sim").value = record.sim;
  if ([...$("plan-model").options].some((o) => o.value === record.model)) $("plan-model").value = record.model;
  state.run.id = record.run;
  state.run.status = { state: record.state, events: record.events, result: record.result, error: record.error };
  state.run.follow = false;
  $("timeline").replaceChildren();
  renderRun(true);
  alarm("");
  say(`The last run of this work folder (${badgeState(state.run.status)}) is in the Run view.`);
}

registerView("run", { posesAt: runPosesAt, steps: () => runEvents().length, setStep: setRunStep });
