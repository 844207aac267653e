"""PDDL export of a planning problem, for Fast Downward, unified-planning, pyperplan.

Two forms with one meaning, that of :mod:`demoplan.planning.strips` (docs/formats.md
and the order rule of §5). Every action costs 1 (no ``:action-costs``), so an
optimal PDDL plan has as many actions as an optimal demoplan plan, and
:func:`action_from_pddl` maps a planner's action back to the paper's
``GRASP o l g`` / ``PUT_DOWN o l g``.

**Lifted** (the default): a typed domain (``item``, ``location``, ``grip``,
``subgoal``) with the schemas ``grasp ?o ?l ?g``, ``put-down ?o ?l ?g`` and,
when there are subgoals, ``put-down-reaching ?o ?l ?g ?s``; the problem's
facts — allowed grasps, collisions, supports, exclusions, accepts, subgoals
and their order — are static facts in ``:init``. A rule over a *set* ("every
location that blocks grasp g at l is free") is not a ``forall``: Fast
Downward's translator makes a universal precondition an axiom, which its
optimal heuristic (LM-cut) refuses, as it refuses conditional effects. So
each set is one static fact listing it (``lifted._AllOf``), and the
precondition an existential over that listing, which a planner grounds over
the one listing there is. The disjunctions ("no such set, or ...") and the
negations are on static facts only, and the one universal effect has a
static condition: the translator evaluates them all while grounding, and
Fast Downward searches the same operators as on the grounded export (3440
for 20 objects either way) — from about 2 % of the text.

**Grounded** (``grounded=True``): plain STRIPS, one parameterless action
per GRASP of an object at a location with a grasp, and per PUT_DOWN likewise
(plus one variant per subgoal a PUT_DOWN can reach). Collision facts,
stacking and exclusion become plain preconditions on ``free`` / ``occupied``
atoms, so the domain needs no quantifiers, conditional effects or negative
preconditions — every STRIPS planner reads it, pyperplan included. Its
predicates keep their arguments — ``(located o l)``, ``(free l)``,
``(occupied l)``, ``(holding o g)``, ``(reached s)``, ``(pending s)``,
``(away o l)`` over the domain's constants — rather than being flattened into
one nullary atom per fact: Fast Downward's translator then finds the state
invariants (an object is at one place or held, a place is free or occupied)
at once, where with hundreds of nullary atoms its invariant synthesis runs
into its candidate limit (about 10 s even for three objects).

In both, the order rule of docs/planning.md is in the preconditions: the plain
PUT_DOWN at a place of one of the object's subgoals needs every subgoal there
reached; the variant that reaches a subgoal needs its predecessors (and the
object's earlier subgoals there) reached. So Fast Downward's plans, like
demoplan's, never put an object on its place before its predecessors.

**Roles** (identical objects, :class:`Roles`): the problem of
one binding of the model's roles (``plate#1``) to the scene's instances
(``plate-a``) would fix which instance goes where, so the export lets the
planner choose. Each type is a subtype of ``item`` holding its instances
and its roles; subgoals, their order and the goal name roles, and what is
moved is a role (an object not of such a type is its own role:
``(plays blue blue)``), by the instance that ``plays`` it — its grasps,
its size. First ``bind ?o ?r ?l ?n`` gives each instance in turn a role of
its type or itself (spare), and the role stands where the instance does
(``bind-reaching`` where standing there reaches a subgoal at the start, as
:mod:`demoplan.planning.strips` counts it); a grasp waits for the last
bind. The binds are in one fixed order, since any order gives the same
plans (and every order would multiply the search: 69 s against 4 s for
Fast Downward on the table for two). So an optimal plan has one bind per
instance of a type with roles, then as many moves as demoplan's shortest
plan over every binding (:func:`plan_from_pddl` reads it back). The
grounded form writes the same binds and moves out, one action per instance,
role it may fill (or itself), location and grasp: ``bind__plate-b__plate-1``,
``grasp__plate-b__loc2__grasp3__plate-1``.
"""

from demoplan.planning.pddl.export import (
    pddl_domain_path,
    problem_to_pddl,
    save_pddl,
    save_pddl_problem,
)
from demoplan.planning.pddl.plans import action_from_pddl, plan_from_pddl
from demoplan.planning.pddl.roles import Roles

__all__ = [
    "Roles",
    "action_from_pddl",
    "pddl_domain_path",
    "plan_from_pddl",
    "problem_to_pddl",
    "save_pddl",
    "save_pddl_problem",
]
