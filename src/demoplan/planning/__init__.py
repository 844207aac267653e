"""Task planning (paper §IV.C): problems, the paper's XML, search, PDDL export."""

from demoplan.planning.problem import Action, Plan, Problem, Subgoal, format_plan
from demoplan.planning.search import SEARCHES, Budget, solve

__all__ = ["SEARCHES", "Action", "Budget", "Plan", "Problem", "Subgoal", "format_plan", "solve"]
