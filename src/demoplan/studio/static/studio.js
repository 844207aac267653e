// demoplan studio: teach, learn, plan and run in the browser (docs/studio.md).
// Plain ES modules; every value shown comes from the studio's server, which
// calls demoplan's command layer (docs/studio-api.md). This module wires the
// views together.

import { $, clone, guarded, say, state } from "./common.js";
import { learn } from "./learn.js";
import {
  addClutter, clearPlan, ensurePlanStart, loadPlanScene, makePlan, saveScene, scramble, setPlanStep,
} from "./plan.js";
import { cancelRun, restoreLastRun, setRunStep, startRun } from "./run.js";
import { play, redraw, stopAnimation, table, tableRoom } from "./stage.js";
import { refreshFiles } from "./files.js";
import { addThing, restoreSource, saveObjects } from "./objects.js";
import { loadFile, newDemonstration, save, undo, useTemplate } from "./teach.js";
import { get } from "./api.js";

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
  $("template").addEventListener("change", () => guarded(() => useTemplate($("template").value)));
  $("add-thing").addEventListener("click", () => guarded(addThing));
  $("save-objects").addEventListener("click", () => guarded(saveObjects));
  $("save-scene").addEventListener("click", () => guarded(saveScene));
  $("new").addEventListener("click", () => guarded(newDemonstration));
  $("save").addEventListener("click", () => guarded(save));
  $("load").addEventListener("click", () => guarded(loadFile));
  $("undo").addEventListener("click", undo);
  $("learn").addEventListener("click", () => guarded(learn));
  $("scramble").addEventListener("click", () => guarded(scramble));
  $("add-clutter").addEventListener("click", () => guarded(addClutter));
  $("load-plan-file").addEventListener("click", () => guarded(loadPlanScene));
  $("start-from-teach").addEventListener("click", () => {
    state.plan.poses = clone(state.teach.poses);
    state.plan.landmarks = clone(state.layout.landmarks || {});
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
    await restoreSource();
    await newDemonstration();
    await restoreLastRun();
  });
  document.body.dataset.ready = "true";
}

start();
