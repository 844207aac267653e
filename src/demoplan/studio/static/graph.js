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
    const line = el("line", {
      x1: x1 + ux * radius, y1: y1 + uy * radius, x2: x2 - ux * radius, y2: y2 - uy * radius,
      class: "edge", "marker-end": "url(#arrow)", "data-edge": `${a} ${b}`,
    }, svg);
    el("title", {}, line).textContent = `${a} before ${b}`;
  }
  for (const n of nodes) {
    const [x, y] = where.get(n);
    const g = el("g", { class: "node", "data-state": n, transform: `translate(${x} ${y})` }, svg);
    el("circle", { r: radius }, g);
    el("text", { y: 4 }, g).textContent = n;
    el("title", {}, g).textContent = objectOf[n] ? `${n}: ${objectOf[n]}` : n;
  }
}
