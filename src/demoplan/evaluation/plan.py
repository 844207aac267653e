"""What an evaluation runs: its settings (``evaluation.json`` in its folder,
so that ``--resume`` needs nothing else), its scenes (``scenes/NAME.json``,
each a file ``demoplan run`` reads) and its runs, every scene × every seed."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from demoplan.errors import InputError, UsageError
from demoplan.evaluation.results import JOURNAL, ROWS
from demoplan.evaluation.runs import RunSpec
from demoplan.evaluation.scenes import LayoutSettings, random_scene_document
from demoplan.execution.robosuite_run import is_robosuite
from demoplan.execution.robosuite_scene import environment_name
from demoplan.fileio import (
    describe_validation_error,
    display_path,
    dump_json,
    read_document,
    write_atomic,
)
from demoplan.model import TaskModel
from demoplan.scenes.scene import MAX_GRIPPER, complete_geometry, scene_from_document
from demoplan.scenes.targets import check_scene_objects

__all__ = [
    "SETTINGS",
    "EvaluationSettings",
    "plan_runs",
    "read_settings",
    "scene_documents",
    "write_plan",
]

SETTINGS = "evaluation.json"
FORMAT = "demoplan/evaluation-1"
MAX_RUNS = 1_000_000
"""Runs of one evaluation at most (scenes × seeds): a 10,000-run evaluation of
the arm is a day of one core (benchmarks/README.md); a million rows are about
1 GB of JSON lines."""
MAX_CLUTTER = 20
"""Clutter objects in one random layout at most."""
MAX_MARGIN_M = 1.0
"""The most a layout's workspace is grown by on each side (m)."""
MAX_ATTEMPTS = 100_000
"""Draws per object at most before a layout is refused as too crowded."""


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


class _LayoutSchema(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)

    stack_probability: float = Field(ge=0.0, le=1.0)
    clutter: int = Field(ge=0, le=MAX_CLUTTER)
    margin: float = Field(ge=0.0, le=MAX_MARGIN_M)
    yaw_range: float = Field(ge=0.0, le=180.0)
    finger_radius: float = Field(gt=0.0, le=MAX_GRIPPER)
    attempts: int = Field(ge=1, le=MAX_ATTEMPTS)


class _SettingsSchema(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)

    format: Literal["demoplan/evaluation-1"]
    model: str = Field(min_length=1, max_length=4096)
    scenes: list[Annotated[str, Field(min_length=1, max_length=4096)]] = Field(max_length=10_000)
    random_scenes: int = Field(ge=0)
    seeds: int = Field(ge=1)
    faults: str = Field(max_length=1000)
    sim: str = Field(max_length=40)
    clutter: int = Field(ge=0, le=MAX_CLUTTER)
    layout: _LayoutSchema


def read_settings(folder: Path) -> EvaluationSettings:
    """The settings an evaluation in ``folder`` was started with, checked field
    by field (a tampered file is one line naming the field), after the folder
    itself (:func:`check_closed_folder`)."""
    check_closed_folder(folder)
    path = folder / SETTINGS
    if not path.is_file():
        raise InputError(
            f"has no {SETTINGS}; a folder an evaluation wrote (--out) expected",
            source=display_path(folder),
        )
    source = display_path(path)
    data = read_document(path)
    try:
        parsed = _SettingsSchema.model_validate(data)
    except ValidationError as exc:
        raise describe_validation_error(exc, source) from None
    settings = EvaluationSettings(
        model=parsed.model,
        scenes=tuple(parsed.scenes),
        random_scenes=parsed.random_scenes,
        seeds=parsed.seeds,
        faults=parsed.faults,
        sim=parsed.sim,
        clutter=parsed.clutter,
        layout=LayoutSettings(**parsed.layout.model_dump()),
    )
    check_settings(settings, source)
    return settings


def check_closed_folder(folder: Path) -> None:
    """An evaluation's folder is opened closed, as a recording is: the folder,
    its ``scenes/`` and every entry demoplan reads or writes there (the
    settings, the rows, the journal, the scene files) is a regular file or
    folder inside it — no link leading anywhere, no special file."""
    entries = [folder, folder / SETTINGS, folder / ROWS, folder / JOURNAL]
    scenes = folder / "scenes"
    entries.append(scenes)
    if scenes.is_dir() and not scenes.is_symlink():
        entries += sorted(scenes.iterdir())
    for entry in entries:
        if not entry.is_symlink() and not entry.exists():
            continue
        kind = "folder" if entry in (folder, scenes) else "file"
        regular = entry.is_dir() if kind == "folder" else entry.is_file()
        if entry.is_symlink() or not regular:
            raise InputError(
                f"is a link or a special file; an evaluation's {kind} expected (a folder "
                "being resumed is read only through its own regular files)",
                source=display_path(entry),
            )


def check_settings(settings: EvaluationSettings, source: str | None = None) -> None:
    """Counts that are whole numbers within the limits (docs/limits.md): the
    options' (``source`` None: a usage error) or a settings file's."""
    limits = {"random_scenes": None, "seeds": None, "clutter": MAX_CLUTTER}
    for name, most in limits.items():
        value = getattr(settings, name)
        option = f"--{name.replace('_', '-')}"
        low = 1 if name == "seeds" else 0
        if not isinstance(value, int) or isinstance(value, bool) or value < low:
            expected = f"a whole number, at least {low}, expected, not {value!r}"
            _refuse(expected, source, name if source else option)
        if most is not None and value > most:
            _refuse(f"at most {most} expected, not {value}", source, name if source else option)
    if is_robosuite(settings.sim):  # one scene: the environment after reset(seed)
        if settings.seeds > MAX_RUNS:
            why = f"{settings.seeds:,} runs; at most {MAX_RUNS:,} expected"
            _refuse(why, source, "seeds" if source else "--seeds")
        return
    scenes = len(settings.scenes) + settings.random_scenes
    runs = scenes * settings.seeds
    if runs > MAX_RUNS:
        why = f"{runs:,} runs (scenes × seeds); at most {MAX_RUNS:,} expected"
        # the factor that made them many: the seeds, or the random layouts
        name = "seeds" if settings.seeds > scenes or not settings.random_scenes else "random_scenes"
        _refuse(why, source, name if source else f"--{name.replace('_', '-')}")


def _refuse(message: str, source: str | None, field: str) -> None:
    if source is None:
        raise UsageError(f"{field}: {message}")
    raise InputError(message, source=source, field=field)


def scene_documents(model: TaskModel, settings: EvaluationSettings) -> dict[str, dict[str, Any]]:
    """Every scene of the evaluation by name — the files given, read and checked
    against the model, then the random layouts —, or the one InputError of the
    first that is refused: read before any cluster is started or joined, so a
    bad scene is one line at once (it waited for Ray, 5–10 s, before)."""
    documents: dict[str, dict[str, Any]] = {}
    if is_robosuite(settings.sim):  # robosuite's reset(seed) makes each run's scene
        return documents
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
    try:
        for seed in range(settings.random_scenes):
            documents[f"random-{seed}"] = random_scene_document(model, seed, layout)
    except InputError as exc:  # the model file's: say which
        if exc.source is not None:
            raise
        raise InputError(exc.message, source=settings.model, field=exc.field) from None
    return documents


def write_plan(
    folder: Path,
    model: TaskModel,
    settings: EvaluationSettings,
    documents: dict[str, dict[str, Any]] | None = None,
) -> None:
    """The settings (first: a folder with them is an evaluation's, to resume) and
    every scene's file not there yet, in ``folder`` — a layout is a function of
    its seed, so an evaluation stopped while writing them writes the same ones
    when resumed. Every scene is checked before anything is written
    (``documents``: :func:`scene_documents`' answer, when already read)."""
    if documents is None:
        documents = scene_documents(model, settings)
    if not (folder / SETTINGS).exists():
        write_atomic(folder / SETTINGS, dump_json(settings.to_json()))
    for name, document in documents.items():
        path = folder / "scenes" / f"{name}.json"
        if not path.exists():
            write_atomic(path, dump_json(document))


def plan_runs(folder: Path, settings: EvaluationSettings) -> list[RunSpec]:
    """Every run, scene by scene (in the order given, then the random ones), seed by
    seed: scene j's runs have seeds jK … jK+K−1 (K: ``seeds``), so that no two
    runs draw the same faults and ``demoplan run --seed S`` repeats each. With
    ``--sim robosuite:ENV`` one scene, ``ENV``, without a document: run k is
    robosuite's environment after ``reset(k)``."""
    if is_robosuite(settings.sim):
        env = environment_name(settings.sim)
        return [RunSpec(env, None, seed, "", settings.sim) for seed in range(settings.seeds)]
    names = [Path(s).stem for s in settings.scenes]
    names += [f"random-{seed}" for seed in range(settings.random_scenes)]
    clutter = settings.clutter > 0
    specs: list[RunSpec] = []
    for index, name in enumerate(names):
        document = read_document(folder / "scenes" / f"{name}.json")
        for seed in range(index * settings.seeds, (index + 1) * settings.seeds):
            specs.append(RunSpec(name, document, seed, settings.faults, settings.sim, clutter))
    return specs
