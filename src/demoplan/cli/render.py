"""Rendering for people: the tables and figures the commands print or write,
from what the library returns."""

from __future__ import annotations

import sys
from collections.abc import Collection, Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.table import Table
from rich.text import Text

from demoplan.cli.common import (
    plain_text,
    say,
    stderr,
    stdout,
    xyz_text,
)
from demoplan.wording import plural, printable

if TYPE_CHECKING:
    from demoplan.model import TaskModel
    from demoplan.scenes.plan import SceneLimitReachedError, SceneNoPlanError, ScenePlan


def fitted_table(
    title: str,
    header: Sequence[str],
    rows: Iterable[Sequence[str]],
    names: Collection[str] = (),
) -> Table:
    """A table that reads in an 80-column terminal: columns empty in every row are
    left out, the columns in ``names`` (object and state names) wrap between
    words but never cut a name (up to 24 characters), and the others fold
    where the width runs out. Cells are plain text ("[m]" is not rich markup)."""
    body = [list(row) for row in rows]
    keep = [k for k in range(len(header)) if any(row[k].strip() for row in body)]
    table = Table(title=title, title_justify="left")
    for k in keep:
        if header[k] in names:  # wrapped between words at most, never cut within one
            words = [word for row in body for word in row[k].split()] + header[k].split()
            widest = max(len(word) for word in words)
            table.add_column(plain_text(header[k]), min_width=min(widest, 24), overflow="fold")
        else:
            table.add_column(plain_text(header[k]), overflow="fold")
    for row in body:
        table.add_row(*(plain_text(row[k]) for k in keep))
    return table


def states_table(model: TaskModel, decimals: int, width: int) -> Table:
    """The states as the paper's Tables II and IV; where that is wider than
    ``width``, compact: the two reference columns in one ("Pcb / Motor":
    position / orientation, one name where they agree) and the position and
    orientation in one, so that the names still read in full."""
    from demoplan.learning.tables import STATE_HEADER, state_rows

    title = "States (as the paper's Tables II and IV)"
    names = ("State", "Object", "Relative Position", "Relative Orientation", "Relative to")
    rows = state_rows(model, decimals)
    table = fitted_table(title, STATE_HEADER, rows, names)
    if Console(width=10_000).measure(table).maximum <= width:  # its natural width
        return table
    compact = []
    for state, obj, by_position, by_orientation, position, yaw, spread, members, margin in rows:
        reference = merged_reference(by_position, by_orientation)
        value = f"{position} {yaw}°" if yaw else position
        compact.append((state, obj, reference, value, spread, members, margin))
    header = ("State", "Object", "Relative to", "Value [m, deg]", "Spread", "Members", "Margin")
    return fitted_table(title, header, compact, names)


def merged_reference(by_position: str, by_orientation: str) -> str:
    """The compact states table's one reference column: ``Pcb / Motor``
    (position / orientation), one name where they agree; where the orientation
    is words (it turns with its position's reference, ``turns with lunchbox:
    never seen turned``), ``lunchbox; turns with it: never seen turned``
    rather than the name twice, and ``sandwich; turns with lunchbox: …``
    where it turns with another."""
    from demoplan.learning.states import FOLLOWS_NOTE

    if not by_orientation or by_orientation == by_position:
        return by_position
    position = by_position or "—"
    if not by_orientation.startswith(FOLLOWS_NOTE):
        return f"{position} / {by_orientation}"
    if by_orientation.startswith(f"{FOLLOWS_NOTE}{by_position}:"):
        said = by_orientation[len(FOLLOWS_NOTE) + len(by_position) :]
        return f"{position}; {FOLLOWS_NOTE}it{said}"
    return f"{position}; {by_orientation}"


def roles_table(model: TaskModel, width: int) -> Table | None:
    """Which instance filled each role of identical objects in every demonstration
    (docs/learning.md, "Roles in tables and figures"): one row per role, one
    column per demonstration; where that is wider than ``width``, the columns
    headed by the demonstration's number alone, and where that is still too
    wide, one column listing ``1:plate-a, 2:plate-b, …`` (wrapped between
    entries). None for a model without roles."""
    from demoplan.learning.tables import role_header, role_rows

    if not model.roles:
        return None
    title = "Roles of identical objects"
    rows = role_rows(model)
    for header in (role_header(model), role_header(model, short=True)):
        table = fitted_table(title, header, rows, header)
        if Console(width=10_000).measure(table).maximum <= width:
            return table
    listed = [
        (role, kind, ", ".join(f"{k}:{name}" for k, name in enumerate(filled, 1)))
        for role, kind, *filled in rows
    ]
    return fitted_table(
        title, ("Role", "Type", "Instance per demonstration"), listed, ("Role", "Type")
    )


def print_model(model: TaskModel, decimals: int) -> None:
    from demoplan.learning.tables import (
        constraint_text,
        diagnostic_lines,
        precision_text,
        sequence_rows,
        support_lines,
        supported_constraint_text,
    )

    roles = roles_table(model, stdout.width)
    if roles is not None:
        stdout.print(roles)
    stdout.print(states_table(model, decimals, stdout.width))
    precision = precision_text(model)
    if precision is not None:
        stdout.print(precision, markup=False, highlight=False)
    for line in diagnostic_lines(model):
        stderr.print(f"warning: {line}", markup=False, highlight=False)
    stdout.print(
        fitted_table(
            "State sequences (Tables III and V)",
            ("Demonstration", "Sequence", "Goal states"),
            sequence_rows(model),
        )
    )
    stdout.print(
        f"Constraints ({len(model.constraints)}): {supported_constraint_text(model)}",
        markup=False,
        highlight=False,
        soft_wrap=True,
    )
    for line in support_lines(model):
        stdout.print(line, markup=False, highlight=False, soft_wrap=True)
    if model.teacher_constraints:
        stdout.print(
            f"Teacher constraints: {constraint_text(model.teacher_constraints)}",
            markup=False,
            highlight=False,
        )
    for index, x, y in model.violations:
        stdout.print(
            f"Demonstration {index + 1} contradicts the teacher's {x}<{y}",
            markup=False,
            highlight=False,
        )


def model_json(model: TaskModel) -> dict[str, Any]:
    from demoplan.learning.modelfile import model_to_dict

    return model_to_dict(model)


def print_scene_preview(preview: Any, decimals: int) -> None:
    table = Table(title=f"Scene {preview.source}", title_justify="left")
    for column in ("Object", "Position [m]", "Yaw", "Size [m]", "On", "Grasps (axis: in the way)"):
        table.add_column(column, overflow="fold")
    for obj in preview.objects:
        grasps = "; ".join(
            f"{g.axis:g}°: " + (", ".join(g.blocked_by) if g.blocked_by else "free")
            for g in obj.grasps
        )
        size = " × ".join(f"{v:g}" for v in obj.geometry.size)
        table.add_row(
            plain_text(obj.name),
            xyz_text(obj.position, decimals),
            f"{obj.yaw:.0f}°",
            f"{obj.geometry.shape} {size}",
            plain_text(", ".join(obj.on) or "table"),
            plain_text(grasps),
        )
    stdout.print(table)
    for landmark in preview.landmarks:
        shape = landmark.geometry
        size = (
            "" if shape is None else f", {shape.shape} " + " × ".join(f"{v:g}" for v in shape.size)
        )
        say(
            f"Landmark {landmark.name} at {xyz_text(landmark.position, decimals)}, "
            f"turned {landmark.yaw:.0f}°{size}"
        )
    where = (
        "generated near the objects (the scene lists none; plan generates its own "
        "near each goal's targets)"
        if preview.freespace_generated
        else "as the scene lists it"
    )
    spots = ", ".join(xyz_text(spot, decimals) for spot in preview.freespace) or "none"
    say(f"Free space, {where}: {plural(len(preview.freespace), 'spot')}: {spots}")
    if preview.freespace_generated and preview.table is not None:
        (x0, y0), (x1, y1) = preview.table
        kind = (
            "inferred around the objects and landmarks" if preview.table_inferred else "the scene's"
        )
        corners = xyz_text((x0, y0), decimals) + "–" + xyz_text((x1, y1), decimals)
        say(f"Table, {kind}: {corners}")
    if preview.shortage:
        say(preview.shortage[0].upper() + preview.shortage[1:])
    stuck = [o.name for o in preview.objects if not o.graspable]
    if stuck:
        say(f"Cannot be grasped where they stand: {', '.join(stuck)} (something else moves first)")


def plot_scene_plan(result: ScenePlan, path: Path) -> None:
    """The chosen plan in the scene it was made in (prepared: sizes, landmarks)."""
    from demoplan.plotting.figures import save_scene_plan
    from demoplan.plotting.output import figure_errors

    chosen = result.chosen
    label = result.model.demonstration_label(chosen.goal)
    title = f"Goal of {label}: {len(chosen.plan) // 2} moves"
    with figure_errors(path):
        save_scene_plan(
            result.scene, chosen.problem, chosen.plan, path, title, chosen.binding.roles
        )


def plot_no_plan(failure: SceneNoPlanError | SceneLimitReachedError, path: Path) -> None:
    """The prepared scene, the first candidate goal's targets and why there is no
    plan (the problems the planner was given, carried by ``failure``)."""
    from demoplan.plotting.figures import save_no_plan
    from demoplan.plotting.output import figure_errors

    with figure_errors(path):
        save_no_plan(failure, path)
    stderr.print(f"wrote {path}", markup=False, highlight=False)


def print_scene_plan(result: ScenePlan) -> None:
    model = result.model
    table = Table(title="Candidate goals", title_justify="left")
    for column in ("goal of demonstration", "actions", "moves", ""):
        table.add_column(column)
    for candidate in result.candidates:
        names = ", ".join(
            model.demonstration_number(k) for k in candidate.problem.candidate.demonstrations
        )
        length = candidate.length
        table.add_row(
            plain_text(names),
            "—" if length is None else str(length),
            "—" if length is None else str(length // 2),
            "chosen" if result.is_chosen(candidate) else plain_text(candidate.reason or ""),
        )
    stdout.print(table)
    chosen = result.chosen
    if chosen.bindings_weighed > 1:
        stdout.print(
            plain_text(
                f"Roles (of {chosen.bindings_weighed} ways to fill them): "
                + chosen.binding.describe()
            )
        )
    sys.stdout.flush()
    for action in chosen.plan.actions:
        sys.stdout.write(printable(f"{action}") + "\n")
    sys.stdout.flush()
    used = dict.fromkeys(a.location for a in chosen.plan.actions)
    locations = Table(title="Locations used", title_justify="left")
    for column in ("location", "x", "y", "z", "yaw", "is"):
        locations.add_column(column, justify="right" if column in "xyz yaw" else "left")
    for name in used:
        loc = chosen.problem.location(name)
        what = loc.kind if not loc.objects else f"{loc.kind} of {', '.join(loc.objects)}"
        locations.add_row(
            name, *(f"{v:.3f}" for v in loc.position), f"{loc.yaw:.1f}", plain_text(what)
        )
    stdout.print(locations)


def print_run_report(report: Any) -> None:
    table = Table(title=f"Run ({report.world})", title_justify="left")
    for column in ("step", "action", "plan", "ok"):
        table.add_column(column)
    for executed in report.actions:
        table.add_row(
            str(executed.step),
            plain_text(str(executed.action)),
            str(executed.plan),
            "yes" if executed.ok else "NO",
        )
    stdout.print(table)
    for fault in report.injected:  # what the simulation did, beside what the executor saw
        say(f"injected at action {fault.action}: {fault.kind}: {fault.detail}")
    for failure in report.failures:
        say(f"step {failure.step}: {failure.kind}: {failure.detail}")
    judged = getattr(report, "env_success", None)  # robosuite's own check (--sim robosuite:ENV)
    if judged is not None:
        say(f"robosuite's success check: {'passed' if judged else 'FAILED'}")
    verdict = "success" if report.success else "FAILED"
    turns = getattr(report, "turn_errors", {})
    errors = ", ".join(
        f"{k} {1000 * v:.1f} mm" + (f" {turns[k]:.1f}°" if k in turns else "")
        for k, v in report.pose_errors.items()
    )
    stdout.print(
        f"{verdict}: {report.reason}; {plural(len(report.actions), 'action')} "
        f"({report.first_plan_length} planned first), {plural(report.replans, 'replan')}; "
        f"final errors: {errors}",
        markup=False,
        highlight=False,
        soft_wrap=True,
    )


def print_steps(title: str, found: Any) -> None:
    """A segmentation's steps as a table on stdout, each push it left out on stderr."""
    table = Table(title=Text(printable(title)), title_justify="left")
    for column in ("step", "object", "picked up [s]", "at rest [s]", "x [m]", "y [m]", "z [m]"):
        table.add_column(plain_text(column), justify="left" if column == "object" else "right")
    for index, move in enumerate(found.moves, 1):
        x, y, z = move.pose.position
        cells = (f"{move.start:.2f}", f"{move.end:.2f}", f"{x:.4f}", f"{y:.4f}", f"{z:.4f}")
        table.add_row(str(index), Text(printable(move.object)), *cells)
    stdout.print(table)
    for push in found.pushes:
        stderr.print(
            f"push (not a step): {printable(push.object)} slid {push.distance * 100:.1f} cm "
            f"along its support at t = {push.start:.2f}–{push.end:.2f} s without being lifted",
            markup=False,
            highlight=False,
        )
