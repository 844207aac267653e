// The studio page's state and messages, shared by every view.

import { ApiError } from "./api.js";

export const $ = (id) => document.getElementById(id);
export const clone = (value) => JSON.parse(JSON.stringify(value));
export const fmt = (v, digits = 3) => (v === null || v === undefined ? "—" : Number(v).toFixed(digits));
export const mm = (v) => (v === null || v === undefined ? "—" : `${(v * 1000).toFixed(1)} mm`);
// `count` and `noun`, in the plural unless `count` is 1 (`many` where adding an s
// is wrong), as src/demoplan/wording.py's plural words it for the command line
export const plural = (count, noun, many) => `${count} ${count === 1 ? noun : many || `${noun}s`}`;
export const SHAPES_IN_SCENES = new Set(["box", "cylinder", "sphere"]);

export const state = {
  view: "teach",
  layout: null, // {template, objects, landmarks, poses, table}
  source: { kind: "template", id: "set_table" },
  teach: { initial: {}, poses: {}, steps: [], saved: false },
  learn: { result: null },
  plan: { poses: null, landmarks: null, extras: null, result: null, step: 0, timer: null },
  run: { id: null, status: null, step: 0, timer: null, poll: null },
  clutter: [], // objects added in the Plan view that the model never saw
  selected: null,
  files: { demonstrations: [], models: [], scenes: [] },
};

// --- messages -------------------------------------------------------------

export function say(text) {
  $("status").textContent = text;
}

export function alarm(text) {
  const box = $("alert");
  box.textContent = text;
  box.hidden = !text;
}

export function failed(error) {
  const text = error instanceof ApiError ? error.message : `unexpected error: ${error.message || error}`;
  alarm(text);
}

export async function guarded(action) {
  try {
    alarm("");
    await action();
  } catch (error) {
    failed(error);
  }
}
