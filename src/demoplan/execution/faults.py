"""Faults to inject into a simulated run (docs/formats.md "Run report": ``--faults``).

``--faults drop=0.2,displace=0.1`` gives each kind a probability:

- ``drop`` (per PUT_DOWN): the held object falls during transport and lands
  near where it fell, on the table or on the top of a landmark under it (a
  tray, a box);
- ``displace`` (after each action): a person moves a random standing object,
  one with nothing on it, to a random free spot;
- ``misplace`` (per PUT_DOWN): the object is released 1.5–5 cm off its target,
  on the table — within the executor's 6 cm for *misplaced*; where no clear
  spot is that near, nothing is injected;
- ``grasp`` (per GRASP): the grasp misses; the object stays where it is;
- ``block`` (after each action, at most twice a run): a new object (one the model
  never saw) appears on the target of a later PUT_DOWN.

Every injected fault leaves the world recoverable: objects land on the table
or a landmark's top, clear of the others by a gripper's reach, so each can be
grasped again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from demoplan.errors import UsageError

__all__ = ["FAULT_KINDS", "Faults", "InjectedFault", "parse_faults"]

FAULT_KINDS = ("drop", "displace", "misplace", "grasp", "block")


@dataclass(frozen=True, slots=True)
class Faults:
    """Probability of each fault kind (0 = never)."""

    drop: float = 0.0
    displace: float = 0.0
    misplace: float = 0.0
    grasp: float = 0.0
    block: float = 0.0

    def any(self) -> bool:
        return any(getattr(self, kind) > 0 for kind in FAULT_KINDS)


@dataclass(frozen=True, slots=True)
class InjectedFault:
    """A fault a simulated world injected, as it happened: its kind, the world's
    action it came with (1-based count of grasps and put-downs; a ``displace``
    or ``block`` comes after that action), the object, where the object ended
    up (None: it did not move, a missed grasp), and a sentence."""

    kind: str
    action: int
    object: str
    position: tuple[float, float, float] | None
    detail: str

    def to_json(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "action": self.action,
            "object": self.object,
            "position": None if self.position is None else [round(v, 6) for v in self.position],
            "detail": self.detail,
        }


def parse_faults(text: str | None) -> Faults:
    """``"drop=0.2,displace=0.1"`` → :class:`Faults` (a usage error names what is wrong)."""
    if not text or not text.strip():
        return Faults()
    values: dict[str, float] = {}
    for item in text.split(","):
        kind, sep, number = item.strip().partition("=")
        kind = kind.strip()
        if not sep or kind not in FAULT_KINDS:
            raise UsageError(
                f"--faults: {item.strip()!r} is not kind=probability with a kind among "
                f"{', '.join(FAULT_KINDS)}"
            )
        try:
            probability = float(number)
        except ValueError:
            probability = math.nan
        if not 0.0 <= probability <= 1.0:
            raise UsageError(f"--faults: {kind}={number.strip()}: a probability in [0, 1] expected")
        if kind in values:
            raise UsageError(f"--faults: {kind} given twice")
        values[kind] = probability
    return Faults(**values)
