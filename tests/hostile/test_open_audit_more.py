"""What demoplan opens, for the commands added last: ``run --bt``,
``calibrate``, ``perceive --sequence`` and ``evaluate``, each under the
file-access monitor (``strace -f``: tests/hostile/file_audit.py) with a
"secret" beside its inputs that a careless or hostile input could lead to —
never touched, not even attempted (as tests/hostile/test_open_audit.py does
for the older commands)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from demoplan.commands.export import behaviour_tree
from demoplan.documents.demonstrations import load_demonstrations
from demoplan.learning import learn
from demoplan.learning.modelfile import save_model
from demoplan.perception.camera import Camera, save_image
from demoplan.perception.filmed import render_demonstration
from tests.hostile.file_audit import Allowed, audit_environment, audited
from tests.hostile.harness import check_clean
from tests.support.helpers import ONE_MOVE_SCENE

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
PYRAMID = EXAMPLES / "scenes" / "pyramid-fig4.json"

pytestmark = pytest.mark.slow  # commands under strace: handed out early


@pytest.fixture(scope="module")
def caches(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("library-caches")


@pytest.fixture(scope="module")
def blocks(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """Experiment 2's model (not audited) and the tree ``export bt`` writes for it."""
    folder = tmp_path_factory.mktemp("blocks")
    model = learn(load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"]))
    save_model(model, folder / "model.json")
    tree, _ = behaviour_tree(model, PYRAMID)
    return folder / "model.json", tree


def _root(tmp_path: Path) -> Path:
    (tmp_path / "work").mkdir()
    return tmp_path


@pytest.mark.parametrize("include", [False, True], ids=["the tree", "a tree including a secret"])
def test_run_bt_opens_the_tree_the_model_and_the_scene_only(
    blocks: tuple[Path, str], caches: Path, tmp_path: Path, include: bool
) -> None:
    model, tree = blocks
    root = _root(tmp_path)
    secret = root / "secret.xml"
    secret.write_text(tree)
    path = root / "task.xml"
    text = tree.replace(
        '<BehaviorTree ID="Task">', f'<include path="{secret}"/><BehaviorTree ID="Task">', 1
    )
    path.write_text(text if include else tree)
    rule = Allowed((model, PYRAMID, path), (), audit_environment(root, caches))
    audit = audited(["run", "--bt", path, model, PYRAMID], root / "work", rule, never=[secret])
    assert audit.answer.code == (1 if include else 0), audit.answer


def test_calibrate_opens_the_image_and_the_markers_only(caches: Path, tmp_path: Path) -> None:
    root = _root(tmp_path)
    image, markers = root / "view.png", root / "markers.json"
    shutil.copy(EXAMPLES / "perception" / "markers-oblique.png", image)
    shutil.copy(EXAMPLES / "perception" / "markers.json", markers)
    secret = root / "camera.json"  # a camera file beside, not named
    secret.write_text("{}")
    out, plot = root / "work" / "out.json", root / "work" / "overlay.png"
    rule = Allowed((image, markers), (out, plot), audit_environment(root, caches))
    args = ["calibrate", image, "--markers", markers, "-o", out, "--plot", plot]
    audit = audited(args, root / "work", rule, never=[secret])
    check_clean(audit.answer, max_seconds=300)
    assert audit.answer.code == 0, audit.answer and out.is_file()


def test_perceive_sequence_opens_its_frames_only(caches: Path, tmp_path: Path) -> None:
    root = _root(tmp_path)
    frames = root / "frames"
    frames.mkdir()
    demo = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])[0]
    for index, frame in enumerate(render_demonstration(demo, Camera(1000.0, (0.0, -0.15)), rng=0)):
        save_image(frame, frames / f"f{index:03d}.png")
    secret = frames / "zz-not-a-frame.png"  # beside the frames, not named
    shutil.copy(frames / "f000.png", secret)
    named = sorted(p for p in frames.iterdir() if p != secret)
    out = root / "work" / "demo.json"
    rule = Allowed(tuple(named), (out,), audit_environment(root, caches))
    args = ["perceive", "--sequence", *named, "--px-per-m", "1000", "--origin", "0", "-0.15"]
    audit = audited([*args, "--side", "0.04", "-o", out], root / "work", rule, never=[secret])
    check_clean(audit.answer, max_seconds=600)
    assert audit.answer.code == 0, audit.answer and out.is_file()


def test_evaluate_opens_its_model_scene_and_folder_only(
    blocks: tuple[Path, str], caches: Path, tmp_path: Path
) -> None:
    """Here, one run after the other (``--workers 0``): Ray's own processes
    read their installation, which is not demoplan's doing. Runs of one move:
    an evaluation opens the same files (rows, scenes, storyboards) for any."""
    model, _ = blocks
    root = _root(tmp_path)
    scene = root / "scene.json"
    shutil.copy(ONE_MOVE_SCENE, scene)
    secret = root / "secret.json"
    shutil.copy(PYRAMID, secret)
    out = root / "work" / "evaluation"
    rule = Allowed((model, scene), (out,), audit_environment(root, caches))
    args = ["evaluate", model, scene, "--workers", "0", "--seeds", "2", "--out", out]
    audit = audited(args, root / "work", rule, never=[secret])
    check_clean(audit.answer, max_seconds=600)
    assert audit.answer.code == 0, audit.answer
    assert (out / "runs.jsonl").is_file()
