"""What an evaluation runs: its settings (``evaluation.json`` in its folder,
so that ``--resume`` needs nothing else), its scenes (``scenes/NAME.json``,
each a file ``demoplan run`` reads) and its runs, every scene × every seed."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from demoplan.errors import InputError
from demoplan.evaluation.runs import RunSpec
from demoplan.evaluation.scenes import LayoutSettings, random_scene_document
from demoplan.fileio import display_path, dump_json, read_document, write_atomic
from demoplan.model import TaskModel
from demoplan.scenes.scene import complete_geometry, scene_from_document
from demoplan.scenes.targets import check_scene_objects

__all__ = ["SETTINGS", "EvaluationSettings", "plan_runs", "read_settings", "write_plan"]

SETTINGS = "evaluation.json"
FORMAT = "demoplan/evaluation-1"


@dataclass(frozen=True, slots=True)
class EvaluationSettings:
    """An evaluation: the model file, the scene files given, ``random_scenes``
    layouts drawn (layout seeds 0 … N-1), ``seeds`` runs of each scene (each run
    its own seed, :func:`plan_runs`)
    in ``sim`` with ``faults`` (``--faults`` text); ``clutter`` clutter objects
    in each random layout (runs allow unknown objects where any scene has them)."""

    model: str
    scenes: tuple[str, ...] = ()
    random_scenes: int = 0
    seeds: int = 1
    faults: str = ""
    sim: str = "kinematic"
    clutter: int = 0
    layout: LayoutSettings = field(default_factory=LayoutSettings)

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        data["scenes"] = list(self.scenes)
        return {"format": FORMAT, **data}


def read_settings(folder: Path) -> EvaluationSettings:
    """The settings an evaluation in ``folder`` was started with."""
    path = folder / SETTINGS
    if not path.is_file():
        raise InputError(
            f"has no {SETTINGS}; a folder an evaluation wrote (--out) expected",
            source=display_path(folder),
        )
    data = read_document(path)
    if data.get("format") != FORMAT:
        raise InputError(f"{FORMAT!r} expected", source=display_path(path), field="format")
    try:
        data.pop("format")
        data["scenes"] = tuple(data["scenes"])
        data["layout"] = LayoutSettings(**data["layout"])
        return EvaluationSettings(**data)
    except (KeyError, TypeError) as exc:
        raise InputError(
            f"not the settings an evaluation writes ({exc}); the folder of one expected",
            source=display_path(path),
        ) from None


def _scene_documents(model: TaskModel, settings: EvaluationSettings) -> dict[str, dict[str, Any]]:
    documents: dict[str, dict[str, Any]] = {}
    for given in settings.scenes:
        name = Path(given).stem
        if name in documents or name.startswith("random-"):
            raise InputError(
                "two scenes of one name, or a name random layouts take; "
                "scene files of distinct stems expected",
                source=given,
            )
        documents[name] = read_document(Path(given))
        scene = complete_geometry(scene_from_document(documents[name], given), model)
        check_scene_objects(model, scene, clutter=settings.clutter > 0)  # here, not in each run
    layout = LayoutSettings(**{**asdict(settings.layout), "clutter": settings.clutter})
    for seed in range(settings.random_scenes):
        documents[f"random-{seed}"] = random_scene_document(model, seed, layout)
    return documents


def write_plan(folder: Path, model: TaskModel, settings: EvaluationSettings) -> None:
    """The settings (first: a folder with them is an evaluation's, to resume) and
    every scene's file not there yet, in ``folder`` — a layout is a function of
    its seed, so an evaluation stopped while writing them writes the same ones
    when resumed. Every scene is checked before anything is written."""
    documents = _scene_documents(model, settings)
    if not (folder / SETTINGS).exists():
        write_atomic(folder / SETTINGS, dump_json(settings.to_json()))
    for name, document in documents.items():
        path = folder / "scenes" / f"{name}.json"
        if not path.exists():
            write_atomic(path, dump_json(document))


def plan_runs(folder: Path, settings: EvaluationSettings) -> list[RunSpec]:
    """Every run, scene by scene (in the order given, then the random ones), seed by
    seed: scene j's runs have seeds jK … jK+K−1 (K: ``seeds``), so that no two
    runs draw the same faults and ``demoplan run --seed S`` repeats each."""
    names = [Path(s).stem for s in settings.scenes]
    names += [f"random-{seed}" for seed in range(settings.random_scenes)]
    clutter = settings.clutter > 0
    specs: list[RunSpec] = []
    for index, name in enumerate(names):
        document = read_document(folder / "scenes" / f"{name}.json")
        for seed in range(index * settings.seeds, (index + 1) * settings.seeds):
            specs.append(RunSpec(name, document, seed, settings.faults, settings.sim, clutter))
    return specs
