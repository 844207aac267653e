// Your own objects (docs/studio.md "Your own objects"): objects and landmarks
// made, changed and removed in the page, saved as an objects file (PUT
// /api/objects/{name}); and the template or file the Teach view starts from,
// kept in the work folder across reloads (GET/PUT /api/source).

import { api, get } from "./api.js";
import { $, SHAPES_IN_SCENES, alarm, clone, say, state } from "./common.js";
import { keepInView, redraw, sceneChanged } from "./stage.js";
import { halfExtents, snap } from "./table.js";
import { refreshFiles } from "./files.js";

// --- the template or file in use, kept in the work folder across reloads ---

export function showSource() {
  const source = state.source;
  $("template").value = source.kind === "template" ? source.id : "";
  const edited = state.teach.edited ? " — changed here, not saved (Save objects)" : "";
  $("source-shown").textContent = source.kind === "template"
    ? `In use: template ${source.id}${edited}`
    : `In use: ${source.name}${edited}`;
}

export async function keepSource() {
  const source = state.source;
  const body = source.kind === "template" ? { kind: "template", id: source.id } : { kind: "file", id: source.name };
  await api("PUT", "/api/source", body);
  showSource();
}

// At start: the template or file last used in this work folder (if it is still there).
export async function restoreSource() {
  const { source } = await get("/api/source");
  const files = state.files;
  if (source && source.kind === "template" && [...$("template").options].some((o) => o.value === source.id)) {
    state.source = { kind: "template", id: source.id };
  } else if (source && source.kind === "file" && ["objects", "scenes", "demonstrations"].some((k) => files[k].includes(source.id))) {
    state.source = { kind: "file", name: source.id };
  }
  showSource();
}

// --- your own objects -------------------------------------------------------

const cm = (v) => Math.round(v * 1000) / 10;

export function renderThings() {
  const list = $("things");
  list.replaceChildren();
  const layout = state.layout;
  const entries = [
    ...Object.entries(layout.objects).filter(([n]) => !state.clutter.includes(n)).map(([n, g]) => [n, g, "object"]),
    ...Object.entries(layout.landmarks || {}).map(([n, g]) => [n, g, "landmark"]),
  ];
  for (const [name, geometry, kind] of entries) {
    const li = document.createElement("li");
    li.dataset.thing = name;
    const swatch = document.createElement("span");
    swatch.className = "swatch";
    swatch.style.background = geometry.colour || "#999";
    const size = geometry.size ? geometry.size.map(cm).join(" × ") + " cm" : "size unknown";
    const extras = [
      geometry.mass != null ? `${geometry.mass} kg` : null,
      geometry.density != null ? `${geometry.density} kg/m³` : null,
      geometry.type ? `type ${geometry.type}` : null,
    ].filter(Boolean).join(", ");
    const text = document.createElement("span");
    text.textContent = `${name}: ${kind === "landmark" ? "landmark, " : ""}${geometry.shape} ${size}${extras ? `, ${extras}` : ""}`;
    const edit = document.createElement("button");
    edit.type = "button";
    edit.textContent = "Edit";
    edit.setAttribute("aria-label", `Edit ${name}`);
    edit.addEventListener("click", () => editThing(name, kind));
    const remove = document.createElement("button");
    remove.type = "button";
    remove.textContent = "Remove";
    remove.setAttribute("aria-label", `Remove ${name}`);
    remove.addEventListener("click", () => removeThing(name, kind));
    li.append(swatch, text, edit, remove);
    list.appendChild(li);
  }
  showSource();
}

function editThing(name, kind) {
  const thing = kind === "landmark" ? state.layout.landmarks[name] : state.layout.objects[name];
  $("thing-kind").value = kind;
  $("thing-name").value = name;
  $("thing-shape").value = SHAPES_IN_SCENES.has(thing.shape) ? thing.shape : "box";
  const size = thing.size || [0.05, 0.05, 0.05];
  ["thing-x", "thing-y", "thing-z"].forEach((id, k) => { $(id).value = String(cm(size[k])); });
  $("thing-colour").value = thing.colour || "#999999";
  $("thing-mass").value = thing.mass != null ? String(thing.mass) : "";
  $("thing-density").value = thing.density != null ? String(thing.density) : "";
  $("thing-type").value = thing.type || "";
  $("thing-name").focus();
}

// The objects change the start: only before the first step.
function startCanChange() {
  if (state.teach.steps.length) {
    alarm("the objects change the start of a demonstration: Save or Undo its steps first, then press New demonstration");
    return false;
  }
  return true;
}

function removeThing(name, kind) {
  if (!startCanChange()) return;
  alarm(""); // what a refused Add said is no longer the news
  if (kind === "landmark") delete state.layout.landmarks[name];
  else {
    delete state.layout.objects[name];
    delete state.teach.poses[name];
    delete state.teach.initial[name];
  }
  state.teach.edited = true;
  state.plan.poses = null;
  state.plan.landmarks = null;
  sceneChanged();
  renderThings();
  redraw();
  say(`${name} removed.`);
}

// Right of everything on the table: a free place for a new thing.
function freePlace(size, shape) {
  const [x0, y0] = state.layout.table.origin;
  const [width, depth] = state.layout.table.size;
  let right = x0;
  const boxes = []; // [left, bottom, right, top] of every thing on the table
  const things = [
    ...Object.entries(state.teach.poses).map(([n, p]) => [state.layout.objects[n], p]),
    ...Object.values(state.layout.landmarks || {}).map((m) => [m, m]),
  ];
  for (const [geometry, pose] of things) {
    if (!geometry || !geometry.size) continue;
    const [ex, ey] = halfExtents(geometry.shape, geometry.size, pose.yaw);
    const [x, y] = pose.position;
    boxes.push([x - ex, y - ey, x + ex, y + ey]);
    right = Math.max(right, x + ex);
  }
  const [hx, hy] = halfExtents(shape, size, 0);
  const beside = [snap(right + 0.03 + hx), snap(y0 + 0.03 + hy)];
  if (beside[0] + hx <= x0 + width) return beside;
  // no room left of the table's right edge: the first free spot on the table,
  // 3 cm clear of everything, row by row from the bottom left
  const gap = 0.03;
  const clear = (cx, cy) => boxes.every(([l, b, r, t]) =>
    cx + hx + gap <= l || cx - hx - gap >= r || cy + hy + gap <= b || cy - hy - gap >= t);
  for (let cy = y0 + gap + hy; cy + hy <= y0 + depth + 1e-9; cy += 0.01) {
    for (let cx = x0 + gap + hx; cx + hx <= x0 + width + 1e-9; cx += 0.01) {
      if (clear(cx, cy)) return [snap(cx), snap(cy)];
    }
  }
  return beside; // a full table: beside it, to be dragged on
}

// m³ of the solid the physics simulates (ObjectGeometry.volume): a box, a
// sphere of the largest extent, a cylinder of the larger of x and y.
function solidVolume(shape, [x, y, z]) {
  if (shape === "box") return x * y * z;
  if (shape === "sphere") return (4 / 3) * Math.PI * (Math.max(x, y, z) / 2) ** 3;
  return Math.PI * (Math.max(x, y) / 2) ** 2 * z;
}

// A number to four significant digits as Python's "{:.4g}" writes it
// (3.979e+05, 301.6, 0.9549), so that the page and the file's check agree.
function fourDigits(value) {
  const exponent = Math.floor(Math.log10(Math.abs(value)));
  const trimmed = (text) => (text.includes(".") ? text.replace(/\.?0+$/, "") : text);
  if (exponent < -4 || exponent >= 4) {
    const [mantissa, power] = value.toExponential(3).split("e");
    const sign = power.startsWith("-") ? "-" : "+";
    return `${trimmed(mantissa)}e${sign}${power.replace(/^[-+]/, "").padStart(2, "0")}`;
  }
  return trimmed(value.toPrecision(4));
}

export function addThing() {
  if (!startCanChange()) return;
  const kind = $("thing-kind").value;
  const name = $("thing-name").value.trim();
  // documents/names.py's rule, and the studio's 60 characters and no '#'
  if (!/^[^\s#]{1,60}$/.test(name) || /[\p{C}\p{Z}]/u.test(name)) {
    alarm("Name: 1–60 characters without spaces or '#' expected (names appear in plans)");
    return;
  }
  if (/^(loc|freespace|grasp)\d+$/.test(name)) {
    alarm(`Name: ${name} is a name demoplan gives locations and grasps (loc…, freespace…, grasp…); another name expected`);
    return;
  }
  const other = kind === "landmark" ? state.layout.objects : state.layout.landmarks || {};
  if (other[name]) {
    alarm(`Name: ${name} is already ${kind === "landmark" ? "an object" : "a landmark"}; another name expected`);
    return;
  }
  const shape = $("thing-shape").value;
  const size = ["thing-x", "thing-y", "thing-z"].map((id) => Math.round(Number($(id).value) * 1000) / 100000);
  if (size.some((v) => !Number.isFinite(v) || v < 0.001 || v > 3)) {
    alarm("Size: three extents of 0.1 to 300 cm expected");
    return;
  }
  const mass = $("thing-mass").value.trim();
  if (mass !== "" && !(Number(mass) > 0 && Number(mass) <= 1000)) {
    alarm("Mass (kg): a number above 0 and at most 1000 expected (empty: solid wood)");
    return;
  }
  const density = $("thing-density").value.trim();
  if (density !== "" && !(Number(density) >= 1.2 && Number(density) <= 22600)) {
    alarm("density (kg/m³): a number from 1.2 (air) to 22600 (osmium) expected (empty: solid wood)");
    return;
  }
  if (mass !== "" && density !== "") {
    alarm("Mass (kg) or density (kg/m³): one of them expected, not both");
    return;
  }
  const volume = solidVolume(shape, size);
  const implied = Number(mass) / volume;
  if (mass !== "" && !(implied >= 1.2 && implied <= 22600)) {
    // as the objects file's check says it (documents/masses.py): 120 typed for 120 g
    alarm(
      `Mass (kg): ${Number(mass)} kg in ${fourDigits(volume * 1e6)} cm³ is a mean density of ` +
        `${fourDigits(implied)} kg/m³; between 1.2 (air) and 22600 (osmium) expected`,
    );
    return;
  }
  const colour = $("thing-colour").value;
  const type = $("thing-type").value.trim();
  if (type && !/^[^\s#]{1,60}$/.test(type)) {
    alarm("Type: a name without spaces or '#' expected (objects of one type are interchangeable)");
    return;
  }
  if (kind === "landmark") {
    state.layout.landmarks = state.layout.landmarks || {};
    const old = state.layout.landmarks[name];
    const position = old ? old.position : [...freePlace(size, shape), 0];
    state.layout.landmarks[name] = { shape, size, colour, position, yaw: old ? old.yaw || 0 : 0 };
  } else {
    const geometry = { shape, size, colour };
    if (mass !== "") geometry.mass = Number(mass);
    if (density !== "") geometry.density = Number(density);
    if (type) geometry.type = type;
    const known = state.layout.objects[name];
    state.layout.objects[name] = geometry;
    if (!known) {
      const pose = { position: [...freePlace(size, shape), 0], yaw: 0 };
      state.teach.poses[name] = pose;
      state.teach.initial[name] = clone(pose);
    }
  }
  state.layout.template = null;
  state.teach.edited = true;
  state.plan.poses = null;
  state.plan.landmarks = null;
  sceneChanged();
  keepInView({ ...state.teach.poses, ...state.layout.landmarks });
  renderThings();
  redraw();
  say(`${name} ${kind === "landmark" ? "(landmark) " : ""}is on the table: drag it where the task starts.`);
}

// The objects, the landmarks and where they stand now, as an objects file;
// from then on the Teach view starts from it.
export async function saveObjects() {
  if (!startCanChange()) return;
  const name = $("objects-name").value.trim() || "objects.json";
  const layout = { ...state.layout, poses: state.teach.poses };
  const replace = state.files.objects.includes(name);
  const answer = await api("PUT", `/api/objects/${encodeURIComponent(name)}`, { layout, replace });
  state.teach.edited = false;
  state.source = { kind: "file", name: answer.file };
  await refreshFiles();
  await keepSource();
  say(`Saved ${answer.file}: New demonstration starts from it (also after a reload).`);
}
