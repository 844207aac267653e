// The Learn view: the model learned from the chosen demonstrations (POST /api/learn).

import { post } from "./api.js";
import { $, alarm, fmt, mm, plural, say, state } from "./common.js";
import { drawGraph } from "./graph.js";
import { redraw } from "./stage.js";
import { refreshFiles } from "./files.js";
import { teachSceneDocument } from "./teach.js";

// --- learn ----------------------------------------------------------------

export async function learn() {
  const files = [...document.querySelectorAll("#learn-files input:checked")].map((i) => i.value);
  if (!files.length) {
    alarm("choose at least one demonstration to learn from (save one in the Teach view)");
    return;
  }
  const output = $("model-name").value.trim() || "model.json";
  say("Learning…");
  // the targets are drawn where the table stands now (its landmarks as placed)
  const scene = teachSceneDocument();
  let result;
  try {
    result = await post("/api/learn", { files, output, scene: Object.keys(scene.objects).length ? scene : null });
  } catch (error) {
    say("Not learned."); // not "Learning…" under the alert that says why
    throw error;
  }
  state.learn.result = result;
  renderLearned(result);
  await refreshFiles();
  $("plan-model").value = result.model;
  say(`Learned ${plural(result.states.length, "state")} from ${plural(files.length, "demonstration")}; saved ${result.model}.`);
  redraw();
}

export function renderLearned(result) {
  const body = $("states").tBodies[0];
  body.replaceChildren();
  for (const s of result.states) {
    const row = body.insertRow();
    row.dataset.state = s.id;
    // the references in the words of `learn`'s states table (the server's, so the two agree)
    const cells = [
      s.id, s.object, s.relative_position || "absolute",
      s.relative_orientation || (s.yaw === null ? "—" : "absolute"), mm(s.spread), s.margin === null || s.margin === undefined ? "—" : `${fmt(s.margin, 2)} ×`,
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
    if (s.notes.length) row.title = s.notes.join("\n"); // every note, also those the cells shorten
  }
  renderRoles(result.roles || []);
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

// Identical objects: per role its type and, per demonstration, the instance
// that filled it (hidden for a model without roles).
function renderRoles(roles) {
  $("roles-box").hidden = !roles.length;
  const count = Math.max(0, ...roles.map((r) => r.instances.length));
  const head = $("roles").tHead.rows[0];
  head.replaceChildren(...["Role", "Type", ...Array.from({ length: count }, (_, k) => `Demonstration ${k + 1}`)].map((text) => {
    const th = document.createElement("th");
    th.scope = "col";
    th.textContent = text;
    return th;
  }));
  const body = $("roles").tBodies[0];
  body.replaceChildren();
  for (const role of roles) {
    const row = body.insertRow();
    const th = document.createElement("th");
    th.scope = "row";
    th.textContent = role.name;
    row.appendChild(th);
    row.insertCell().textContent = role.type;
    for (const instance of role.instances) row.insertCell().textContent = instance ?? "—";
  }
}
