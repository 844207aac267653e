// The work folder's files, listed in every view that chooses one (Teach, Learn, Plan).

import { get } from "./api.js";
import { $, plural, state } from "./common.js";

export async function refreshFiles() {
  state.files = await get("/api/files");
  const file = $("file");
  const keep = file.value;
  file.replaceChildren(new Option("(none)", ""));
  for (const kind of ["objects", "demonstrations", "scenes"]) {
    const group = document.createElement("optgroup");
    group.label = kind;
    for (const name of state.files[kind]) group.appendChild(new Option(name, name));
    if (state.files[kind].length) file.appendChild(group);
  }
  file.value = ["objects", "demonstrations", "scenes"].some((k) => state.files[k].includes(keep)) ? keep : "";
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
  for (const kind of ["scenes", "objects", "demonstrations"]) {
    const group = document.createElement("optgroup");
    group.label = kind;
    for (const name of state.files[kind]) group.appendChild(new Option(name, name));
    if (state.files[kind].length) planFile.appendChild(group);
  }
  planFile.value = ["scenes", "objects", "demonstrations"].some((k) => state.files[k].includes(keepPlan)) ? keepPlan : "";
  const models = $("plan-model");
  const current = models.value;
  models.replaceChildren();
  for (const name of state.files.models) models.appendChild(new Option(name, name));
  // the model chosen stays; else the one learned last (not the first by name)
  if (state.files.models.includes(current)) models.value = current;
  else if (state.files.latest_model) models.value = state.files.latest_model;
  $("workfolder").textContent = `work folder: ${plural(state.files.demonstrations.length, "demonstration")}, ` +
    `${plural(state.files.models.length, "model")}, ${plural(state.files.scenes.length, "scene")}`;
}
