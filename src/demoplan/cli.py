"""The ``demoplan`` command line (SPEC §4).

Commands only parse options, call the library and render what it returns with
rich. ``--json`` output goes to stdout and nothing else does; a domain error
becomes one line on stderr and the exit code of SPEC §4.
"""

from __future__ import annotations

import json
import logging
import re
import sys
from collections.abc import Collection, Iterable, Iterator, Sequence
from contextlib import contextmanager, nullcontext, suppress
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.console import Console
from rich.table import Table
from rich.text import Text

from demoplan import __version__
from demoplan.deadline import LEARNING_TIMEOUT, PERCEPTION_TIMEOUT
from demoplan.errors import (
    DemoplanError,
    InputError,
    LimitReachedError,
    NoPlanError,
    UsageError,
    error_line,
)
from demoplan.fileio import (
    display_path,
    os_error,
    os_reason,
    refuse_overwriting_inputs,
)
from demoplan.wording import plural

if TYPE_CHECKING:
    from demoplan.model import TaskModel

app = typer.Typer(
    name="demoplan",
    help="Learn pick-and-place task models from human demonstrations and plan them in new scenes.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)

_stdout = Console(soft_wrap=False, emoji=False, width=None if sys.stdout.isatty() else 140)
_stderr = Console(stderr=True, soft_wrap=True, emoji=False)

REPORT_FILES = re.compile(r"report\.(md|html)$|summary\.json$|experiment\d")
"""Names ``experiments`` writes: a folder of only these is an earlier report."""
FRAME_FILES = re.compile(r"frame-\d+\.png$|storyboard\.png$")
"""Names ``run --frames`` writes: a folder of only these holds an earlier run's frames."""


@contextmanager
def _reported_errors() -> Iterator[None]:
    """Turn a demoplan error into one line on stderr and its exit code."""
    try:
        yield
    except DemoplanError as exc:
        _stderr.print(error_line(exc), markup=False, highlight=False)
        raise typer.Exit(exc.exit_code) from None
    except OSError as exc:  # a file system refusal no reader foresaw: still one line
        if exc.filename is None:  # printing failed: stdout full, or its reader gone
            raise  # demoplan.launcher.main names standard output
        sys.stderr.write(error_line(os_error(exc)) + "\n")
        raise typer.Exit(1) from None
    except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM: exit 130 / 143 (SPEC §4)
        from demoplan.interrupts import interrupted_by_signal, interrupted_exit_code

        if interrupted_by_signal():
            raise  # demoplan.launcher.main reports it, once
        sys.stderr.write("demoplan: interrupted\n")
        raise typer.Exit(interrupted_exit_code(exc)) from None


@contextmanager
def _working(text: str) -> Iterator[None]:
    """A progress bar on stderr while long work runs (learning: objects done;
    perception: colour regions done), on a terminal only; it goes when done."""
    if not _stderr.is_terminal:
        yield
        return
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

    from demoplan.deadline import reporting_progress

    with Progress(
        TextColumn(text),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[what]}"),
        console=_stderr,
        transient=True,
    ) as bar:
        task = bar.add_task(text, total=None, what="")

        def update(what: str, done: int, total: int) -> None:
            bar.update(task, completed=done, total=total, what=what)

        with reporting_progress(update):
            yield


@contextmanager
def _model_named(path: Path) -> Iterator[None]:
    """A fault in the model found only while planning (a cycle of references)
    names the model file, not "task model"."""
    try:
        yield
    except InputError as exc:
        if exc.source != "task model":
            raise
        raise InputError(exc.message, source=str(path), field=exc.field) from None


def _version(value: bool) -> None:
    if value:
        _stdout.print(f"demoplan {__version__}", markup=False)
        raise typer.Exit()


@app.callback()
def _main(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Print the version.")
    ] = False,
    verbose: Annotated[
        bool, typer.Option("--verbose", "-v", help="Log progress to stderr.")
    ] = False,
) -> None:
    from demoplan.commands import mark_command_start

    mark_command_start()
    logging.basicConfig(
        level=logging.INFO if verbose else logging.WARNING,
        format="demoplan: %(levelname)s: %(message)s",
        stream=sys.stderr,
        force=True,
    )
    # Warnings of the libraries (NumPy overflow, shapely, MuJoCo) never reach the
    # terminal as raw text: bad numbers are refused with our one-line errors
    # before they get that far, and what is left is harmless; --verbose logs them.
    logging.captureWarnings(True)
    logging.getLogger("py.warnings").setLevel(logging.INFO if verbose else logging.CRITICAL)


def _print_json(data: Any) -> None:
    sys.stdout.write(json.dumps(data, indent=2, ensure_ascii=False, allow_nan=False) + "\n")


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
            table.add_column(Text(header[k]), min_width=min(widest, 24), overflow="fold")
        else:
            table.add_column(Text(header[k]), overflow="fold")
    for row in body:
        table.add_row(*(Text(row[k]) for k in keep))
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
        if by_orientation and by_orientation != by_position:
            reference = f"{by_position or '—'} / {by_orientation}"
        else:
            reference = by_position
        value = f"{position} {yaw}°" if yaw else position
        compact.append((state, obj, reference, value, spread, members, margin))
    header = ("State", "Object", "Relative to", "Value [m, deg]", "Spread", "Members", "Margin")
    return fitted_table(title, header, compact, names)


def _print_model(model: TaskModel, decimals: int) -> None:
    from demoplan.learning.tables import (
        constraint_text,
        diagnostic_lines,
        precision_text,
        sequence_rows,
    )

    _stdout.print(states_table(model, decimals, _stdout.width))
    precision = precision_text(model)
    if precision is not None:
        _stdout.print(precision, markup=False, highlight=False)
    for line in diagnostic_lines(model):
        _stderr.print(f"warning: {line}", markup=False, highlight=False)
    _stdout.print(
        fitted_table(
            "State sequences (Tables III and V)",
            ("Demonstration", "Sequence", "Goal states"),
            sequence_rows(model),
        )
    )
    _stdout.print(
        f"Constraints ({len(model.constraints)}): {constraint_text(model.constraints)}",
        markup=False,
        highlight=False,
        soft_wrap=True,
    )
    if model.teacher_constraints:
        _stdout.print(
            f"Teacher constraints: {constraint_text(model.teacher_constraints)}",
            markup=False,
            highlight=False,
        )
    for index, x, y in model.violations:
        _stdout.print(
            f"Demonstration {index + 1} contradicts the teacher's {x}<{y}",
            markup=False,
            highlight=False,
        )


_FRAME_OPTION = typer.Option(
    help="ROS 2 bags: the world frame TF frames are composed to (default: the TF tree's root).",
    show_default=False,
)
_OBJECTS_OPTION = typer.Option(
    help="The objects to keep: names or glob patterns, comma-separated ('cup,plate', "
    "'obj_*'). Default: every object; in a TF tree, every frame without children.",
    show_default=False,
)


@app.command()
def learn(
    demos: Annotated[
        list[Path],
        typer.Argument(
            metavar="DEMO",
            help="Demonstration files or folders, or pose streams (CSV, ROS 2 bags) to "
            "segment first (with --update: the new ones).",
            show_default=False,
        ),
    ],
    output: Annotated[
        Path | None,
        typer.Option(
            "--output",
            "-o",
            help="Model file to write (with --json, optional).",
            show_default=False,
        ),
    ] = None,
    update: Annotated[
        Path | None,
        typer.Option(
            help="Existing model to extend with DEMOS (written back unless -o).", show_default=False
        ),
    ] = None,
    require: Annotated[
        list[str] | None,
        typer.Option(
            help="Teacher constraint 'A<B' (state ids or object names); repeatable.",
            show_default=False,
        ),
    ] = None,
    require_file: Annotated[
        Path | None,
        typer.Option(help="File of teacher constraints, one 'A<B' per line.", show_default=False),
    ] = None,
    position_noise: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            help="Placement precision (RMS) in m: spreads closer than this are ties "
            "(default: estimated from the demonstrations).",
            show_default=False,
        ),
    ] = None,
    orientation_noise: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            help="Orientation precision (RMS) in degrees (default: estimated).",
            show_default=False,
        ),
    ] = None,
    significance: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            max=0.999,
            help="Level of the F test a reference or a split must pass to add states "
            "(default 0.05; 0: the paper's plain comparison).",
            show_default=False,
        ),
    ] = None,
    timeout: Annotated[
        float,
        typer.Option(
            min=0.0,
            help="Seconds learning may take before it stops with exit 4 (inf: no limit).",
        ),
    ] = LEARNING_TIMEOUT,
    paper: Annotated[
        bool,
        typer.Option(
            "--paper",
            help="The paper's reading: fixed 3 mm / 0.5° ties and the plain comparison "
            "(what the shipped examples were drawn for); other options still apply.",
        ),
    ] = False,
    position_separation: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            help="Minimum distance between clusters in m (default 0.05).",
            show_default=False,
        ),
    ] = None,
    orientation_separation: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            help="Minimum angle between clusters in degrees (default 15).",
            show_default=False,
        ),
    ] = None,
    max_clusters: Annotated[
        int | None,
        typer.Option(
            min=0,
            help="Cap on clusters per object and reference (default 0: none, as the paper).",
            show_default=False,
        ),
    ] = None,
    frame: Annotated[str | None, _FRAME_OPTION] = None,
    objects: Annotated[str | None, _OBJECTS_OPTION] = None,
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the model as JSON on stdout.")
    ] = False,
    decimals: Annotated[
        int, typer.Option(min=0, max=6, help="Decimals of positions in the tables.")
    ] = 2,
) -> None:
    """Learn a task model (states, constraints, goals) from demonstrations (paper §IV.A–B)."""
    from demoplan.learning.files import learn_files
    from demoplan.segmentation.types import parse_object_patterns

    with _reported_errors():
        if update is None and output is None and not json_output:
            raise typer.BadParameter(
                "give -o MODEL (or --update MODEL, or --json to print the model only)",
                param_hint="'-o'",
            )
        options = {
            "position_noise": position_noise,
            "orientation_noise": orientation_noise,
            "position_separation": position_separation,
            "orientation_separation": orientation_separation,
            "max_clusters": max_clusters,
            "significance": significance,
        }
        result = learn_files(
            demos,
            output=output,
            update_path=update,
            require=require or (),
            require_file=require_file,
            paper=paper,
            overrides={k: v for k, v in options.items() if v is not None},
            frame=frame,
            objects=parse_object_patterns(objects),
            timeout=timeout,
            working=lambda: _working("Learning states and constraints…"),
        )
        if result.changes is not None:  # on stderr, so that --json stays pure
            for line in result.changes.lines():
                _stderr.print(f"update: {line}", markup=False, highlight=False)
        if json_output:
            _print_json(_model_json(result.model))
        else:
            _print_model(result.model, decimals)
            _stdout.print(
                f"Learned from {plural(len(result.model.demonstrations), 'demonstration')}; "
                f"wrote {result.written}",
                markup=False,
                highlight=False,
            )


def _model_json(model: TaskModel) -> dict[str, Any]:
    from demoplan.learning.modelfile import model_to_dict

    return model_to_dict(model)


@app.command()
def show(
    path: Annotated[
        Path,
        typer.Argument(
            metavar="MODEL|SCENE",
            help="A model file written by 'learn', or a scene file to look at before planning.",
        ),
    ],
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the model or the scene preview as JSON.")
    ] = False,
    decimals: Annotated[int, typer.Option(min=0, max=6, help="Decimals of positions.")] = 2,
    model_path: Annotated[
        Path | None,
        typer.Option("--model", help="A scene: take sizes the scene omits from this model."),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option(help="A scene: draw it from above into this image (PNG, SVG)."),
    ] = None,
) -> None:
    """Print a model as the paper's tables (states, sequences, constraints), or
    preview a scene: where each object stands, which grasps its neighbours
    block, the landmarks and free space (the scene's, else spots near the objects)."""
    from demoplan.fileio import check_format, read_document
    from demoplan.learning.modelfile import model_from_dict

    with _reported_errors():
        document = read_document(path)
        kind, _ = check_format(document, {"model", "scene"}, display_path(path))
        if kind == "model":
            if plot is not None or model_path is not None:
                option = "--plot" if plot is not None else "--model"
                raise InputError(f"{option} is for a scene; {path} is a model", field=option)
            model = model_from_dict(document, str(path))
            if json_output:
                _print_json(_model_json(model))
            else:
                _print_model(model, decimals)
            return
        _show_scene(path, document, json_output, decimals, model_path, plot)


def _show_scene(
    path: Path,
    document: dict[str, Any],
    json_output: bool,
    decimals: int,
    model_path: Path | None,
    plot: Path | None,
) -> None:
    from demoplan.learning.modelfile import load_model
    from demoplan.scenes.preview import preview_scene
    from demoplan.scenes.scene import complete_geometry, scene_from_document

    if plot is not None:
        from demoplan.plotting import check_figure_path

        check_figure_path(plot, "--plot")
    scene = scene_from_document(document, str(path))
    if model_path is not None:
        scene = complete_geometry(scene, load_model(model_path))
    preview = preview_scene(scene)
    if plot is not None:
        from demoplan.plotting import save_scene_targets

        with _plot_errors(plot):
            title = f"{display_path(path)}: the scene before planning"
            save_scene_targets(scene, preview.problem, "", plot, title)
        _stderr.print(f"wrote {plot}", markup=False, highlight=False)
    if json_output:
        _print_json(preview.to_json())
    else:
        _print_scene_preview(preview, decimals)


def _print_scene_preview(preview: Any, decimals: int) -> None:
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
            Text(obj.name),
            _xyz_text(obj.position, decimals),
            f"{obj.yaw:.0f}°",
            f"{obj.geometry.shape} {size}",
            Text(", ".join(obj.on) or "table"),
            Text(grasps),
        )
    _stdout.print(table)
    for name, position in preview.landmarks:
        _line(f"Landmark {name} at {_xyz_text(position, decimals)}")
    where = (
        "generated near the objects (the scene lists none; plan generates its own "
        "near each goal's targets)"
        if preview.freespace_generated
        else "as the scene lists it"
    )
    spots = ", ".join(_xyz_text(spot, decimals) for spot in preview.freespace) or "none"
    _line(f"Free space, {where}: {plural(len(preview.freespace), 'spot')}: {spots}")
    stuck = [o.name for o in preview.objects if not o.graspable]
    if stuck:
        _line(
            f"Cannot be grasped where they stand: {', '.join(stuck)} (something else moves first)"
        )


def _line(text: str) -> None:
    """A message on stdout: plain text, one line however long (scripts read it)."""
    _stdout.print(text, markup=False, highlight=False, soft_wrap=True)


def _xyz_text(position: Any, decimals: int) -> str:
    return "(" + ", ".join(f"{v:.{decimals}f}" for v in position) + ")"


class SearchName(StrEnum):
    """Search strategies of ``demoplan solve`` (demoplan.planning.search.SEARCHES)."""

    astar = "astar"
    bfs = "bfs"


@app.command()
def solve(
    problem_path: Annotated[
        Path, typer.Argument(metavar="PROBLEM.xml", help="A problem in the paper's XML format.")
    ],
    json_output: Annotated[bool, typer.Option("--json", help="Print the plan as JSON.")] = False,
    search: Annotated[
        SearchName,
        typer.Option(
            help="astar (default: a fast plan, then A* to prove it) or bfs (the paper's)."
        ),
    ] = SearchName.astar,
    max_nodes: Annotated[
        int | None, typer.Option(min=1, help="A* / BFS expand at most this many states.")
    ] = None,
    timeout: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            help="Seconds for the whole command [default: 2]; the best plan found by then is "
            "printed, with its proven lower bound if not proved shortest ('inf': no limit).",
        ),
    ] = None,
    optimal: Annotated[
        bool,
        typer.Option("--optimal", help="Only a plan proved shortest; exit 4 without one."),
    ] = False,
) -> None:
    """Solve a planning problem: a GRASP / PUT_DOWN plan (paper §IV.C), shortest where
    proved within the time budget. stderr says which, and the proven lower bound."""
    from demoplan.commands import SolveOptions, solve_text

    with _reported_errors():
        options = SolveOptions(problem_path, json_output, search.value, max_nodes, timeout, optimal)
        # a spinner while a long search runs on a terminal; nothing when piped
        spinner = _stderr.status if _stderr.is_terminal else None
        text, note = solve_text(options, spinner)
        sys.stdout.write(text)
        sys.stderr.write(note)


GroundedOption = Annotated[
    bool,
    typer.Option(
        "--grounded",
        help="Write grounded STRIPS (one action per grasp and put-down) for pyperplan and "
        "planners without quantifiers.",
    ),
]


@app.command()
def pddl(
    problem_path: Annotated[
        Path, typer.Argument(metavar="PROBLEM.xml", help="A problem in the paper's XML format.")
    ],
    output: Annotated[
        Path, typer.Option("--output", "-o", help="Folder for domain.pddl and problem.pddl.")
    ],
    grounded: GroundedOption = False,
) -> None:
    """Export a problem as PDDL: a lifted domain and problem (--grounded: plain STRIPS)."""
    from demoplan.planning.pddl import save_pddl
    from demoplan.planning.xml import load_problem

    with _reported_errors():
        for name in ("domain.pddl", "problem.pddl"):  # the files save_pddl writes
            refuse_overwriting_inputs(output / name, [problem_path])
        domain, problem = save_pddl(load_problem(problem_path), output, grounded=grounded)
        _stderr.print(f"wrote {domain} and {problem}", markup=False, highlight=False)


def _scene_inputs(model_path: Path, scene_path: Path) -> tuple[Any, Any]:
    from demoplan.learning.modelfile import load_model
    from demoplan.scenes.scene import load_scene

    return load_model(model_path), load_scene(scene_path)


ModelArgument = Annotated[
    Path, typer.Argument(metavar="MODEL", help="A task model written by 'learn'.")
]
SceneArgument = Annotated[
    Path, typer.Argument(metavar="SCENE", help="The scene at run time (demoplan/scene-1).")
]
ClutterOption = Annotated[
    bool,
    typer.Option(help="Allow objects the model never saw (they get no goal; moved if in the way)."),
]
FreespaceOption = Annotated[
    int | None,
    typer.Option(
        "--freespace",
        min=0,
        max=50,
        help="Free-space spots to generate when the scene gives none (default 3).",
    ),
]


def _geometry_settings(freespace: int | None) -> Any:
    from demoplan.scenes.geometry import GeometrySettings

    return GeometrySettings() if freespace is None else GeometrySettings(n_freespace=freespace)


@app.command()
def plan(
    model_path: ModelArgument,
    scene_path: SceneArgument,
    json_output: Annotated[bool, typer.Option("--json", help="Print the plan as JSON.")] = False,
    freespace: FreespaceOption = None,
    max_nodes: Annotated[
        int | None, typer.Option(min=1, help="Per candidate: A* expands at most this many states.")
    ] = None,
    timeout: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            help="Seconds for the whole command, shared by the candidate goals [default: 2].",
        ),
    ] = None,
    optimal: Annotated[
        bool,
        typer.Option("--optimal", help="Only a plan proved shortest; exit 4 without one."),
    ] = False,
    plot: Annotated[
        Path | None, typer.Option(help="Also draw the plan from above into this image (PNG, SVG).")
    ] = None,
    clutter: ClutterOption = False,
) -> None:
    """Plan the task in a scene: every demonstrated goal, the shortest plan chosen (§IV.C)."""
    from demoplan.commands import command_budget
    from demoplan.planning.problem import optimality_line
    from demoplan.scenes.plan import plan_in_scene

    with _reported_errors(), _model_named(model_path):
        if plot is not None:
            from demoplan.plotting import check_figure_path

            check_figure_path(plot, "--plot")
        model, scene = _scene_inputs(model_path, scene_path)
        budget = command_budget(max_nodes, timeout)
        settings = _geometry_settings(freespace)
        try:
            with (
                _stderr.status("Planning every candidate goal…")
                if _stderr.is_terminal
                else (nullcontext())
            ):
                result = plan_in_scene(
                    model, scene, budget=budget, settings=settings, clutter=clutter
                )
        except (NoPlanError, LimitReachedError) as exc:
            if plot is not None:  # a picture of the targets is what is needed now
                _plot_no_plan(model, scene, settings, clutter, str(exc), plot)
            raise
        if optimal and not result.optimal:
            raise LimitReachedError(
                f"{optimality_line(result.as_plan())}; no plan proved shortest (--optimal)"
            )
        if plot is not None:
            _plot_scene_plan(model, scene, result, plot)
        if json_output:
            _print_json(result.to_json())
        else:
            _print_scene_plan(result, model)
        _stderr.print(f"demoplan: {optimality_line(result.as_plan())}", markup=False)


def _plot_scene_plan(model: TaskModel, scene: Any, result: Any, path: Path) -> None:
    from demoplan.plotting import save_scene_plan
    from demoplan.scenes.scene import complete_geometry

    chosen = result.chosen
    title = f"Goal of {model.demonstration_label(chosen.goal)}: {len(chosen.plan) // 2} moves"
    with _plot_errors(path):
        save_scene_plan(complete_geometry(scene, model), chosen.problem, chosen.plan, path, title)


@contextmanager
def _plot_errors(path: Path) -> Iterator[None]:
    """--plot's failures as one-line input errors."""
    try:
        yield
    except ImportError:
        raise InputError(
            "matplotlib is not installed; pip install 'demoplan[plot]'", field="--plot"
        ) from None
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot write the plot ({exc})", source=str(path)) from None


def _plot_no_plan(
    model: TaskModel, scene: Any, settings: Any, clutter: bool, reason: str, path: Path
) -> None:
    """The scene, the first candidate goal's targets and why there is no plan."""
    from demoplan.plotting import save_scene_targets
    from demoplan.scenes.plan import scene_problems
    from demoplan.scenes.scene import complete_geometry

    first = scene_problems(model, scene, settings, clutter=clutter)[0]
    goal = first.candidate.demonstrations[0]
    title = f"No plan; the targets of the goal of {model.demonstration_label(goal)}"
    with _plot_errors(path):
        save_scene_targets(complete_geometry(scene, model), first, reason, path, title)
    _stderr.print(f"wrote {path}", markup=False, highlight=False)


def _print_scene_plan(result: Any, model: TaskModel) -> None:
    table = Table(title="Candidate goals", title_justify="left")
    for column in ("goal of demonstration", "actions", "moves", ""):
        table.add_column(column)
    for candidate in result.candidates:
        names = ", ".join(
            model.demonstration_number(k) for k in candidate.problem.candidate.demonstrations
        )
        length = candidate.length
        chosen = candidate is result.chosen
        table.add_row(
            Text(names),
            "—" if length is None else str(length),
            "—" if length is None else str(length // 2),
            "chosen" if chosen else Text(candidate.reason or ""),
        )
    _stdout.print(table)
    sys.stdout.flush()
    chosen = result.chosen
    for action in chosen.plan.actions:
        sys.stdout.write(f"{action}\n")
    sys.stdout.flush()
    used = dict.fromkeys(a.location for a in chosen.plan.actions)
    locations = Table(title="Locations used", title_justify="left")
    for column in ("location", "x", "y", "z", "yaw", "is"):
        locations.add_column(column, justify="right" if column in "xyz yaw" else "left")
    for name in used:
        loc = chosen.problem.location(name)
        what = loc.kind if not loc.objects else f"{loc.kind} of {', '.join(loc.objects)}"
        locations.add_row(name, *(f"{v:.3f}" for v in loc.position), f"{loc.yaw:.1f}", Text(what))
    _stdout.print(locations)


@app.command()
def problem(
    model_path: ModelArgument,
    scene_path: SceneArgument,
    output: Annotated[
        Path,
        typer.Option(
            "--output", "-o", help="The problem file (XML; with --pddl the PDDL problem)."
        ),
    ],
    goal: Annotated[
        int,
        typer.Option(
            min=1,
            help="The demonstration whose goal to plan for, numbered from 1 as 'learn' and "
            "'plan' print them.",
        ),
    ] = 1,
    pddl_output: Annotated[
        bool,
        typer.Option(
            "--pddl", help="Write PDDL: the problem to FILE, the domain to FILE-domain.pddl."
        ),
    ] = False,
    freespace: FreespaceOption = None,
    grounded: GroundedOption = False,
) -> None:
    """Write the planning problem of one candidate goal (for 'solve' or a PDDL planner)."""
    from demoplan.errors import UsageError
    from demoplan.planning.pddl import pddl_domain_path, save_pddl_problem
    from demoplan.planning.xml import save_problem
    from demoplan.scenes.plan import goal_problem

    with _reported_errors(), _model_named(model_path):
        if grounded and not pddl_output:
            raise UsageError("--grounded chooses the PDDL form: it needs --pddl")
        inputs = [model_path, scene_path]
        refuse_overwriting_inputs(output, inputs)
        if pddl_output:
            refuse_overwriting_inputs(pddl_domain_path(output), inputs)
        model, scene = _scene_inputs(model_path, scene_path)
        chosen = goal_problem(model, scene, goal, _geometry_settings(freespace))
        if pddl_output:
            domain_path = save_pddl_problem(chosen.problem, output, grounded=grounded)
            _stderr.print(f"wrote {output} and {domain_path}", markup=False, highlight=False)
        else:
            save_problem(chosen.problem, output)
            _stderr.print(f"wrote {output}", markup=False, highlight=False)
        for obstacle in chosen.obstacles:
            _stderr.print(f"demoplan: warning: {obstacle}", markup=False, highlight=False)


class PerceptionName(StrEnum):
    """How ``demoplan run`` observes the world."""

    state = "state"
    camera = "camera"


class SimName(StrEnum):
    """Worlds of ``demoplan run``."""

    kinematic = "kinematic"
    mujoco = "mujoco"


@app.command()
def run(
    model_path: ModelArgument,
    scene_path: SceneArgument,
    sim: Annotated[
        SimName, typer.Option(help="kinematic (exact, fast) or mujoco (physics).")
    ] = SimName.kinematic,
    faults: Annotated[
        str | None,
        typer.Option(
            help="Faults to inject, kind=probability,...: drop, displace, misplace, grasp, block."
        ),
    ] = None,
    seed: Annotated[int, typer.Option(min=0, help="Seed of the injected faults.")] = 0,
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the run report as JSON.")
    ] = False,
    frames: Annotated[
        Path | None, typer.Option(help="Write top-view PNG frames and a storyboard here.")
    ] = None,
    max_replans: Annotated[int, typer.Option(min=0, help="Give up after this many replans.")] = 25,
    perception: Annotated[
        PerceptionName,
        typer.Option(help="state (read the simulator) or camera (perceive its top view; mujoco)."),
    ] = PerceptionName.state,
    freespace: FreespaceOption = None,
    timeout: Annotated[
        float,
        typer.Option(min=0.0, help="Seconds for each (re)planning (the best plan found by then)."),
    ] = 2.0,
    clutter: ClutterOption = False,
) -> None:
    """Execute the task in simulation: plan, act, observe, replan on failure."""
    from demoplan.execution.faults import parse_faults
    from demoplan.execution.runner import run_task
    from demoplan.fileio import staged_folder

    with _reported_errors(), _model_named(model_path):
        model, scene = _scene_inputs(model_path, scene_path)
        fault_rates = parse_faults(faults)
        live = _stderr.is_terminal and not json_output
        # The frames folder whole or not at all: built beside --frames, swapped in at the end.
        staging = (
            staged_folder(frames, lambda name: bool(FRAME_FILES.match(name)))
            if frames is not None
            else nullcontext(None)
        )
        with staging as building:
            report = run_task(
                model,
                scene,
                sim=sim.value,
                faults=fault_rates,
                seed=seed,
                frames=building,
                max_replans=max_replans,
                perception=perception.value,
                geometry=_geometry_settings(freespace),
                display=_stderr if live else None,
                planning_seconds=timeout,
                clutter=clutter,
            )
        if frames is not None and building is not None:
            report.frames[:] = [str(frames / Path(f).name) for f in report.frames]
        if json_output:
            _print_json(report.to_json())
        else:
            _print_run_report(report)
        if not report.success:
            _stderr.print(f"demoplan: error: {report.reason}", markup=False, highlight=False)
            raise typer.Exit(report.exit_code)


def _print_run_report(report: Any) -> None:
    table = Table(title=f"Run ({report.world})", title_justify="left")
    for column in ("step", "action", "plan", "ok"):
        table.add_column(column)
    for executed in report.actions:
        table.add_row(
            str(executed.step),
            Text(str(executed.action)),
            str(executed.plan),
            "yes" if executed.ok else "NO",
        )
    _stdout.print(table)
    for failure in report.failures:
        _stdout.print(
            f"step {failure.step}: {failure.kind}: {failure.detail}",
            markup=False,
            highlight=False,
            soft_wrap=True,  # one line per message, however long: it is read by scripts too
        )
    verdict = "success" if report.success else "FAILED"
    errors = ", ".join(f"{k} {1000 * v:.1f} mm" for k, v in report.pose_errors.items())
    _stdout.print(
        f"{verdict}: {report.reason}; {plural(len(report.actions), 'action')} "
        f"({report.first_plan_length} planned first), {plural(report.replans, 'replan')}; "
        f"final errors: {errors}",
        markup=False,
        highlight=False,
        soft_wrap=True,
    )


@app.command()
def perceive(
    image_path: Annotated[
        Path, typer.Argument(metavar="IMAGE", help="A top-down orthographic colour image (PNG).")
    ],
    px_per_m: Annotated[
        float, typer.Option("--px-per-m", min=1e-3, max=1e7, help="Pixels per metre.")
    ],
    origin: Annotated[
        tuple[float, float],
        typer.Option(help="World x y (m) of the image's bottom-left corner."),
    ],
    json_output: Annotated[bool, typer.Option("--json", help="Print the scene as JSON.")] = False,
    before: Annotated[
        Path | None,
        typer.Option(help="The picture before the last move: blocks it covers stand under it."),
    ] = None,
    output: Annotated[
        Path | None, typer.Option("--output", "-o", help="Also write the scene to this file.")
    ] = None,
    side: Annotated[
        float | None,
        typer.Option(
            min=1e-4, help="The blocks' side (m), when known: sizes 15 % off it are not blocks."
        ),
    ] = None,
    timeout: Annotated[
        float,
        typer.Option(
            min=0.0, help="Seconds perception may take before it stops with exit 4 (inf: none)."
        ),
    ] = PERCEPTION_TIMEOUT,
) -> None:
    """Find the blocks in a top-view image (paper §V.B: Hough transform over x, y, θ, s)."""
    from demoplan.fileio import dump_json, write_atomic
    from demoplan.perception.images import perceive_files
    from demoplan.perception.stacking import scene_document

    with _reported_errors():
        if output is not None:
            refuse_overwriting_inputs(output, [image_path, *([before] if before else [])])
        with _working("Finding blocks…"):
            blocks = perceive_files(
                image_path, px_per_m, origin, before=before, side=side, timeout=timeout
            )
        document = scene_document(blocks)
        if output is not None:
            write_atomic(output, dump_json(document))
        if json_output:
            _print_json(document)
            return
        table = Table(title=f"Blocks in {image_path.name}", title_justify="left")
        for column in ("name", "x [m]", "y [m]", "z [m]", "yaw [deg]", "side [m]"):
            table.add_column(column, justify="left" if column == "name" else "right")
        for name, b in blocks.items():
            table.add_row(
                name, f"{b.x:.4f}", f"{b.y:.4f}", f"{b.z:.3f}", f"{b.yaw:.1f}", f"{b.side:.4f}"
            )
        _stdout.print(table)


@app.command()
def segment(
    stream_path: Annotated[
        Path,
        typer.Argument(
            metavar="STREAM", help="A pose stream: CSV, or a ROS 2 bag (sqlite3, mcap)."
        ),
    ],
    output: Annotated[
        Path, typer.Option("--output", "-o", help="The demonstration file to write.")
    ],
    plot: Annotated[
        Path | None, typer.Option(help="Also draw speed over time with the moves shaded.")
    ] = None,
    name: Annotated[str | None, typer.Option(help="The demonstration's name.")] = None,
    frame: Annotated[str | None, _FRAME_OPTION] = None,
    objects: Annotated[str | None, _OBJECTS_OPTION] = None,
    objects_file: Annotated[
        Path | None,
        typer.Option(
            help="JSON/YAML file {objects: {NAME: {shape, size}}} (a demonstration's "
            "'objects'): geometry written into the demonstration.",
            show_default=False,
        ),
    ] = None,
    thresholds: Annotated[
        list[str] | None,
        typer.Option(
            "--set",
            metavar="NAME=VALUE",
            help="Change a threshold (repeatable; lengths m, times s, speeds m/s, "
            "angles degrees). Defaults: " + _segmentation_defaults() + ".",
            show_default=False,
        ),
    ] = None,
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the demonstration as JSON.")
    ] = False,
) -> None:
    """Segment a continuous pose stream into pick-and-place steps (a demonstration).

    A step is a move that lifts an object off its support and releases it at
    rest on a support (docs/segmentation.md); a push along the support is
    reported, not a step; a pause in the air is not a placement.
    """
    from demoplan.fileio import StagedOutputs, dump_json
    from demoplan.learning.demonstrations import demonstration_to_dict, load_object_geometry
    from demoplan.plotting import check_figure_path
    from demoplan.segmentation import load_stream
    from demoplan.segmentation import segment as segment_stream
    from demoplan.segmentation.types import parse_object_patterns

    with _reported_errors():
        inputs = [stream_path, *([objects_file] if objects_file is not None else [])]
        refuse_overwriting_inputs(output, inputs)
        if plot is not None:
            refuse_overwriting_inputs(plot, [*inputs, output])
            check_figure_path(plot, "--plot")
        stream = load_stream(stream_path, frame=frame, objects=parse_object_patterns(objects))
        geometry = (
            load_object_geometry(objects_file, known=stream.objects)
            if objects_file is not None
            else {}
        )
        from demoplan.segmentation.settings import settings_from_text

        found = segment_stream(stream, settings_from_text(thresholds or []), geometry=geometry)
        if objects_file is not None:
            # A demonstration's objects, when given, list every object it moves.
            without = sorted({m.object for m in found.moves} - set(geometry))
            if without:
                raise InputError(
                    f"no geometry for {', '.join(map(repr, without))}; every object "
                    "that moves needs one (a demonstration's objects list them all)",
                    source=str(objects_file),
                    field="objects",
                )
        demo = found.to_demonstration(name or stream_path.stem, objects=geometry)
        # The demonstration and the plot are written both or neither.
        with StagedOutputs() as outputs:
            text = dump_json(demonstration_to_dict(demo))
            outputs.add(output, text.encode("utf-8", "backslashreplace"))  # see write_atomic
            if plot is not None:
                outputs.add(plot, _segmentation_figure(found, plot))
        if json_output:
            _print_json(demonstration_to_dict(demo))
            return
        _print_steps(f"Steps found in {stream_path.name}", found)
        _stderr.print(
            f"{_count(len(found.moves), 'step')} ({_count(len(found.pushes), 'push')} and "
            f"{_count(len(found.nudges), 'nudge')} left out); wrote {output}",
            markup=False,
            highlight=False,
        )


def _segmentation_figure(found: Any, plot: Path) -> bytes:
    """The segmentation figure, encoded for ``plot``."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise InputError(
            "matplotlib is not installed; pip install 'demoplan[plot]'", field="--plot"
        ) from None
    from demoplan.plotting import figure_bytes
    from demoplan.segmentation import plot_segmentation

    axes = plot_segmentation(found)
    if not axes:
        raise InputError("nothing to draw (no object moved)", source=str(plot), field="--plot")
    figure: Any = axes[0].figure
    try:
        return figure_bytes(figure, plot)
    finally:
        plt.close(figure)


def _print_steps(title: str, found: Any) -> None:
    """A segmentation's steps as a table on stdout, each push it left out on stderr."""
    table = Table(title=Text(title), title_justify="left")
    for column in ("step", "object", "picked up [s]", "at rest [s]", "x [m]", "y [m]", "z [m]"):
        table.add_column(Text(column), justify="left" if column == "object" else "right")
    for index, move in enumerate(found.moves, 1):
        x, y, z = move.pose.position
        cells = (f"{move.start:.2f}", f"{move.end:.2f}", f"{x:.4f}", f"{y:.4f}", f"{z:.4f}")
        table.add_row(str(index), Text(move.object), *cells)
    _stdout.print(table)
    for push in found.pushes:
        _stderr.print(
            f"push (not a step): {push.object} slid {push.distance * 100:.1f} cm along its "
            f"support at t = {push.start:.2f}–{push.end:.2f} s without being lifted",
            markup=False,
            highlight=False,
        )


def _count(n: int, noun: str) -> str:
    plural = noun + ("es" if noun.endswith("sh") else "s")
    return f"{n} {noun if n == 1 else plural}"


def _segmentation_defaults() -> str:
    from demoplan.segmentation.settings import settings_help

    return settings_help()


def _write_all(files: list[tuple[Path, str]], folder: Path) -> None:
    """Write every file (atomically) or none: on any failure, or Ctrl-C, the files
    written so far are removed (and ``folder`` too when this call created it)."""
    from demoplan.fileio import write_atomic

    if folder.exists() and not folder.is_dir():
        raise InputError("exists and is not a folder; a folder expected", source=str(folder))
    created = not folder.exists()
    written: list[Path] = []
    try:
        folder.mkdir(parents=True, exist_ok=True)
        for path, text in files:
            write_atomic(path, text)
            written.append(path)
    except OSError as exc:
        _remove(written, folder if created else None)
        raise InputError(f"cannot write ({os_reason(exc)})", source=str(folder)) from None
    except BaseException:
        _remove(written, folder if created else None)
        raise


def _remove(files: list[Path], folder: Path | None) -> None:
    for path in files:
        path.unlink(missing_ok=True)
    if folder is not None:
        with suppress(OSError):  # not empty: someone else wrote there meanwhile
            folder.rmdir()


def _move_json(move: Any) -> dict[str, Any]:
    from demoplan.poses import pose_to_dict

    return {
        "object": move.object,
        "start": round(move.start, 4),
        "end": round(move.end, 4),
        **pose_to_dict(move.pose),
    }


@app.command("import")
def import_(
    recording: Annotated[
        Path,
        typer.Argument(
            metavar="RECORDING", help="A robosuite (0.3, 1.x) or robomimic HDF5 recording."
        ),
    ],
    output: Annotated[
        Path,
        typer.Option(
            "--output", "-o", help="Folder for the demonstration files (created if missing)."
        ),
    ],
    json_output: Annotated[
        bool, typer.Option("--json", help="Print a summary as JSON on stdout.")
    ] = False,
    name_prefix: Annotated[
        str | None,
        typer.Option(
            help="Names are PREFIX-<demo key> (default: the file's stem, or the environment "
            "for robosuite's demo.hdf5).",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Import a robot-learning recording: one demonstration file per demonstration in it."""
    from demoplan.fileio import dump_json
    from demoplan.learning.demonstrations import demonstration_to_dict
    from demoplan.segmentation.importing import import_recording_details

    with _reported_errors():
        if name_prefix is not None and not re.fullmatch(r"[\w.+-]+", name_prefix):
            raise UsageError(f"--name-prefix {name_prefix!r}: letters, digits and . _ + - expected")
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

        with Progress(
            TextColumn("Importing {task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            console=_stderr,
            transient=True,
            disable=not _stderr.is_terminal,
        ) as bar:
            task = bar.add_task(recording.name, total=None)

            def advance(done: int, total: int, key: str) -> None:
                bar.update(task, completed=done, total=total, description=f"{recording.name} {key}")

            items = import_recording_details(
                recording, progress=advance, name_prefix=name_prefix, skip_empty=True
            )
        files: list[tuple[Path, str]] = []
        targets: dict[str, Path] = {}
        for item in items:
            if item.demonstration is None:
                continue
            target = output / f"{item.demonstration.name}.json"
            refuse_overwriting_inputs(target, [recording])
            targets[item.key] = target
            files.append((target, dump_json(demonstration_to_dict(item.demonstration))))
        if not files:
            problems = "; ".join(f"{i.key}: {i.problem}" for i in items)
            raise InputError(f"no demonstration with a step ({problems})", source=str(recording))
        _write_all(files, output)
        for item in items:
            if item.demonstration is None:
                _stderr.print(
                    f"demoplan: warning: {item.problem}; not written", markup=False, highlight=False
                )
        if json_output:
            _print_json(
                {
                    "source": str(recording),
                    "output": str(output),
                    "demonstrations": [
                        {
                            "key": item.key,
                            "name": None if item.demonstration is None else item.demonstration.name,
                            "file": str(targets[item.key]) if item.key in targets else None,
                            "samples": item.recorded.samples,
                            "objects": list(item.recorded.stream.objects),
                            "landmarks": [name for name, _ in item.recorded.landmarks],
                            "steps": [_move_json(m) for m in item.segmentation.moves],
                            "provenance": dict(item.recorded.provenance),
                            **({"problem": item.problem} if item.problem else {}),
                        }
                        for item in items
                    ],
                }
            )
            return
        for item in items:
            title = f"{item.key}: {item.recorded.samples} samples"
            if item.key in targets:
                title += f" → {targets[item.key]}"
            _print_steps(title, item.segmentation)
        _stderr.print(
            f"{len(files)} of {plural(len(items), 'demonstration')} imported, "
            f"{plural(sum(len(i.segmentation.moves) for i in items), 'step')}; wrote {output}",
            markup=False,
            highlight=False,
        )


@app.command()
def experiments(
    out: Annotated[Path, typer.Option(help="Folder for the report.")] = Path("demoplan-report"),
    open_report: Annotated[
        bool,
        typer.Option("--open", help="Open report.html in the web browser when done."),
    ] = False,
) -> None:
    """Reproduce the paper's experiments and write a report: report.md and a
    self-contained report.html (tables, figures, models)."""
    from demoplan.experiments import run_experiments
    from demoplan.fileio import staged_folder

    with _reported_errors():
        # The whole report or none of it: built beside --out, then put in its place
        # (an earlier report is replaced; a folder of anything else is refused).
        with (
            _stdout.status("Running the paper's experiments…") as status,
            staged_folder(out, lambda name: bool(REPORT_FILES.match(name))) as building,
        ):
            result = run_experiments(building, progress=lambda text: status.update(text))
        report = out / result.report.name
        table = Table(title="Paper vs. demoplan", title_justify="left")
        for column in ("Experiment", "Check", "Paper", "demoplan", "Match"):
            table.add_column(column)
        for check in result.checks:
            cells = (check.experiment, check.name, check.paper, check.ours)
            table.add_row(*map(Text, cells), "yes" if check.ok else "NO")
        _stdout.print(table)
        _stdout.print(f"Report: {report}", markup=False, highlight=False)
        if result.html is not None:
            page = out / result.html.name
            _stdout.print(f"Report page: {page}", markup=False, highlight=False)
            if open_report and not _open_in_browser(page):
                _stderr.print(
                    f"demoplan: note: no web browser to open {page} (open it by hand)",
                    markup=False,
                    highlight=False,
                )
        differing = [c for c in result.checks if not c.ok]
        if differing:
            names = ", ".join(f"{c.experiment.split(' (')[0]} {c.name}" for c in differing)
            _stderr.print(
                f"demoplan: error: {len(differing)} results differ from the paper ({names}); "
                f"see {report}",
                markup=False,
                highlight=False,
            )
            raise typer.Exit(1)


def _open_in_browser(page: Path) -> bool:
    """Open a file in the user's web browser; False where there is none."""
    import webbrowser

    try:
        return webbrowser.open(page.resolve().as_uri())
    except webbrowser.Error:
        return False


def main() -> None:
    """Run the typer application (the ``demoplan`` executable is :func:`demoplan.launcher.main`)."""
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
