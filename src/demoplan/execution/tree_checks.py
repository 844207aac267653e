"""A behaviour tree file checked before the engine sees it (docs/limits.md
"Behaviour trees").

BehaviorTree.CPP trusts its trees: a ``SubTree`` that refers to itself recurses
until the process dies (SIGSEGV), an ``<include>`` reads any file the path
names, a ``Script`` that reads an undefined variable throws through the Python
bindings, a ``RetryUntilSuccessful`` of ``-1`` attempts loops inside one tick
where no Ctrl-C reaches it, and port values are taken as they come. So
:func:`check_tree` reads the document with the hardened XML reader and refuses,
in one line naming the node and what was expected:

- anything but ``BehaviorTree`` and ``TreeNodesModel`` under the root
  (``include`` is never followed: a tree file holds its trees itself);
- a ``SubTree`` naming a tree the file does not define, or trees that refer to
  one another in a cycle;
- node types outside :data:`NODE_TYPES` (the engine's control and decorator
  nodes, ``Script``, and the four leaves of demoplan's vocabulary);
- ``Script`` code other than ``name:='text'`` (what ``export bt`` writes) and
  the engine's scripted attributes (``_skipIf``, ``_onSuccess``, …);
- retry and repeat counts outside 1 … :data:`MAX_ATTEMPTS`;
- on the vocabulary's nodes (``IsAt``, ``Grasp``, ``PutDown``, ``MoveToFree``):
  unknown ports, input values that the engine would read as blackboard entries
  (``{…}``), and numbers outside the bounds a scene file has (positions within
  :data:`~demoplan.documents.poses.MAX_DISTANCE_M` of the origin, angles within
  :data:`~demoplan.documents.poses.MAX_ANGLE`, tolerances positive and at most
  :data:`MAX_TOLERANCE_M` / 180°).
"""

from __future__ import annotations

import math
import re
from typing import Any
from xml.etree.ElementTree import ParseError

from defusedxml.ElementTree import fromstring

from demoplan.documents.poses import MAX_ANGLE, MAX_DISTANCE_M
from demoplan.errors import InputError

__all__ = ["MAX_ATTEMPTS", "MAX_TOLERANCE_M", "NODE_TYPES", "check_tree"]

MAX_ATTEMPTS = 1000
"""The most attempts a ``RetryUntilSuccessful`` (or cycles a ``Repeat``) may
ask for: the engine loops over them inside one tick."""

MAX_TOLERANCE_M = 0.5
"""The largest position tolerance a vocabulary node may give (m)."""

VOCABULARY = {
    "IsAt": "IsAtCondition",
    "Grasp": "GraspAction",
    "PutDown": "PutDownAction",
    "MoveToFree": "MoveToFreeAction",
}
"""The ``SubTree`` IDs of demoplan's vocabulary and the leaf each holds."""

NODE_TYPES = frozenset(
    {
        # control nodes
        "Sequence",
        "SequenceWithMemory",
        "ReactiveSequence",
        "Fallback",
        "ReactiveFallback",
        "IfThenElse",
        "WhileDoElse",
        # decorators
        "Inverter",
        "ForceSuccess",
        "ForceFailure",
        "RetryUntilSuccessful",
        "Repeat",
        "KeepRunningUntilFailure",
        "RunOnce",
        # leaves
        "AlwaysSuccess",
        "AlwaysFailure",
        "Script",
        "SubTree",
        *VOCABULARY.values(),
    }
)
"""The node types a tree may use: the engine's own that end without threads or
timers, and the vocabulary's leaves."""

_COUNTS = {"RetryUntilSuccessful": "num_attempts", "Repeat": "num_cycles"}
_SCRIPT = re.compile(r"[A-Za-z_]\w*\s*:=\s*'[^'{}]*'")
_REFERENCE = re.compile(r"\{[A-Za-z_]\w*\}")
_TEXT_PORTS = ("object", "subgoal", "reference", "name")
_POSITIONS = ("x", "y", "z", "offset_x", "offset_y", "offset_z")
_ANGLES = ("yaw", "axis")
_OUTPUTS = ("failure", "failure_detail")
_PORTS = {
    "IsAt": {*_TEXT_PORTS, *_POSITIONS, "yaw", "offset_frame", "tolerance", "yaw_tolerance"}
    | {"check_yaw", *_OUTPUTS},
    "Grasp": {"object", "name", "axis", *_OUTPUTS},
    "MoveToFree": {"object", "name", "axis", "x", "y", "z", "yaw", "tolerance", *_OUTPUTS},
}
_PORTS["PutDown"] = _PORTS["IsAt"]
_CHOICES = {"check_yaw": ("true", "false"), "offset_frame": ("world", "reference")}


def check_tree(xml: str, source: str) -> None:
    """Refuse a tree document the engine could crash, hang or be misled on
    (module docstring): an InputError naming ``source``, the node and what was
    expected. A tree ``export bt`` writes always passes."""
    try:
        root = fromstring(xml)
    except (ParseError, ValueError) as exc:
        raise InputError(f"not a behaviour tree ({exc})", source=source) from None
    if root.tag != "root" or root.get("BTCPP_format") != "4":
        raise InputError(
            f'<{root.tag}>: a <root BTCPP_format="4"> document expected', source=source
        )
    trees: dict[str, Any] = {}
    for child in root:
        if child.tag == "TreeNodesModel":
            continue
        if child.tag != "BehaviorTree":
            what = "is not followed" if child.tag == "include" else "is not a tree"
            raise InputError(
                f"<{child.tag}> {what}: a tree file holds its <BehaviorTree> elements itself",
                source=source,
            )
        name = child.get("ID") or ""
        if not name or name in trees:
            raise InputError(
                f"<BehaviorTree ID={name!r}>: a unique, non-empty ID expected", source=source
            )
        trees[name] = child
    main = root.get("main_tree_to_execute") or (next(iter(trees)) if len(trees) == 1 else "")
    if main not in trees:
        raise InputError(
            f"main_tree_to_execute={main!r}: one of the file's trees expected "
            f"({', '.join(sorted(trees)) or 'none'})",
            source=source,
        )
    for name, tree in trees.items():
        for node in tree.iter():
            if node is not tree:
                _check_node(node, name, trees, source)
    _refuse_cycles(trees, source)


def _check_node(node: Any, tree: str, trees: dict[str, Any], source: str) -> None:
    where = f"<{node.tag}> in tree {tree!r}"
    if node.tag not in NODE_TYPES:
        raise InputError(
            f"{where}: an unknown node type (docs/formats.md lists the ones a tree may use)",
            source=source,
        )
    scripted = sorted(key for key in node.attrib if key.startswith("_") and key != "_description")
    if scripted:
        raise InputError(f"{where}: {scripted[0]} is not run (scripted attributes)", source=source)
    if node.tag == "Script" and not _SCRIPT.fullmatch(node.get("code", "")):
        raise InputError(
            f"{where}: code={node.get('code')!r}: only name:='text' is run", source=source
        )
    if node.tag in _COUNTS:
        port = _COUNTS[node.tag]
        text = node.get(port, "")
        if not (text.isascii() and text.isdigit() and 1 <= int(text) <= MAX_ATTEMPTS):
            raise InputError(
                f"{where}: {port}={text!r}: a whole number from 1 to {MAX_ATTEMPTS} expected",
                source=source,
            )
    if node.tag == "SubTree":
        called = node.get("ID", "")
        if called not in trees:
            raise InputError(f"{where}: ID={called!r}: a tree of this file expected", source=source)
        if called in VOCABULARY:
            _check_ports(node, f"<SubTree ID={called!r}> in tree {tree!r}", source)


def _check_ports(node: Any, where: str, source: str) -> None:
    kind = node.get("ID")
    for port, text in node.attrib.items():
        if port == "ID":
            continue
        if port not in _PORTS[kind]:
            expected = ", ".join(sorted(_PORTS[kind]))
            raise InputError(
                f"{where}: {port!r} is not a port of {kind}; expected {expected}", source=source
            )
        if port in _OUTPUTS:
            if not _REFERENCE.fullmatch(text):
                raise InputError(
                    f"{where}: {port}={text!r}: a blackboard entry {{name}} expected",
                    source=source,
                )
        elif "{" in text or "}" in text:
            raise InputError(
                f"{where}: {port}={text!r}: a literal value expected (the engine reads {{…}} "
                "as a blackboard entry)",
                source=source,
            )
        elif port in _CHOICES and text not in _CHOICES[port]:
            raise InputError(
                f"{where}: {port}={text!r}: {' or '.join(_CHOICES[port])} expected", source=source
            )
        else:
            _check_number(port, text, f"{where}: {port}={text!r}", source)


def _check_number(port: str, text: str, where: str, source: str) -> None:
    bounds = (
        (-MAX_DISTANCE_M, MAX_DISTANCE_M, f"a number of metres within {MAX_DISTANCE_M:g} m")
        if port in _POSITIONS
        else (-MAX_ANGLE, MAX_ANGLE, f"an angle within {MAX_ANGLE:g}°")
        if port in _ANGLES
        else (0.0, MAX_TOLERANCE_M, f"a tolerance above 0 and at most {MAX_TOLERANCE_M:g} m")
        if port == "tolerance"
        else (0.0, 180.0, "a tolerance above 0° and at most 180°")
        if port == "yaw_tolerance"
        else None
    )
    if bounds is None:
        return
    low, high, expected = bounds
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    positive = port in ("tolerance", "yaw_tolerance")
    if not (low <= value <= high) or (positive and value <= 0.0):
        raise InputError(f"{where}: {expected} expected", source=source)


def _refuse_cycles(trees: dict[str, Any], source: str) -> None:
    """No tree reaches itself through ``SubTree`` references (the engine would
    recurse until the process dies). Trees that call no tree left are taken
    away until none is; what stays holds a cycle, which is named."""
    calls = {
        name: {node.get("ID", "") for node in tree.iter("SubTree")} for name, tree in trees.items()
    }
    left = set(calls)
    while ends := {name for name in left if not calls[name] & left}:
        left -= ends
    if not left:
        return
    walk = [min(left)]
    while walk.count(walk[-1]) < 2:
        walk.append(min(calls[walk[-1]] & left))
    cycle = walk[walk.index(walk[-1]) :]
    raise InputError(
        f"SubTree references form a cycle ({' → '.join(cycle)}): a tree may not reach itself",
        source=source,
    )
