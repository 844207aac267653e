"""Small directed-graph helpers shared by the constraint logic and the planner:
a cycle (:func:`find_cycle`), strongly connected components, acyclicity, and
the feedback vertex sets of the planner's bounds
(:mod:`demoplan.planning.bounds`, :mod:`demoplan.planning.tight`)."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Hashable, Iterable
from typing import TypeVar

__all__ = [
    "acyclic",
    "disjoint_cycles",
    "find_cycle",
    "minimum_feedback_set",
    "strongly_connected",
]

Node = TypeVar("Node", bound=Hashable)


def find_cycle(
    edges: Iterable[tuple[Node, Node]], order: Callable[[Node], object] = str
) -> list[Node]:
    """A cycle ``[a, b, …, a]`` of the directed graph ``edges``, or ``[]``.

    Depth-first with colours, iteratively (no recursion limit); ``order`` makes
    the answer deterministic.
    """
    after: dict[Node, list[Node]] = {}
    for a, b in edges:
        after.setdefault(a, []).append(b)
    for successors in after.values():
        successors.sort(key=order)  # type: ignore[arg-type]
    colour: dict[Node, int] = {}  # 1: on the current path, 2: finished
    for root in sorted(after, key=order):  # type: ignore[arg-type]
        if root in colour:
            continue
        path = [root]
        colour[root] = 1
        stack = [iter(after.get(root, []))]
        while stack:
            nxt = next(stack[-1], None)
            if nxt is None:
                colour[path.pop()] = 2
                stack.pop()
            elif colour.get(nxt) == 1:
                return [*path[path.index(nxt) :], nxt]
            elif nxt not in colour:
                colour[nxt] = 1
                path.append(nxt)
                stack.append(iter(after.get(nxt, [])))
    return []


def disjoint_cycles(edges: dict[int, list[int]]) -> int:
    """How many vertex-disjoint cycles a search finds in the digraph ``edges``
    (node -> successors), each cycle's nodes set aside once found: a lower
    bound on the most such cycles (any disjoint set is one)."""
    taken: set[int] = set()
    count = 0
    for root in sorted(edges):
        if root in taken:
            continue
        # Depth-first from root along untaken nodes, looking for a way back to root.
        path = [root]
        on_path = {root}
        stacks = [iter(edges.get(root, ()))]
        visited = {root}
        while stacks:
            step = next(stacks[-1], None)
            if step is None:
                stacks.pop()
                on_path.discard(path.pop())
                continue
            if step == root:
                taken |= on_path
                count += 1
                break
            if step in taken or step in visited:
                continue
            visited.add(step)
            path.append(step)
            on_path.add(step)
            stacks.append(iter(edges.get(step, ())))
    return count


def strongly_connected(edges: dict[int, list[int]]) -> list[list[int]]:
    """The strongly connected components of the digraph ``edges`` (node ->
    successors, every successor a key), by Tarjan's algorithm without recursion."""
    index: dict[int, int] = {}
    low: dict[int, int] = {}
    on_stack: set[int] = set()
    stack: list[int] = []
    components: list[list[int]] = []
    for root in edges:
        if root in index:
            continue
        work = [(root, iter(edges[root]))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, successors = work[-1]
            step = next(successors, None)
            if step is not None:
                if step not in index:
                    index[step] = low[step] = len(index)
                    stack.append(step)
                    on_stack.add(step)
                    work.append((step, iter(edges[step])))
                elif step in on_stack:
                    low[node] = min(low[node], index[step])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                components.append(component)
    return components


def minimum_feedback_set(nodes: list[int], edges: tuple[tuple[int, int], ...]) -> int:
    """The fewest nodes whose removal leaves the digraph acyclic, by trying
    sets of growing size (small components only)."""
    for size in range(1, len(nodes)):
        for removed in itertools.combinations(nodes, size):
            if acyclic(set(nodes).difference(removed), edges):
                return size
    return len(nodes) - 1


def acyclic(nodes: set[int], edges: Iterable[tuple[int, int]]) -> bool:
    """Whether the digraph on ``nodes`` (edges among them only) has no cycle."""
    successors: dict[int, list[int]] = {node: [] for node in nodes}
    waiting = dict.fromkeys(nodes, 0)
    for a, b in edges:
        if a in waiting and b in waiting:
            successors[a].append(b)
            waiting[b] += 1
    ready = [node for node, count in waiting.items() if not count]
    done = 0
    while ready:
        node = ready.pop()
        done += 1
        for nxt in successors[node]:
            waiting[nxt] -= 1
            if not waiting[nxt]:
                ready.append(nxt)
    return done == len(nodes)
