"""Object names read from files are drawn as written in every figure: a name
holding matplotlib's TeX markup (``$\\sqrt{x$``) neither fails a plot, the
frames of a run and its storyboard, nor turns into mathematics."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from demoplan.learning.modelfile import save_model
from tests.hostile.harness import check_clean, run
from tests.support.helpers import EXAMPLES, paper_model

pytest.importorskip("matplotlib")

NAMES = ["$\\sqrt{x$", "$x^2$", "50$-and-60$"]


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("literal")
    model = folder / "model.json"
    save_model(paper_model("set_table"), model)
    scene = json.loads((EXAMPLES / "scenes" / "set-table-cluttered.json").read_text())
    for index, name in enumerate(NAMES):
        scene["objects"][name] = {"position": [0.05 + 0.08 * index, 0.05, 0.0], "size": [0.04] * 3}
    path = folder / "scene.json"
    path.write_text(json.dumps(scene))
    return model, path


@pytest.mark.parametrize(
    ("command", "made"),
    [
        (["plan", "{model}", "{scene}", "--clutter", "--plot", "{out}/plan.png"], ["plan.png"]),
        (["show", "{scene}", "--model", "{model}", "--plot", "{out}/show.png"], ["show.png"]),
        (
            ["run", "{model}", "{scene}", "--clutter", "--frames", "{out}/frames"],
            ["frames/storyboard.png", "frames/frame-0000.png"],
        ),
    ],
)
def test_a_name_with_tex_markup_is_drawn_as_written(
    inputs: tuple[Path, Path], tmp_path: Path, command: list[str], made: list[str]
) -> None:
    model, scene = inputs
    args = [a.format(model=model, scene=scene, out=tmp_path) for a in command]
    done = run(args, tmp_path)
    check_clean(done)
    assert done.code == 0, done
    for name in made:
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_text_of_a_figure_is_kept_as_written_and_tick_labels_keep_their_notation() -> None:
    """The figure's own text objects hold the name, not parsed (and not measured
    as TeX: measuring ``$\\sqrt{x$`` raises), while a log axis keeps its
    ``$10^{2}$`` tick labels as mathematics."""
    from demoplan.plotting.backend import tight_layout, use_agg

    use_agg()
    import matplotlib.pyplot as plt

    figure, ax = plt.subplots()
    try:
        ax.set_yscale("log")
        ax.set_ylim(0.1, 1000)
        text = ax.set_title(NAMES[0])
        tight_layout(figure)  # measures every text: raised ValueError before
        assert text.get_text() == NAMES[0] and not text.get_parse_math()
        assert all(label.get_parse_math() for label in ax.get_yticklabels())
    finally:
        plt.close(figure)
