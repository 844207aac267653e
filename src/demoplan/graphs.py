"""Small graph helpers shared by the constraint logic and the planner."""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable
from typing import TypeVar

__all__ = ["find_cycle"]

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
