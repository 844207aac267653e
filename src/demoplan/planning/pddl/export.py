"""The PDDL export's entry points: the two texts of a problem, lifted or
grounded, and both written to files (both or neither)."""

from __future__ import annotations

from pathlib import Path

from demoplan.planning.pddl.grounded import (
    grounded_pddl,
    grounded_roles_pddl,
)
from demoplan.planning.pddl.lifted import (
    lifted_pddl,
)
from demoplan.planning.pddl.roles import (
    Roles,
    cast_roles,
)
from demoplan.planning.problem import Problem

__all__ = [
    "pddl_domain_path",
    "problem_to_pddl",
    "save_pddl",
    "save_pddl_problem",
]


def problem_to_pddl(
    problem: Problem, *, grounded: bool = False, roles: Roles | None = None
) -> tuple[str, str]:
    """``(domain, problem)`` PDDL texts for ``problem``: a lifted domain with the
    problem's facts in ``:init``, or with ``grounded`` the grounded STRIPS export.

    With ``roles`` (identical objects), the lifted export lets a planner bind
    the roles to the instances: ``bind`` actions first give every instance of
    a type a role (or itself: spare), then the moves are of roles; an optimal
    plan has one ``bind`` per instance of a type with roles and as many moves
    as the shortest demoplan plan over every binding; grounded, the same
    actions written out per instance and role it may fill."""
    if roles is not None and roles.kinds and grounded:
        return grounded_roles_pddl(problem, cast_roles(problem, roles))
    if grounded:
        return grounded_pddl(problem)
    return lifted_pddl(problem, roles)


def save_pddl(
    problem: Problem, folder: str | Path, *, grounded: bool = False, roles: Roles | None = None
) -> tuple[Path, Path]:
    """Write ``domain.pddl`` and ``problem.pddl`` into ``folder`` (both or neither):
    lifted, or with ``grounded`` the grounded STRIPS export (see :func:`problem_to_pddl`)."""
    from demoplan.fileio import check_output_folder

    domain, problem_text = problem_to_pddl(problem, grounded=grounded, roles=roles)
    folder = Path(folder)
    check_output_folder(folder)
    paths = (folder / "domain.pddl", folder / "problem.pddl")
    _write_both(paths, (domain, problem_text))
    return paths


def save_pddl_problem(
    problem: Problem, path: str | Path, *, grounded: bool = False, roles: Roles | None = None
) -> Path:
    """Write the PDDL problem to ``path`` and its domain beside it, to
    ``<stem>-domain.pddl`` (both or neither); returns the domain's path.
    ``roles``: identical objects, bound by the planner (:func:`problem_to_pddl`)."""
    path = Path(path)
    domain, problem_text = problem_to_pddl(problem, grounded=grounded, roles=roles)
    domain_path = pddl_domain_path(path)
    _write_both((domain_path, path), (domain, problem_text))
    return domain_path


def _write_both(paths: tuple[Path, Path], texts: tuple[str, str]) -> None:
    """The domain and the problem, written both or neither (atomically)."""
    from demoplan.fileio import StagedOutputs

    with StagedOutputs() as outputs:
        for path, text in zip(paths, texts, strict=True):
            outputs.add(path, text.encode("utf-8", "backslashreplace"))


def pddl_domain_path(problem_path: str | Path) -> Path:
    """Where :func:`save_pddl_problem` puts the domain of ``problem_path``."""
    path = Path(problem_path)
    return path.with_name(f"{path.stem}-domain.pddl")
