"""One numbering: a demonstration is "demonstration N (name)", N from 1, wherever a
person reads it — learn's table, plan's table and figure title, run's messages
— while JSON keeps docs/formats.md's 0-based goal."""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")


from demoplan.wording import plural
from tests.support.cli import exit_and_output as invoke
from tests.support.helpers import EXAMPLES

SCENE = EXAMPLES / "scenes" / "pyramid-fig4.json"


def test_the_chosen_demonstration_has_one_number_everywhere(tmp_path: Path) -> None:
    """Experiment 2 (--paper: Table IV) chooses the second demonstration's goal,
    pyramid-2: learn lists it as 2, plan's table marks row 2 chosen and titles
    the figure with it, run reports reaching it; --json says goal 1 (0-based)."""
    model = tmp_path / "blocks.json"
    code, out, err = invoke("learn", EXAMPLES / "blocks", "--paper", "-o", model)
    assert code == 0, err
    assert "Demonstration 2 (pyramid-2)" in out
    # --timeout inf: which goal is chosen rests on the shortest lengths (8 against
    # 10), which must not race the default 2 s on a loaded machine
    code, out, err = invoke("plan", model, SCENE, "--timeout", "inf")
    assert code == 0, err
    rows = {
        cells[1].strip(): cells[-2].strip()
        for line in out.splitlines()
        if line.startswith("│ ") and len(cells := line.split("│")) > 4
    }
    assert rows["2 (pyramid-2)"] == "chosen" and rows["1 (pyramid-1)"] == ""
    code, out, _ = invoke("plan", model, SCENE, "--json", "--timeout", "inf")
    assert json.loads(out)["goal"] == 1
    code, out, err = invoke("run", model, SCENE, "--timeout", "inf")  # the same choice
    assert code == 0, err
    assert "success: goal of demonstration 2 (pyramid-2) reached" in out
    assert "demonstration 1 " not in out


def test_the_plan_figure_is_titled_with_the_same_number(tmp_path: Path) -> None:
    import matplotlib.pyplot as plt

    from demoplan.documents.demonstrations import load_demonstrations
    from demoplan.learning import learn
    from demoplan.learning.settings import PAPER_SETTINGS

    model = learn(load_demonstrations([EXAMPLES / "blocks"]), settings=PAPER_SETTINGS)
    assert model.demonstration_label(1) == "demonstration 2 (pyramid-2)"
    path = tmp_path / "plan.png"
    captured: list[str] = []
    original = plt.Axes.set_title

    def spy(self: plt.Axes, label: str, *args: object, **kwargs: object) -> object:
        captured.append(label)
        return original(self, label, *args, **kwargs)

    plt.Axes.set_title = spy  # type: ignore[method-assign]
    try:
        model_path = tmp_path / "m.json"
        invoke("learn", EXAMPLES / "blocks", "--paper", "-o", model_path)
        code, _, err = invoke("plan", model_path, SCENE, "--plot", path)
    finally:
        plt.Axes.set_title = original  # type: ignore[method-assign]
    assert code == 0, err
    assert path.exists()
    assert "Goal of demonstration 2 (pyramid-2): 4 moves" in captured


def test_counted_nouns() -> None:
    assert [plural(n, "replan") for n in (0, 1, 2)] == ["0 replans", "1 replan", "2 replans"]
    assert plural(1, "demonstration") == "1 demonstration"
