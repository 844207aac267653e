"""Plans read back: a PDDL planner's actions mapped to the paper's
``GRASP o l g`` / ``PUT_DOWN o l g`` (and, with roles, the binding its binds
chose)."""

from __future__ import annotations

from collections.abc import Sequence

from demoplan.planning.pddl.roles import (
    ROLE_KEY,
    Cast,
    Roles,
    cast_roles,
)
from demoplan.planning.pddl.syntax import (
    LIFTED_RESERVED,
    RESERVED,
    unique_names,
)
from demoplan.planning.problem import Action, Problem

__all__ = [
    "action_from_pddl",
    "plan_from_pddl",
]


def action_from_pddl(problem: Problem, name: str, roles: Roles | None = None) -> Action:
    """The demoplan action behind a PDDL action as a planner prints it: lifted,
    ``(grasp box loc264 grasp6)``, ``(put-down box freespace1 grasp6)`` or
    ``(put-down-reaching o l g s)``; grounded, ``(grasp__box__loc264__grasp6)``.
    With ``roles``, of the export with them: ``(grasp plate-a loc1 grasp3
    plate-1)`` is plate-a's GRASP (filling role plate#1); a ``bind`` is no
    action (ValueError; :func:`plan_from_pddl` reads whole plans)."""
    if roles is not None and roles.kinds:
        return _role_action(name, cast_roles(problem, roles))
    text = name.strip("() ").lower()
    lifted = " " in text
    names = unique_names(problem, LIFTED_RESERVED if lifted else RESERVED)
    reverse = {v: k for k, v in names[0].items()}
    if lifted:
        parts = text.split()
        kinds = {"grasp": ("GRASP", 4), "put-down": ("PUT_DOWN", 4)}
        kinds["put-down-reaching"] = ("PUT_DOWN", 5)
        valid = parts[0] in kinds and len(parts) == kinds[parts[0]][1]
        valid = valid and (len(parts) == 4 or parts[4] in names[1].values())
    else:
        parts = text.split("__")
        kinds = {"grasp": ("GRASP", 4), "put_down": ("PUT_DOWN", 4)}
        valid = parts[0] in kinds
    try:
        if not valid:
            raise KeyError(name)
        o, loc, g = (reverse[p] for p in parts[1:4])
    except (KeyError, ValueError):
        raise ValueError(f"{name!r} is not an action of this problem's PDDL export") from None
    return Action(kinds[parts[0]][0], o, loc, g)


def _role_action(name: str, cast: Cast) -> Action:
    text = name.strip("() ").lower()
    reverse = {v: k for k, v in cast.names.items() if not k.startswith(ROLE_KEY)}
    if " " in text:  # lifted: (grasp o l g r), (put-down-reaching o l g r s)
        parts = text.split()
        kinds = {"grasp": ("GRASP", 5), "put-down": ("PUT_DOWN", 5)}
        kinds["put-down-reaching"] = ("PUT_DOWN", 6)
        valid = parts[0] in kinds and len(parts) == kinds[parts[0]][1]
    else:  # grounded: grasp__o__l__g[__r], put_down__o__l__g[__r][__reach__s]
        parts = text.split("__")
        kinds = {"grasp": ("GRASP", 0), "put_down": ("PUT_DOWN", 0)}
        valid = parts[0] in kinds and 4 <= len(parts) <= 7
    if valid:
        try:
            o, loc, g = (reverse[p] for p in parts[1:4])
            return Action(kinds[parts[0]][0], o, loc, g)
        except KeyError:
            pass
    raise ValueError(f"{name!r} is not an action of this problem's PDDL export")


def plan_from_pddl(
    problem: Problem, names: Sequence[str], roles: Roles | None = None
) -> tuple[list[Action], dict[str, str]]:
    """A planner's plan of the export of ``problem`` as demoplan actions, and
    the binding its ``bind`` actions chose (role → instance; empty without
    ``roles``): the plan is demoplan's for ``roles.rebind(problem, binding)``."""
    if roles is None or not roles.kinds:
        return [action_from_pddl(problem, name) for name in names], {}
    cast = cast_roles(problem, roles)
    reverse = {v: k for k, v in cast.names.items()}
    actions: list[Action] = []
    binding: dict[str, str] = {}
    for name in names:
        text = name.strip("() ").lower()
        parts = text.split() if " " in text else text.split("__")
        if parts[:1] in (["bind"], ["bind-reaching"]) and len(parts) >= 3:
            o, r = reverse.get(parts[1], ""), reverse.get(parts[2], "")
            if o in cast.kinds and r in cast.role_kinds:
                binding[r.removeprefix(ROLE_KEY)] = o
            elif not (o in cast.kinds and r == o):
                raise ValueError(f"{name!r} is not a binding of this problem's PDDL export")
            continue
        actions.append(_role_action(name, cast))
    return actions, binding
