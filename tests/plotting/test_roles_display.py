"""Roles of identical objects in tables and figures (issue 29): which instance
filled which role, per demonstration, in `learn`/`show`'s roles table, in
`--json`, in the studio's model JSON, in the report and in the figures'
labels; and models without roles shown exactly as before.

The data: a table for two laid with identical objects whose instance names
are handed out to the seats at random (tests/support/table_for_two.py), the truth
the roles table must show.
"""

from __future__ import annotations

import json
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

import matplotlib
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

matplotlib.use("Agg")

from demoplan.documents.demonstrations import demonstration_to_dict, load_demonstrations
from demoplan.learning import learn
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.learning.tables import role_header, role_rows
from demoplan.model import Demonstration, ObjectGeometry, Pose, Step, TaskModel
from demoplan.planning.strips import validate
from demoplan.plotting.figures import save_demonstrations
from demoplan.plotting.labels import role_label
from demoplan.plotting.output import observing_saved_figures
from demoplan.scenes.prepared import prepare
from tests.support.cli import invoke
from tests.support.helpers import EXAMPLES
from tests.support.table_for_two import (
    SWAPS,
    TYPES,
    Seating,
    expected_rows,
    seating_from,
    table_for_two,
)


@pytest.fixture(scope="module")
def seatings() -> list[Seating]:
    return seating_from(SWAPS)


@pytest.fixture(scope="module")
def demos(seatings: list[Seating]) -> list[Demonstration]:
    return [table_for_two(f"dinner-{k + 1}", s, k) for k, s in enumerate(seatings)]


@pytest.fixture(scope="module")
def model(demos: list[Demonstration]) -> TaskModel:
    return learn(demos)


@pytest.fixture(scope="module")
def demo_files(demos: list[Demonstration], tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    folder = tmp_path_factory.mktemp("dinner")
    paths = []
    for demo in demos:
        path = folder / f"{demo.name}.json"
        path.write_text(json.dumps(demonstration_to_dict(demo)))
        paths.append(path)
    return paths


def table_rows(text: str, title: str) -> list[tuple[str, ...]]:
    """The body rows of the rich table printed under ``title`` (cells stripped,
    a row wrapped onto several lines joined)."""
    lines = text.splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith(title))
    rows: list[list[str]] = []
    body = False
    for line in lines[start + 1 :]:
        if line.startswith("┡"):
            body = True
        elif line.startswith("└"):
            break
        elif body and line.startswith("│"):
            cells = [cell.strip() for cell in line.strip().strip("│").split("│")]
            if rows and not cells[0]:  # a row wrapped onto this line
                rows[-1] = [f"{a} {b}".strip() for a, b in zip(rows[-1], cells, strict=True)]
            else:
                rows.append(cells)
    return [tuple(row) for row in rows]


# The roles table


@settings(max_examples=6, deadline=None)
@given(
    swaps=st.lists(
        st.fixed_dictionaries({kind: st.booleans() for kind in TYPES}), min_size=2, max_size=4
    ),
    seed=st.integers(0, 1000),
)
def test_the_roles_table_names_the_instance_each_demonstration_put_in_each_seat(
    swaps: list[dict[str, bool]], seed: int
) -> None:
    seatings = seating_from(swaps)
    demos = [table_for_two(f"d{k}", s, seed + k) for k, s in enumerate(seatings)]
    model = learn(demos)
    assert role_rows(model) == expected_rows(seatings)
    assert role_header(model) == (
        "Role",
        "Type",
        *(f"Demonstration {k}" for k in range(1, len(demos) + 1)),
    )


def test_learn_prints_the_roles_table_before_the_states(
    demo_files: list[Path], seatings: list[Seating], tmp_path: Path
) -> None:
    result = invoke("learn", *demo_files, "-o", tmp_path / "model.json")
    assert result.exit_code == 0, result.output
    title = "Roles of identical objects"
    assert table_rows(result.stdout, title) == expected_rows(seatings)
    assert result.stdout.index(title) < result.stdout.index("States (as the paper")
    states = table_rows(result.stdout, "States (as the paper")
    # the states name roles where they name objects: every role placed once per seat
    assert sorted(row[1] for row in states) == sorted(row[0] for row in expected_rows(seatings))
    shown = invoke("show", tmp_path / "model.json")  # the model file keeps the roles
    assert shown.exit_code == 0, shown.output
    assert table_rows(shown.stdout, title) == expected_rows(seatings)


def test_learn_json_carries_the_roles(demo_files: list[Path], seatings: list[Seating]) -> None:
    result = invoke("learn", *demo_files, "--json")
    assert result.exit_code == 0, result.output
    roles = json.loads(result.stdout)["roles"]
    expected = expected_rows(seatings)
    assert [(r["name"], r["type"], *r["instances"]) for r in roles] == expected


def test_a_narrow_terminal_gets_the_demonstrations_numbered_then_listed(
    model: TaskModel, seatings: list[Seating]
) -> None:
    import io

    from rich.console import Console

    from demoplan.cli.render import roles_table

    def rendered(width: int) -> str:
        console = Console(width=width, file=io.StringIO(), record=True)
        console.print(roles_table(model, width))
        return console.export_text()

    title = "Roles of identical"
    wide, numbered, listed = rendered(100), rendered(56), rendered(40)
    assert "Demonstration 1" in wide and "Demonstration 1" not in numbered
    assert table_rows(numbered, title) == expected_rows(seatings)
    for width, text in ((56, numbered), (40, listed)):
        assert max(len(line) for line in text.splitlines()) <= width
    # the listed form: "1:plate-a, 2:plate-b, …" per role, wrapped between entries
    assert table_rows(listed, title) == [
        (role, kind, ", ".join(f"{k}:{name}" for k, name in enumerate(filled, 1)))
        for role, kind, *filled in expected_rows(seatings)
    ]


def test_a_demonstration_without_an_instance_shows_a_dash(
    demos: list[Demonstration], seatings: list[Seating]
) -> None:
    """The third demonstration lays no glass at the second seat: its glass#2 is ``—``."""
    last = demos[2]
    gone = last.steps[-1].object
    assert gone == seatings[2]["glass"][1]
    short = replace(
        last,
        steps=last.steps[:-1],
        objects=tuple(o for o in last.objects if o[0] != gone),
        types=tuple(t for t in last.types if t[0] != gone),
    )
    expected = expected_rows(seatings)
    expected[-1] = (*expected[-1][:-1], "—")
    assert role_rows(learn([*demos[:2], short])) == expected


def test_a_type_with_one_instance_per_demonstration_has_one_role_named_like_it(
    tmp_path: Path,
) -> None:
    cup = ObjectGeometry("cylinder", (0.08, 0.08, 0.1))
    paths = []
    for k in (1, 2):
        steps = (
            Step(f"cup-{k}", Pose((0.3 + 0.01 * k, 0.2, 0.0))),
            Step("saucer", Pose((0.5, 0.2 + 0.01 * k, 0.0))),
        )
        objects = ((f"cup-{k}", cup), ("saucer", cup))
        demo = Demonstration(f"d{k}", steps, objects, types=((f"cup-{k}", "cup"),))
        paths.append(tmp_path / f"d{k}.json")
        paths[-1].write_text(json.dumps(demonstration_to_dict(demo)))
    result = invoke("learn", *paths, "-o", tmp_path / "model.json")
    assert result.exit_code == 0, result.output
    title = "Roles of identical objects"
    assert table_rows(result.stdout, title) == [("cup", "cup", "cup-1", "cup-2")]
    states = table_rows(result.stdout, "States (as the paper")
    assert [row[1] for row in states] == ["cup", "saucer"]


@pytest.mark.parametrize("folder", ["set_table", "blocks"])
def test_a_model_without_roles_prints_no_roles_table(folder: str, tmp_path: Path) -> None:
    result = invoke("learn", EXAMPLES / folder, "-o", tmp_path / "m.json", "--paper")
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith("States (as the paper's Tables II and IV)")
    assert "Roles" not in result.stdout and "←" not in result.stdout
    data = json.loads(invoke("learn", EXAMPLES / folder, "--json", "--paper").stdout)
    assert "roles" not in data


# Figures


def _labels(path: Path, draw: Any) -> list[list[str]]:
    """The texts of every axes of the figure ``draw`` writes to ``path``."""
    found: list[list[str]] = []

    def record(figure: Any, renderer: Any, written: Path) -> None:
        found.extend([t.get_text() for t in ax.texts if t.get_text()] for ax in figure.axes)

    with observing_saved_figures(record):
        draw()
    return found


def test_the_demonstrations_figure_names_the_instance_under_each_role(
    model: TaskModel, seatings: list[Seating], tmp_path: Path
) -> None:
    path = tmp_path / "demos.png"
    axes = _labels(path, lambda: save_demonstrations(model, path, "dinner"))
    tops = axes[0::2]  # each demonstration's top view, its constraint graph below it
    assert len(tops) == len(seatings)
    truth = {row[0]: row[2:] for row in expected_rows(seatings)}
    for k, (texts, demo) in enumerate(zip(tops, model.demonstrations, strict=True)):
        expected = [
            f"{n} {state} {step.object}\n← {truth[step.object][k]}"
            for n, (state, step) in enumerate(zip(model.sequences[k], demo.steps, strict=True), 1)
        ]
        assert [t for t in texts if t[0].isdigit()] == expected
    graphs = axes[1::2]  # the graphs name each state's role
    assert {"plate#1", "glass#2"} <= set(graphs[0])


def test_the_two_line_labels_get_room_beside_a_long_narrow_table(
    model: TaskModel, tmp_path: Path
) -> None:
    """The table for two is long and narrow (its seats one behind the other):
    the top views fill their panels, and no two labels of one overlap."""
    from tests.support.shared_experiments import text_box

    filled: list[float] = []
    overlaps: list[str] = []

    def record(figure: Any, renderer: Any, written: Path) -> None:
        for ax in figure.axes[0::2]:
            drawn, panel = ax.get_position(), ax.get_position(original=True)
            filled.append(drawn.width * drawn.height / (panel.width * panel.height))
            boxes = [(t.get_text(), text_box(t, renderer)) for t in ax.texts if t.get_text()]
            overlaps.extend(
                f"{a!r} over {b!r}"
                for i, (a, box_a) in enumerate(boxes)
                for b, box_b in boxes[i + 1 :]
                if box_a.overlaps(box_b)
            )

    path = tmp_path / "demos.png"
    with observing_saved_figures(record):
        save_demonstrations(model, path, "dinner")
    assert len(filled) == len(model.demonstrations)
    assert min(filled) > 0.95  # (at the data's own aspect: 0.29 of them)
    assert overlaps == []


@pytest.mark.parametrize("folder", ["set_table", "blocks"])
def test_figures_of_models_without_roles_keep_their_labels(folder: str, tmp_path: Path) -> None:
    model = learn(load_demonstrations([EXAMPLES / folder]), settings=PAPER_SETTINGS)
    path = tmp_path / "demos.png"
    axes = _labels(path, lambda: save_demonstrations(model, path, folder))
    for k, demo in enumerate(model.demonstrations):
        expected = [
            f"{n} {state} {step.object}"
            for n, (state, step) in enumerate(zip(model.sequences[k], demo.steps, strict=True), 1)
        ]
        assert [t for t in axes[2 * k] if t[0].isdigit()] == expected


def test_scene_figures_name_the_role_an_instance_fills(tmp_path: Path) -> None:
    """The plan (top and side view) and the no-plan figure: an instance that
    fills a role of another name is labelled ``role ← instance``, every other
    label stays as it was."""
    from demoplan.plotting.figures import save_scene_plan, save_scene_targets
    from demoplan.scenes.plan import plan_in_scene
    from demoplan.scenes.preview import preview_scene
    from demoplan.scenes.scene import load_scene

    scene = load_scene(EXAMPLES / "scenes" / "pyramid-fig4.json")
    model = learn(load_demonstrations([EXAMPLES / "blocks"]), settings=PAPER_SETTINGS)
    result = plan_in_scene(model, prepare(model, scene))
    chosen = result.chosen
    validate(chosen.problem.problem, chosen.plan.actions)
    problem = preview_scene(scene).problem
    bound = {"block#2": "green"}  # green fills a role of another name
    path = tmp_path / "figure.png"
    drawings = {
        "plan": lambda roles: save_scene_plan(
            scene, chosen.problem, chosen.plan, path, "plan", roles
        ),
        "targets": lambda roles: save_scene_targets(scene, problem, "", path, "no plan", roles),
    }
    for kind, draw in drawings.items():
        plain = _labels(path, partial(draw, None))
        roles = _labels(path, partial(draw, bound))
        assert len(plain) == len(roles) == (2 if kind == "plan" else 1)  # the plan stacks
        for before, after in zip(plain, roles, strict=True):
            assert "green" in before and "block#2 ← green" not in before
            assert [t if t != "green" else "block#2 ← green" for t in before] == after
    assert role_label("plate#1", "plate#1") == "plate#1"  # filled by its own name: no arrow


# The studio and the report


def test_the_studio_model_json_carries_roles_only_where_there_are_some(
    model: TaskModel, seatings: list[Seating]
) -> None:
    from demoplan.studio.views import model_json

    roles = model_json(model)["roles"]
    assert [(r["name"], r["type"], *r["instances"]) for r in roles] == expected_rows(seatings)
    plain = learn(load_demonstrations([EXAMPLES / "blocks"]), settings=PAPER_SETTINGS)
    assert "roles" not in model_json(plain)


def test_the_report_section_has_the_roles_table(model: TaskModel, seatings: list[Seating]) -> None:
    from demoplan.experiments.report import _learning_section
    from demoplan.experiments.runs import LearningRun

    text = _learning_section(LearningRun("Dinner", Path("dinner"), model, (), None, 0.0))
    header = "| Role | Type | " + " | ".join(f"Demonstration {k}" for k in (1, 2, 3)) + " |"
    assert header in text
    for row in expected_rows(seatings):
        assert "| " + " | ".join(row) + " |" in text


def test_the_no_plan_figures_reason_is_wrapped_within_its_width() -> None:
    """Why there is no plan stands under the title in lines as wide as the
    axes' cell, a long file path broken inside itself (it was cut at 90
    characters whatever the figure's width, and a path wider than that ran off)."""
    import matplotlib.pyplot as plt

    from demoplan.plotting.figures import plot_scene_targets
    from demoplan.plotting.labels import figure_renderer
    from demoplan.scenes.preview import preview_scene
    from demoplan.scenes.scene import load_scene

    scene = load_scene(EXAMPLES / "scenes" / "pyramid-fig4.json")
    problem = preview_scene(scene).problem
    path = "/home/user/" + "a-very-long-folder-name/" * 12 + "scene.json"
    reason = f"{path}: objects.red.position: no free space left on the table " * 3
    figure, ax = plt.subplots(figsize=(4, 4))
    plot_scene_targets(scene, problem, reason, ax, title="No plan")
    title = ax.title
    lines = title.get_text().split("\n")
    assert lines[0] == "No plan" and len(lines) > 4
    assert "".join(lines[1:]).replace(" ", "") == reason.replace(" ", "")  # every character kept
    extent = title.get_window_extent(figure_renderer(figure))  # type: ignore[arg-type]
    assert extent.width <= figure.bbox.width
    plt.close(figure)
