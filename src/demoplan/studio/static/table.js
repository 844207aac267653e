// The table seen from above (SVG) and the side strip of heights.
//
// Scale contract (docs/studio.md): the <svg id="table"> element carries
// data-metres-per-pixel and data-origin="x y", the world point (metres) at the
// element's bottom-left corner; world y grows upwards on screen. One SVG user
// unit is one CSS pixel.

const SVG = "http://www.w3.org/2000/svg";
const MARGIN = 0.03; // metres drawn around the layout's table rectangle
const SNAP = 1e-4; // positions snap to 0.1 mm
const STRIP_WIDTH = 90; // px, the side strip of heights

export const snap = (v) => Math.round(v / SNAP) * SNAP;
const round6 = (v) => Math.round(v * 1e6) / 1e6;

function el(name, attributes = {}, parent = null) {
  const node = document.createElementNS(SVG, name);
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, String(value));
  if (parent) parent.appendChild(node);
  return node;
}

// Half extents of a footprint along world x and y (rotated box or ellipse).
export function halfExtents(shape, size, yaw) {
  const t = ((yaw || 0) * Math.PI) / 180;
  const c = Math.abs(Math.cos(t));
  const s = Math.abs(Math.sin(t));
  if (shape === "cylinder" || shape === "sphere") {
    const a = size[0] / 2;
    const b = (shape === "sphere" ? size[0] : size[1]) / 2;
    return [Math.hypot(a * c, b * s), Math.hypot(a * s, b * c)];
  }
  return [(c * size[0] + s * size[1]) / 2, (s * size[0] + c * size[1]) / 2];
}

export function height(shape, size) {
  return shape === "sphere" ? size[0] : size[2];
}

function darker(hex) {
  const m = /^#([0-9a-f]{6})$/i.exec(hex || "");
  if (!m) return "#333";
  const n = parseInt(m[1], 16);
  const part = (shift) => Math.round(((n >> shift) & 255) * 0.55);
  return `rgb(${part(16)},${part(8)},${part(0)})`;
}

// The objects standing on `name` (touching its top, footprints overlapping).
export function ridersOf(name, layout, poses) {
  const base = layout.objects[name];
  const pose = poses[name];
  const top = (pose.position[2] || 0) + height(base.shape, base.size);
  const [bx, by] = halfExtents(base.shape, base.size, pose.yaw);
  const riders = [];
  for (const [other, geometry] of Object.entries(layout.objects)) {
    if (other === name || !poses[other]) continue;
    const p = poses[other];
    if (Math.abs((p.position[2] || 0) - top) > 0.003) continue;
    const [ox, oy] = halfExtents(geometry.shape, geometry.size, p.yaw);
    const overlapX = bx + ox - Math.abs(p.position[0] - pose.position[0]);
    const overlapY = by + oy - Math.abs(p.position[1] - pose.position[1]);
    if (overlapX > 0.001 && overlapY > 0.001) riders.push(other);
  }
  return riders;
}

export class TableView {
  constructor(svg, strip, handlers) {
    this.svg = svg;
    this.strip = strip;
    this.handlers = handlers;
    this.layout = null;
    this.poses = {};
    this.options = {};
    this.drag = null;
    this.maxWidth = 700;
    this.maxHeight = 600;
    svg.addEventListener("pointerdown", (e) => this.pointerDown(e));
    svg.addEventListener("pointermove", (e) => this.pointerMove(e));
    svg.addEventListener("pointerup", (e) => this.pointerUp(e));
    svg.addEventListener("pointercancel", () => this.cancelDrag());
    svg.addEventListener("wheel", (e) => this.wheel(e), { passive: false });
    svg.addEventListener("keydown", (e) => this.key(e));
    svg.addEventListener("focusin", (e) => {
      const name = thingOf(e.target);
      if (name && name !== this.options.selected) this.handlers.select(name);
    });
  }

  // available: [width, height] in CSS pixels for the table drawing.
  setLayout(layout, available = null) {
    this.layout = layout;
    if (available) [this.maxWidth, this.maxHeight] = available.map((v) => Math.max(300, Math.floor(v)));
    const [x0, y0] = layout.table.origin;
    const [w, h] = layout.table.size;
    const width = w + 2 * MARGIN;
    const depth = h + 2 * MARGIN;
    // A round scale (0.05 mm steps) so that the numbers in data-* stay short.
    const raw = Math.max(width / this.maxWidth, depth / this.maxHeight);
    this.mpp = Math.ceil(raw / 5e-5) * 5e-5;
    this.origin = [round6(x0 - MARGIN), round6(y0 - MARGIN)];
    this.widthPx = Math.ceil(width / this.mpp);
    this.heightPx = Math.ceil(depth / this.mpp);
    this.svg.setAttribute("width", this.widthPx);
    this.svg.setAttribute("height", this.heightPx);
    this.svg.setAttribute("viewBox", `0 0 ${this.widthPx} ${this.heightPx}`);
    this.svg.dataset.metresPerPixel = String(this.mpp);
    this.svg.dataset.origin = `${this.origin[0]} ${this.origin[1]}`;
  }

  px(x) {
    return (x - this.origin[0]) / this.mpp;
  }

  py(y) {
    return this.heightPx - (y - this.origin[1]) / this.mpp;
  }

  world(event) {
    const box = this.svg.getBoundingClientRect();
    const scale = this.widthPx / box.width; // 1 unless zoomed by CSS
    const u = (event.clientX - box.left) * scale;
    const v = (event.clientY - box.top) * scale;
    return [this.origin[0] + u * this.mpp, this.origin[1] + (this.heightPx - v) * this.mpp];
  }

  // The landmarks as shown: options.landmarks (the Plan view's start) or the layout's.
  landmarks() {
    return this.options.landmarks || this.layout.landmarks || {};
  }

  // poses: name -> {position:[x,y,z], yaw}; options: {selected, held, outlines:[...],
  // interactive, landmarksMovable, landmarks}
  draw(poses, options = {}) {
    this.poses = poses;
    this.options = options;
    const focused = thingOf(document.activeElement);
    this.svg.replaceChildren();
    const layout = this.layout;
    if (!layout) return;
    el("rect", { x: 0, y: 0, width: this.widthPx, height: this.heightPx, class: "floor" }, this.svg);
    const [x0, y0] = layout.table.origin;
    const [w, h] = layout.table.size;
    el("rect", {
      x: this.px(x0), y: this.py(y0 + h), width: w / this.mpp, height: h / this.mpp, class: "tabletop",
    }, this.svg);
    this.drawGrid();
    const landmarks = el("g", { class: "landmarks" }, this.svg);
    const movable = options.interactive && options.landmarksMovable;
    for (const [name, mark] of Object.entries(this.landmarks())) {
      const pose = this.drag && this.drag.name === name ? this.drag.pose : mark;
      const g = this.shape(landmarks, name, mark, pose, "landmark");
      g.dataset.landmark = name;
      g.dataset.x = String(round6(pose.position[0]));
      g.dataset.y = String(round6(pose.position[1]));
      g.dataset.yaw = String(round6(pose.yaw || 0));
      g.setAttribute(
        "aria-label",
        `landmark ${name} at x ${pose.position[0].toFixed(3)}, y ${pose.position[1].toFixed(3)} m, yaw ${(pose.yaw || 0).toFixed(1)}°`,
      );
      g.setAttribute("role", movable ? "button" : "img");
      g.setAttribute("tabindex", movable ? "0" : "-1");
      if (movable) g.classList.add("movable");
      if (name === options.selected) g.classList.add("selected");
    }
    const objects = el("g", { class: "objects" }, this.svg);
    const order = Object.keys(layout.objects)
      .filter((name) => poses[name])
      .sort((a, b) => poses[a].position[2] - poses[b].position[2]);
    for (const name of order) {
      const geometry = layout.objects[name];
      const pose = this.drag && this.drag.name === name ? this.drag.pose : poses[name];
      const g = this.shape(objects, name, geometry, pose, "object");
      g.dataset.object = name;
      g.dataset.x = String(round6(pose.position[0]));
      g.dataset.y = String(round6(pose.position[1]));
      g.dataset.z = String(round6(pose.position[2] || 0));
      g.dataset.yaw = String(round6(pose.yaw || 0));
      g.setAttribute("tabindex", options.interactive ? "0" : "-1");
      g.setAttribute("role", "button");
      g.setAttribute("aria-roledescription", "object");
      g.setAttribute(
        "aria-label",
        `object ${name} at x ${pose.position[0].toFixed(3)}, y ${pose.position[1].toFixed(3)}, ` +
          `z ${(pose.position[2] || 0).toFixed(3)} m, yaw ${(pose.yaw || 0).toFixed(1)}°`,
      );
      if (name === options.selected) g.classList.add("selected");
      if (name === options.held) g.classList.add("held");
      if (options.interactive) g.classList.add("movable");
    }
    // a landmark's name over the things standing in it (a caddy's, a box's),
    // where it covers none of them
    const names = el("g", { class: "landmark-labels" }, this.svg);
    const things = order.map((name) => this.footprintBox(
      layout.objects[name], this.drag && this.drag.name === name ? this.drag.pose : poses[name],
    ));
    for (const label of landmarks.querySelectorAll(".landmark > text.label")) {
      const name = label.parentNode.dataset.landmark;
      const g = el("g", { transform: label.parentNode.getAttribute("transform") }, names);
      g.appendChild(label);
      const mark = this.landmarks()[name];
      if (mark && mark.size) {
        const pose = this.drag && this.drag.name === name ? this.drag.pose : mark;
        this.placeLabel(label, mark, pose, things);
      }
    }
    const outlines = el("g", { class: "outlines" }, this.svg);
    const lettered = []; // where each state's letter went: stacked targets' side by side
    for (const target of options.outlines || []) {
      const geometry = layout.objects[target.object];
      if (!geometry) continue;
      const g = this.shape(outlines, target.object, geometry, target, "outline");
      g.dataset.target = target.state;
      g.dataset.x = String(round6(target.position[0]));
      g.dataset.y = String(round6(target.position[1]));
      g.dataset.yaw = String(round6(target.yaw || 0));
      let x = this.px(target.position[0]) + 4;
      const y = this.py(target.position[1]) - 4;
      while (lettered.some(([lx, ly]) => Math.abs(lx - x) < 9 && Math.abs(ly - y) < 11)) x += 10;
      lettered.push([x, y]);
      const label = el("text", { x, y, class: "outline-label" }, outlines);
      label.textContent = target.state;
    }
    if (focused) {
      this.svg.querySelector(`[data-object="${CSS.escape(focused)}"],[data-landmark="${CSS.escape(focused)}"]`)?.focus();
    }
    this.drawHeights(poses);
  }

  // A thing's footprint on the page: [left, top, right, bottom] in SVG units.
  footprintBox(geometry, pose) {
    const [hx, hy] = halfExtents(geometry.shape, geometry.size, pose.yaw);
    const x = this.px(pose.position[0]);
    const y = this.py(pose.position[1]);
    return [x - hx / this.mpp, y - hy / this.mpp, x + hx / this.mpp, y + hy / this.mpp];
  }

  // A landmark's name where it covers no thing on the table: inside its top
  // edge as always where that is free, else just outside it — above, below,
  // left, right — else where it covers the least; always on the page.
  placeLabel(label, mark, pose, things) {
    const [hx, hy] = halfExtents(mark.shape, mark.size, pose.yaw).map((h) => h / this.mpp);
    const d = mark.size[1] / this.mpp;
    const cx = this.px(pose.position[0]);
    const cy = this.py(pose.position[1]);
    const width = label.getComputedTextLength() || 6.5 * label.textContent.length;
    const tall = 11; // px: the labels' font size (studio.css)
    const candidates = [
      [0, -d / 2 + 12],
      [0, -hy - 4],
      [0, hy + tall + 2],
      [-hx - width / 2 - 4, 4],
      [hx + width / 2 + 4, 4],
    ];
    const covered = ([dx, dy]) => {
      const box = [cx + dx - width / 2, cy + dy - tall, cx + dx + width / 2, cy + dy + 2];
      const off = box[0] < 0 || box[1] < 0 || box[2] > this.widthPx || box[3] > this.heightPx;
      let area = 0;
      for (const [l, t, r, b] of things) {
        area += Math.max(0, Math.min(r, box[2]) - Math.max(l, box[0])) *
          Math.max(0, Math.min(b, box[3]) - Math.max(t, box[1]));
      }
      return off ? Infinity : area;
    };
    let best = candidates[0];
    let least = covered(best);
    for (const candidate of candidates.slice(1)) {
      if (least === 0) break;
      const area = covered(candidate);
      if (area < least) [best, least] = [candidate, area];
    }
    label.setAttribute("x", String(best[0]));
    label.setAttribute("y", String(best[1]));
  }

  drawGrid() {
    const grid = el("g", { class: "grid", "aria-hidden": "true" }, this.svg);
    const step = 0.1;
    const [ox, oy] = this.origin;
    const right = ox + this.widthPx * this.mpp;
    const top = oy + this.heightPx * this.mpp;
    for (let x = Math.ceil(ox / step) * step; x <= right; x += step) {
      el("line", { x1: this.px(x), x2: this.px(x), y1: 0, y2: this.heightPx }, grid);
      const t = el("text", { x: this.px(x) + 2, y: this.heightPx - 3 }, grid);
      t.textContent = `${x.toFixed(1)}`;
    }
    for (let y = Math.ceil(oy / step) * step; y <= top; y += step) {
      el("line", { x1: 0, x2: this.widthPx, y1: this.py(y), y2: this.py(y) }, grid);
      const t = el("text", { x: 2, y: this.py(y) - 2 }, grid);
      t.textContent = `${y.toFixed(1)}`;
    }
  }

  shape(parent, name, geometry, pose, kind) {
    const g = el("g", { class: kind, transform: `translate(${this.px(pose.position[0])} ${this.py(pose.position[1])})` }, parent);
    const turn = el("g", { transform: `rotate(${-(pose.yaw || 0)})` }, g);
    if (kind === "landmark" && !geometry.size) {
      // a landmark known only by its pose: a frame marker (x axis longer)
      el("circle", { r: 6, class: "marker" }, turn);
      el("line", { x1: 0, y1: 0, x2: 18, y2: 0, class: "marker-axis" }, turn);
      el("line", { x1: 0, y1: 0, x2: 0, y2: -10, class: "marker-axis" }, turn);
      el("text", { class: "label", y: -10 }, g).textContent = name;
      return g;
    }
    const size = geometry.size;
    const fill = kind === "outline" ? "none" : geometry.colour || "#999";
    const stroke = kind === "outline" ? geometry.colour || "#333" : darker(geometry.colour);
    const w = size[0] / this.mpp;
    const d = (geometry.shape === "sphere" ? size[0] : size[1]) / this.mpp;
    if (geometry.shape === "cylinder" || geometry.shape === "sphere") {
      el("ellipse", { rx: w / 2, ry: d / 2, fill, stroke }, turn);
    } else {
      el("rect", { x: -w / 2, y: -d / 2, width: w, height: d, fill, stroke }, turn);
      // a tick on the +x face shows the yaw
      el("line", { x1: w / 2 - Math.min(6, w / 3), y1: 0, x2: w / 2, y2: 0, stroke, class: "tick" }, turn);
    }
    if (kind !== "outline") {
      const label = el("text", { class: "label", y: kind === "landmark" ? -d / 2 + 12 : 4 }, g);
      label.textContent = name;
    }
    return g;
  }

  // The side strip: the table seen from +x, world y vertical as on the table,
  // heights growing to the right from the table top.
  drawHeights(poses) {
    const strip = this.strip;
    strip.replaceChildren();
    const layout = this.layout;
    const things = [];
    for (const [name, mark] of Object.entries(this.landmarks())) {
      const pose = this.drag && this.drag.name === name ? this.drag.pose : mark;
      if (mark.size) things.push({ name, geometry: mark, pose, landmark: true });
    }
    for (const [name, geometry] of Object.entries(layout.objects)) {
      const pose = this.drag && this.drag.name === name ? this.drag.pose : poses[name];
      if (pose) things.push({ name, geometry, pose, landmark: false });
    }
    const stripWidth = STRIP_WIDTH;
    const ground = 10;
    let top = 0.02;
    for (const t of things) top = Math.max(top, (t.pose.position[2] || 0) + height(t.geometry.shape, t.geometry.size));
    const scale = Math.min(2 / this.mpp, (stripWidth - ground - 8) / top); // px per metre of height
    strip.setAttribute("width", stripWidth);
    strip.setAttribute("height", this.heightPx);
    strip.setAttribute("viewBox", `0 0 ${stripWidth} ${this.heightPx}`);
    el("rect", { x: 0, y: 0, width: stripWidth, height: this.heightPx, class: "strip" }, strip);
    el("line", { x1: ground, x2: ground, y1: 0, y2: this.heightPx, class: "ground" }, strip);
    things.sort((a, b) => b.pose.position[0] - a.pose.position[0]);
    for (const t of things) {
      const [, hy] = halfExtents(t.geometry.shape, t.geometry.size, t.pose.yaw);
      const z = t.pose.position[2] || 0;
      const hgt = height(t.geometry.shape, t.geometry.size);
      const r = el("rect", {
        x: ground + z * scale, y: this.py(t.pose.position[1] + hy),
        width: Math.max(1, hgt * scale), height: (2 * hy) / this.mpp,
        fill: t.geometry.colour || (t.landmark ? "#d8d2c4" : "#999"), stroke: darker(t.geometry.colour),
        "fill-opacity": 0.85, "data-height-of": t.name,
      }, strip);
      const title = el("title", {}, r);
      title.textContent = `${t.name}: ${(z * 1000).toFixed(1)}–${((z + hgt) * 1000).toFixed(1)} mm above the table`;
    }
    const label = el("text", { x: ground + 2, y: 12, class: "strip-label" }, strip);
    label.textContent = "height →";
    const scaleLabel = el("text", { x: ground + 2, y: this.heightPx - 4, class: "strip-label" }, strip);
    scaleLabel.textContent = `top ${(top * 1000).toFixed(0)} mm`;
  }

  // --- pointer and keyboard ------------------------------------------------

  pointerDown(event) {
    if (event.button !== 0 || !this.options.interactive) return;
    if (document.body.dataset.pending !== "0") return; // the last release is still being placed
    const target = event.target.closest("[data-object],[data-landmark]");
    if (!target) return;
    const isObject = target.dataset.object !== undefined;
    const name = isObject ? target.dataset.object : target.dataset.landmark;
    if (!isObject && !this.options.landmarksMovable) return;
    if (isObject && !this.handlers.canPickUp(name)) {
      event.preventDefault();
      return;
    }
    const pose = isObject ? this.poses[name] : this.landmarks()[name];
    const [x, y] = this.world(event);
    this.drag = {
      name, isObject, id: event.pointerId, moved: false,
      grab: [pose.position[0] - x, pose.position[1] - y],
      start: [event.clientX, event.clientY],
      pose: { position: [...pose.position, 0].slice(0, 3), yaw: pose.yaw || 0 },
    };
    this.svg.setPointerCapture(event.pointerId);
    this.handlers.select(name);
    this.svg.querySelector(`[data-${isObject ? "object" : "landmark"}="${CSS.escape(name)}"]`)?.focus({ preventScroll: true });
    event.preventDefault();
  }

  pointerMove(event) {
    const drag = this.drag;
    if (!drag || event.pointerId !== drag.id) return;
    if (Math.hypot(event.clientX - drag.start[0], event.clientY - drag.start[1]) >= 1) drag.moved = true;
    if (!drag.moved) return;
    const [x, y] = this.world(event);
    drag.pose.position[0] = snap(x + drag.grab[0]);
    drag.pose.position[1] = snap(y + drag.grab[1]);
    this.draw(this.poses, this.options);
  }

  pointerUp(event) {
    const drag = this.drag;
    if (!drag || event.pointerId !== drag.id) return;
    this.drag = null;
    if (this.svg.hasPointerCapture(event.pointerId)) this.svg.releasePointerCapture(event.pointerId);
    if (!drag.moved) {
      this.draw(this.poses, this.options);
      return;
    }
    if (drag.isObject) {
      this.handlers.drop(drag.name, [drag.pose.position[0], drag.pose.position[1]], drag.pose.yaw);
    } else {
      this.handlers.landmarkDropped(drag.name, [drag.pose.position[0], drag.pose.position[1]], drag.pose.yaw);
    }
  }

  cancelDrag() {
    if (!this.drag) return;
    this.drag = null;
    this.draw(this.poses, this.options);
  }

  wheel(event) {
    if (!this.options.interactive) return;
    const name = this.drag ? this.drag.name : this.options.selected;
    if (!name) return;
    event.preventDefault();
    const delta = event.deltaY !== 0 ? event.deltaY : event.deltaX; // Shift+wheel may scroll sideways
    if (delta === 0) return;
    const step = (event.shiftKey ? 1 : 5) * (delta < 0 ? 1 : -1);
    this.turn(name, step);
  }

  turn(name, degrees) {
    if (this.drag && this.drag.name === name) {
      this.drag.pose.yaw = turned(this.drag.pose.yaw, degrees);
      this.draw(this.poses, this.options);
    } else {
      this.handlers.rotate(name, degrees);
    }
  }

  key(event) {
    if (!this.options.interactive) return;
    if (event.key === "Escape") {
      this.cancelDrag();
      return;
    }
    const name = thingOf(event.target) || this.options.selected;
    if (!name) return;
    const fine = event.shiftKey;
    if (event.code === "BracketRight" || event.code === "BracketLeft") {
      event.preventDefault();
      this.turn(name, (fine ? 1 : 5) * (event.code === "BracketRight" ? 1 : -1));
      return;
    }
    const moves = { ArrowLeft: [-1, 0], ArrowRight: [1, 0], ArrowUp: [0, 1], ArrowDown: [0, -1] };
    if (moves[event.key] && !this.drag) {
      event.preventDefault();
      const step = fine ? 0.001 : 0.01;
      this.handlers.nudge(name, moves[event.key][0] * step, moves[event.key][1] * step);
    }
  }
}

// The object or landmark an element of the table belongs to.
function thingOf(element) {
  const thing = element?.closest?.("[data-object],[data-landmark]");
  return thing ? thing.dataset.object ?? thing.dataset.landmark : undefined;
}

// A turn by `degrees` goes to the next multiple of |degrees| in that direction
// (so that whole-degree yaws can always be reached from a scrambled one).
export function turned(yaw, degrees) {
  const step = Math.abs(degrees);
  const units = Math.round(((yaw || 0) / step) * 1e6) / 1e6;
  const next = degrees > 0 ? Math.floor(units) + 1 : Math.ceil(units) - 1;
  return normaliseYaw(next * step);
}

export function normaliseYaw(yaw) {
  let y = ((yaw + 180) % 360 + 360) % 360 - 180;
  if (y === -180) y = 180;
  return Math.round(y * 1000) / 1000;
}
