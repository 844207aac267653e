"""PDDL export of a planning problem, for Fast Downward, pyperplan and friends.

The export is *grounded STRIPS*: one parameterless action per GRASP of an
object at a location with a grasp, and per PUT_DOWN likewise (plus one
variant per subgoal a PUT_DOWN can reach). Collision facts, stacking and
exclusion become plain preconditions on ``free_*`` / ``occupied_*`` atoms, so
the domain needs no quantifiers, conditional effects or negative
preconditions — every STRIPS planner reads it, pyperplan included. Each
action costs 1 (no ``:action-costs``), so an optimal PDDL plan has as many
actions as an optimal demoplan plan; action names map back to the paper's
``GRASP o l g`` / ``PUT_DOWN o l g``.
"""

from __future__ import annotations

import re
from pathlib import Path

from demoplan.planning.compiled import compile_problem
from demoplan.planning.problem import Action, Problem

__all__ = ["action_from_pddl", "problem_to_pddl", "save_pddl"]

_SAFE = re.compile(r"[^a-z0-9]")  # no "_": "__" separates the parts of action names


def _atom(*parts: str) -> str:
    return "-".join(_SAFE.sub("-", p.lower()) for p in parts)


def problem_to_pddl(problem: Problem) -> tuple[str, str]:
    """``(domain, problem)`` PDDL texts for ``problem``."""
    c = compile_problem(problem)
    names = _unique_names(problem)
    locations, objects, grasps = c.locations, c.objects, c.grasps
    at = {(o, loc): f"at_{names[o]}_{names[loc]}" for o in objects for loc in locations}
    free = {loc: f"free_{names[loc]}" for loc in locations}
    occupied = {loc: f"occupied_{names[loc]}" for loc in locations}
    holding = {(o, g): f"holding_{names[o]}_{names[g]}" for o in objects for g in grasps}
    reached = {s.id: f"reached_{names['#' + s.id]}" for s in problem.subgoals}
    pending = {s.id: f"pending_{names['#' + s.id]}" for s in problem.subgoals}

    def mask(bits: int) -> list[str]:
        return [locations[i] for i in range(len(locations)) if bits >> i & 1]

    actions: list[str] = []
    for oi, o in enumerate(objects):
        for gi in c.grasps_of[oi]:
            g = grasps[gi]
            for li, loc in enumerate(locations):
                pre = ["handempty", at[(o, loc)]]
                pre += [free[b] for b in mask(c.block[li][gi] | c.above[li])]
                actions.append(
                    _action(
                        f"grasp__{names[o]}__{names[loc]}__{names[g]}",
                        pre,
                        add=[holding[(o, g)], free[loc]],
                        delete=["handempty", at[(o, loc)], occupied[loc]],
                    )
                )
                pre = [holding[(o, g)], free[loc]]
                pre += [free[b] for b in mask(c.block[li][gi] | c.exclusive[li])]
                pre += [occupied[b] for b in mask(c.below[li])]
                add = ["handempty", at[(o, loc)], occupied[loc]]
                delete = [holding[(o, g)], free[loc]]
                base = f"put_down__{names[o]}__{names[loc]}__{names[g]}"
                actions.append(_action(base, pre, add, delete))
                for s in problem.subgoals:  # the same PUT_DOWN, reaching a subgoal
                    if s.object != o or s.location != loc:
                        continue
                    before = [reached[a] for a, b in sorted(problem.precedences) if b == s.id]
                    actions.append(
                        _action(
                            f"{base}__reach__{names['#' + s.id]}",
                            [*pre, pending[s.id], *before],
                            [*add, reached[s.id]],
                            [*delete, pending[s.id]],
                        )
                    )
    predicates = (
        ["handempty"]
        + list(at.values())
        + list(free.values())
        + list(occupied.values())
        + list(holding.values())
        + list(reached.values())
        + list(pending.values())
    )
    domain_name = _atom("demoplan", problem.name)
    domain = (
        f"(define (domain {domain_name})\n"
        "  (:requirements :strips)\n"
        "  (:predicates\n"
        + "".join(f"    ({p})\n" for p in predicates)
        + "  )\n"
        + "".join(actions)
        + ")\n"
    )
    start_at = dict(problem.initial)
    taken = set(start_at.values())
    init = ["handempty"]
    init += [at[(o, loc)] for o, loc in problem.initial]
    init += [occupied[loc] if loc in taken else free[loc] for loc in locations]
    start_reached = {s.id for i, s in enumerate(problem.subgoals) if c.start_reached >> i & 1}
    init += [reached[s] if s in start_reached else pending[s] for s in reached]
    goal = ["handempty", *(at[(o, loc)] for o, loc in problem.goal), *reached.values()]
    problem_text = (
        f"(define (problem {_atom(problem.name)})\n"
        f"  (:domain {domain_name})\n"
        "  (:init\n" + "".join(f"    ({fact})\n" for fact in init) + "  )\n"
        "  (:goal (and\n" + "".join(f"    ({fact})\n" for fact in goal) + "  ))\n"
        ")\n"
    )
    return domain, problem_text


def _action(name: str, pre: list[str], add: list[str], delete: list[str]) -> str:
    precondition = " ".join(f"({p})" for p in dict.fromkeys(pre))
    effect = " ".join([*(f"({a})" for a in add), *(f"(not ({d}))" for d in delete)])
    return (
        f"  (:action {name}\n"
        "    :parameters ()\n"
        f"    :precondition (and {precondition})\n"
        f"    :effect (and {effect}))\n"
    )


def _unique_names(problem: Problem) -> dict[str, str]:
    """PDDL-safe, distinct names for every object, location, grasp and subgoal id."""
    names: dict[str, str] = {}
    used: set[str] = set()
    everything = [
        *problem.objects,
        *problem.locations,
        *problem.grasps,
        *("#" + s.id for s in problem.subgoals),
    ]
    for original in everything:
        base = _atom(original.lstrip("#")) or "x"
        if not base[0].isalpha():
            base = "n" + base
        name, k = base, 2
        while name in used:
            name, k = f"{base}-{k}", k + 1
        used.add(name)
        names[original] = name
    return names


def action_from_pddl(problem: Problem, name: str) -> Action:
    """The demoplan action behind a PDDL action name (as a planner prints it)."""
    reverse = {v: k for k, v in _unique_names(problem).items()}
    parts = name.strip("() ").lower().split("__")
    kind = {"grasp": "GRASP", "put_down": "PUT_DOWN"}[parts[0]]
    return Action(kind, reverse[parts[1]], reverse[parts[2]], reverse[parts[3]])


def save_pddl(problem: Problem, folder: str | Path) -> tuple[Path, Path]:
    """Write ``domain.pddl`` and ``problem.pddl`` into ``folder`` (atomically)."""
    from demoplan.fileio import write_atomic

    domain, problem_text = problem_to_pddl(problem)
    folder = Path(folder)
    paths = (folder / "domain.pddl", folder / "problem.pddl")
    write_atomic(paths[0], domain)
    write_atomic(paths[1], problem_text)
    return paths
