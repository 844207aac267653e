// The Run view: a run in a worker thread on the server, polled, its events as a timeline (POST /api/runs).

import { del, get, post } from "./api.js";
import { $, alarm, clone, guarded, say, state } from "./common.js";
import { chosenModel, sceneDocument, stopAnimation } from "./plan.js";
import { redraw } from "./stage.js";

// --- run ------------------------------------------------------------------

export function runEvents() {
  return state.run.status ? state.run.status.events : [];
}

export function runPosesAt(step) {
  const poses = clone(state.plan.poses || state.teach.poses);
  for (const event of runEvents().slice(0, step)) {
    if (event.poses) Object.assign(poses, clone(event.poses));
  }
  return poses;
}

export function setRunStep(step) {
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

export const MARKS = { plan: "▸", failure: "✗", replan: "↻", done: "✓", action: "•" };

export function renderRun() {
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

export async function startRun() {
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

export function stopPolling() {
  if (state.run.poll) clearInterval(state.run.poll);
  state.run.poll = null;
}

export async function pollRun() {
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

export async function cancelRun() {
  if (!state.run.id) return;
  await del(`/api/runs/${encodeURIComponent(state.run.id)}`);
  say("Cancelling the run…");
}
