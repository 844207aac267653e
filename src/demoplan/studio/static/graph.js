// The learned constraints as a layered graph: an edge A → B means state A
// comes before state B (the transitive reduction, as the report draws it).

const SVG = "http://www.w3.org/2000/svg";

function el(name, attributes, parent) {
  const node = document.createElementNS(SVG, name);
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, String(value));
  parent.appendChild(node);
  return node;
}

// Layer of each node: the longest path from a node with no predecessor.
function layers(nodes, edges) {
  const layer = new Map(nodes.map((n) => [n, 0]));
  for (let pass = 0; pass < nodes.length; pass += 1) {
    let changed = false;
    for (const [a, b] of edges) {
      if (layer.get(b) < layer.get(a) + 1) {
        layer.set(b, layer.get(a) + 1);
        changed = true;
      }
    }
    if (!changed) break;
  }
  return layer;
}

export function drawGraph(svg, graph, objectOf = {}) {
  svg.replaceChildren();
  const nodes = graph.nodes || [];
  const edges = (graph.edges || []).filter(([a, b]) => nodes.includes(a) && nodes.includes(b));
  const layer = layers(nodes, edges);
  const columns = new Map();
  for (const n of nodes) {
    const k = layer.get(n);
    if (!columns.has(k)) columns.set(k, []);
    columns.get(k).push(n);
  }
  const dx = 74;
  const dy = 44;
  const rows = Math.max(1, ...[...columns.values()].map((c) => c.length));
  const width = Math.max(120, columns.size * dx + 20);
  const height = rows * dy + 16;
  svg.setAttribute("width", width);
  svg.setAttribute("height", height);
  svg.setAttribute("viewBox", `0 0 ${width} ${height}`);
  const defs = el("defs", {}, svg);
  const marker = el("marker", {
    id: "arrow", viewBox: "0 0 10 10", refX: 10, refY: 5, markerWidth: 7, markerHeight: 7, orient: "auto-start-reverse",
  }, defs);
  el("path", { d: "M 0 0 L 10 5 L 0 10 z", class: "arrowhead" }, marker);
  const where = new Map();
  for (const [k, column] of columns) {
    column.forEach((n, i) => where.set(n, [30 + k * dx, 8 + dy / 2 + i * dy + ((rows - column.length) * dy) / 2]));
  }
  const radius = 15;
  for (const [a, b] of edges) {
    const [x1, y1] = where.get(a);
    const [x2, y2] = where.get(b);
    const length = Math.hypot(x2 - x1, y2 - y1) || 1;
    const ux = (x2 - x1) / length;
    const uy = (y2 - y1) / length;
    // a node the straight line would pass through (C → E through B reads as
    // C → B → E): the edge bends round it, away from it
    const crossed = nodes.filter((n) => n !== a && n !== b).map((n) => where.get(n)).find(([x, y]) => {
      const t = Math.max(0, Math.min(1, ((x - x1) * ux + (y - y1) * uy) / length));
      return Math.hypot(x1 + t * (x2 - x1) - x, y1 + t * (y2 - y1) - y) < radius + 6;
    });
    let edge;
    if (crossed) {
      const side = (crossed[0] - x1) * -uy + (crossed[1] - y1) * ux > 0 ? -1 : 1; // away from it
      const bend = 2 * (radius + 9);
      const cx = (x1 + x2) / 2 - uy * bend * side;
      const cy = (y1 + y2) / 2 + ux * bend * side;
      const from = Math.hypot(cx - x1, cy - y1);
      const to = Math.hypot(x2 - cx, y2 - cy);
      const start = [x1 + ((cx - x1) / from) * radius, y1 + ((cy - y1) / from) * radius];
      const end = [x2 - ((x2 - cx) / to) * radius, y2 - ((y2 - cy) / to) * radius];
      edge = el("path", {
        d: `M ${start[0]} ${start[1]} Q ${cx} ${cy} ${end[0]} ${end[1]}`,
        class: "edge", "marker-end": "url(#arrow)", "data-edge": `${a} ${b}`,
      }, svg);
    } else {
      edge = el("line", {
        x1: x1 + ux * radius, y1: y1 + uy * radius, x2: x2 - ux * radius, y2: y2 - uy * radius,
        class: "edge", "marker-end": "url(#arrow)", "data-edge": `${a} ${b}`,
      }, svg);
    }
    el("title", {}, edge).textContent = `${a} before ${b}`;
  }
  for (const n of nodes) {
    const [x, y] = where.get(n);
    const g = el("g", { class: "node", "data-state": n, transform: `translate(${x} ${y})` }, svg);
    el("circle", { r: radius }, g);
    el("text", { y: 4 }, g).textContent = n;
    el("title", {}, g).textContent = objectOf[n] ? `${n}: ${objectOf[n]}` : n;
  }
}
