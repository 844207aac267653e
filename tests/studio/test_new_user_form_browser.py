"""A newcomer's slips in **Your objects** are caught when the thing is
added, not later: a plate's mass typed in grams (120 for 0.12 kg) made a
plate of 120 kg, shown as such in the list, and only **Save objects** said
that its density could not be. Now **Add or change** refuses it, with the
mean density and the range, as the saved file's check does."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.support.helpers import EXAMPLES
from tests.support.studio_browser import Studio, chromium_browser, studio_page

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def shared_browser() -> Iterator[Any]:
    """One chromium for the module's pages (a launch is about a second of CPU);
    each test's page opens in a context of its own on a studio of its own."""
    with chromium_browser() as launched:
        yield launched


@pytest.fixture
def page(tmp_path: Path, shared_browser: Any) -> Iterator[Studio]:
    workdir = tmp_path / "work"
    workdir.mkdir()
    with studio_page(workdir, tmp_path, shared_browser) as studio:
        studio.tab.get_by_label("Template").select_option("empty")
        studio.settle()
        studio.tab.get_by_text("Your objects").click()
        yield studio


def fill(page: Studio, name: str, shape: str, size: tuple[float, float, float], mass: str) -> None:
    tab = page.tab
    tab.get_by_label("Kind").select_option("object")
    tab.get_by_label("Name", exact=True).fill(name)
    tab.get_by_label("Shape").select_option(shape)
    for field, value in zip(("Size x (cm)", "y (cm)", "z (cm)"), size, strict=True):
        tab.get_by_label(field, exact=True).fill(str(value))
    tab.get_by_label("Mass (kg)").fill(mass)
    page.button("Add or change").click()
    page.settle()


@pytest.mark.parametrize(
    ("shape", "size", "mass", "density"),
    [
        ("cylinder", (16, 16, 1.5), "120", "3.979e+05"),  # grams for kilograms
        ("box", (10, 6, 4), "1000", "4.167e+06"),
        ("sphere", (10, 10, 10), "0.0005", "0.9549"),  # lighter than air
    ],
)
def test_a_mass_no_material_has_is_refused_when_added(
    page: Studio, shape: str, size: tuple[float, float, float], mass: str, density: str
) -> None:
    fill(page, "plate", shape, size, mass)
    assert f"a mean density of {density} kg/m³" in page.alert()
    assert "between 1.2 (air) and 22600 (osmium) expected" in page.alert()
    assert page.tab.locator("#table [data-object]").count() == 0


def test_a_plate_of_a_tenth_of_a_kilogram_is_added(page: Studio) -> None:
    fill(page, "plate", "cylinder", (16, 16, 1.5), "0.1")
    assert page.alert() == ""
    assert "plate: cylinder 16 × 16 × 1.5 cm, 0.1 kg" in page.tab.locator("#things").inner_text()


@pytest.mark.parametrize(
    ("name", "said"),
    [
        ("loc3", "loc3 is a name demoplan gives locations and grasps"),
        ("grasp12", "grasp12 is a name demoplan gives locations and grasps"),
        ("freespace0", "freespace0 is a name demoplan gives locations and grasps"),
        ("cup\u202e", "without spaces or '#' expected"),
        ("cup\u00a0a", "without spaces or '#' expected"),
    ],
)
def test_a_name_a_plan_cannot_show_is_refused_when_added(
    page: Studio, name: str, said: str
) -> None:
    """``loc3`` was added to the table (the form checked spaces and '#' only),
    and refused only by **Save objects**; a bidirectional override or a
    no-break space passed the form too. The form now holds the rule every
    file is read by (docs/formats.md, "Object names")."""
    fill(page, name, "box", (4, 4, 4), "0.05")
    assert said in page.alert()
    assert page.tab.locator("#table [data-object]").count() == 0


def test_removing_a_thing_clears_what_a_refused_add_said(page: Studio) -> None:
    """A refused **Add or change** left its alert standing over the next
    actions: **Remove** said ``cup removed.`` under ``Name: … expected``."""
    fill(page, "cup", "cylinder", (7, 7, 9), "0.15")
    fill(page, "bad name", "box", (4, 4, 4), "0.05")
    assert "Name:" in page.alert()
    page.tab.get_by_role("button", name="Remove cup", exact=True).click()
    page.settle()
    assert page.alert() == ""
    assert page.tab.locator("#status").inner_text() == "cup removed."


@pytest.fixture
def taught(tmp_path: Path, shared_browser: Any) -> Iterator[Studio]:
    """A studio on a work folder holding the blocks' demonstrations and a
    model file that is broken (a newcomer's hand edit)."""
    workdir = tmp_path / "work"
    workdir.mkdir()
    shutil.copyfile(EXAMPLES / "blocks" / "demonstrations.json", workdir / "blocks.json")
    (workdir / "model.json").write_text('{"format": "demoplan/model-1", "states": "oops"}')
    with studio_page(workdir, tmp_path, shared_browser) as studio:
        yield studio


def test_a_refused_learn_or_plan_does_not_leave_its_progress_line(taught: Studio) -> None:
    """Learn into a name the work folder refuses, Plan with a broken model:
    the alert says why, and the status line no longer reads ``Learning…`` /
    ``Planning…`` under it, as if the work went on."""
    tab = taught.tab
    taught.view("2 · Learn")
    tab.get_by_label("Model file").fill("bad name.json")
    taught.button("Learn").click()
    taught.settle()
    assert "bad name.json" in taught.alert()
    assert tab.locator("#status").inner_text() == "Not learned."
    taught.view("3 · Plan")
    tab.get_by_label("Model", exact=True).select_option("model.json")
    taught.button("Plan").click()
    taught.settle()
    assert "model.json" in taught.alert()
    assert tab.locator("#status").inner_text() == "Not planned."
    taught.errors.clear()  # the refused requests' 422s in the console


def _world_box(page: Studio) -> tuple[float, float, float, float]:
    """The world rectangle the table element draws: x0, y0, x1, y1 (metres)."""
    table = page.tab.locator("#table")
    box = table.bounding_box()
    assert box is not None
    per_pixel = float(table.get_attribute("data-metres-per-pixel") or "nan")
    x0, y0 = (float(v) for v in (table.get_attribute("data-origin") or "").split())
    return x0, y0, x0 + box["width"] * per_pixel, y0 + box["height"] * per_pixel


def test_a_landmark_dragged_past_the_table_edge_stays_in_view(page: Studio) -> None:
    """A box dragged to the table's far edge (its centre 1 cm inside the
    drawn area) was put there and the drawing kept its size: the box stood
    half outside it, and in the Run view, drawn the same, out of sight.
    Objects grew the drawing; landmarks now do too."""
    tab = page.tab
    fill(page, "cup", "cylinder", (7, 7, 9), "0.15")
    tab.get_by_label("Kind").select_option("landmark")
    tab.get_by_label("Name", exact=True).fill("box")
    tab.get_by_label("Shape").select_option("box")
    for field, value in zip(("Size x (cm)", "y (cm)", "z (cm)"), (20, 12, 3), strict=True):
        tab.get_by_label(field, exact=True).fill(str(value))
    tab.get_by_label("Mass (kg)").fill("")
    page.button("Add or change").click()
    page.settle()
    assert page.alert() == ""
    x0, _, x1, y1 = _world_box(page)
    mark = tab.locator('#table [data-landmark="box"]')
    start = tuple(float(mark.get_attribute(f"data-{k}") or "nan") for k in ("x", "y"))
    target = ((x0 + x1) / 2, y1 - 0.01)
    mouse = tab.mouse
    mouse.move(*page.pixel(start[0], start[1]))
    mouse.down()
    mouse.move(*page.pixel(*target), steps=4)
    mouse.up()
    page.settle()
    assert page.alert() == ""
    placed_y = float(mark.get_attribute("data-y") or "nan")
    assert placed_y == pytest.approx(target[1], abs=2e-3)
    assert _world_box(page)[3] >= placed_y + 0.05 - 1e-6  # the margin objects get
