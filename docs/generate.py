"""Write docs/formats.md and docs/cli.md from the code they describe.

    python docs/generate.py            # rewrite both files
    python docs/generate.py --check    # exit 1 naming each file that is out of date

Run with demoplan installed (``pip install -e ".[dev]"``), from any folder.
The field tables of formats.md come from the pydantic schemas the readers
validate with, its examples from ``examples/`` and from running the library
on them, and cli.md from the typer application itself; the prose is kept
here. Nothing depends on the terminal or the environment: no help text is
wrapped to a terminal width, example paths are relative to the repository,
and the computed examples leave out their timings. ``tests/e2e/test_docs_generated.py``
checks that the committed files are what this script writes.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Any, get_args, get_origin

import typer
import typer.core
import typer.main
from pydantic import BaseModel

from demoplan.budget import Clock
from demoplan.cli import app
from demoplan.cli.launcher import INTERRUPTED_EXIT, TERMINATED_EXIT
from demoplan.documents.colours import COLOUR_FORMS
from demoplan.documents.masses import MAX_DENSITY, MIN_DENSITY
from demoplan.documents.names import MAX_NAME_LENGTH
from demoplan.documents.poses import (
    MAX_ANGLE,
    MAX_COORDINATE,
    MAX_DISTANCE_M,
    MAX_SIZE_M,
    MIN_SIZE_M,
    LandmarkSchema,
    ObjectSchema,
    PoseSchema,
    UnitsSchema,
)
from demoplan.documents.units import MAX_CARRIED_M, MAX_SPREAD_M, MAX_SPREAD_PER_OBJECT
from demoplan.errors import InputError, LimitReachedError, NoPlanError, UsageError
from demoplan.execution.behaviour_tree import ATTEMPTS, MAX_TICKS, NODES, task_tree
from demoplan.execution.executor import ExecutionSettings
from demoplan.execution.faults import FAULT_KINDS, Faults
from demoplan.execution.runner import run_task
from demoplan.execution.tree_checks import MAX_ATTEMPTS, MAX_TOLERANCE_M, NODE_TYPES
from demoplan.fileio import FORMAT_VERSION, MAX_FILE_BYTES
from demoplan.learning import learn
from demoplan.documents.demonstrations import (
    GEOMETRY_TOLERANCE,
    DemonstrationSchema,
    DemonstrationsSchema,
    ObjectsFileSchema,
    StepSchema,
    load_demonstrations,
)

# The schemas the readers validate with; most are private to their modules, and
# read here only to describe them.
from demoplan.learning.modelfile import (
    _ModelSchema,
    _OrientationSchema,
    _PositionSchema,
    _PrecisionSchema,
    _RoleSchema,
    _SettingsSchema,
    _StateSchema,
    _ViolationSchema,
    model_to_dict,
)
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.model import WOOD_DENSITY
from demoplan.perception.calibration import (
    _CameraSchema,
    _CentreSchema,
    _ErrorSchema,
    _UsedMarkersSchema,
)
from demoplan.perception.calibration_inputs import (
    MAX_MARKER_SIDE,
    _IntrinsicsSchema,
    _MarkersSchema,
)
from demoplan.perception.camera import MAX_IMAGE_BYTES, MAX_PIXELS, MAX_SIDE
from demoplan.perception.frames import VIDEO_SUFFIXES
from demoplan.planning.problem import format_plan, optimality_line, plan_to_json
from demoplan.planning.search import Budget, solve
from demoplan.planning.xml import MAX_XML_BYTES, load_problem
from demoplan.plotting.output import FIGURE_FORMATS
from demoplan.scenes.plan import plan_in_scene
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import (
    MAX_GRIPPER,
    _GripperSchema,
    _ObjectSchema,
    _RobotSchema,
    _SceneSchema,
    _TableSchema,
    load_scene,
)
from demoplan.segmentation.readers.csv import MAX_STREAM_BYTES, PLAUSIBLE_METRES

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
WIDTH = 100
"""The width compact JSON examples are folded to."""
GENERATED = "This page is written by `python docs/generate.py`; edit the generator, not this page."

# ----------------------------------------------------------------------------- markdown


def slug(heading: str) -> str:
    """The anchor GitHub gives a heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def escape(text: str) -> str:
    """Text from the code as markdown that shows it as it is (table cells too)."""
    for char in ("\\", "*", "<", "|", "[", "]"):
        text = text.replace(char, "\\" + char)
    return text


def code(text: str) -> str:
    """``text`` as a code span that may stand in a table cell."""
    return "`" + text.replace("|", "\\|") + "`"


PROSE_WIDTH = 80
"""The width prose is wrapped to, as in the other pages of docs/."""
_MARKER = re.compile(r"^(?:[-+*>|]|#{1,6}|\d+[.)]|=+|`{3,}|~{3,})$")
"""A word that would start a list, a quote, a heading or a fence at the start of a line."""
_WORD = re.compile(r"\S*\[[^\]\n]*\]\([^)\s]*\)\S*|\S+")
"""A word, or a link with its text (never broken across lines)."""


def blocks(parts: Iterable[str]) -> str:
    """Markdown blocks, one blank line apart; paragraphs and lists wrapped, headings,
    tables and fenced blocks as they are."""
    out: list[str] = []
    for part in parts:
        if part.startswith(("```", "|", "#")):
            out.append(part)
        else:
            out += [wrap(paragraph) for paragraph in part.split("\n\n")]
    return "\n\n".join(out)


def wrap(paragraph: str) -> str:
    """A paragraph, or a list of ``- `` items, wrapped to :data:`PROSE_WIDTH`."""
    if paragraph.startswith("- "):
        items = re.split(r"\n(?=- )", paragraph)
        return "\n".join(wrap_words(item[2:], "- ", "  ") for item in items)
    return wrap_words(paragraph, "", "")


def wrap_words(text: str, first: str, indent: str) -> str:
    """Greedy wrapping that never starts a line with a markdown marker (``-``, ``#``,
    ``1.``, …): such a word goes to the next line with the word before it."""
    units: list[str] = []
    for word in _WORD.findall(text):
        if units and _MARKER.match(word):
            units[-1] += " " + word
        else:
            units.append(word)
    lines: list[str] = []
    line, empty = first, True
    for unit in units:
        if not empty and len(line) + 1 + len(unit) > PROSE_WIDTH:
            lines.append(line)
            line = indent + unit
        else:
            line = line + unit if empty else f"{line} {unit}"
        empty = False
    lines.append(line)
    return "\n".join(lines)


def table(header: Sequence[str], rows: Iterable[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def fenced(language: str, text: str) -> str:
    return f"```{language}\n{text.rstrip()}\n```"


def compact_json(value: Any, width: int = WIDTH, indent: int = 0, used: int = 0) -> str:
    """JSON with every object or array that fits in ``width`` on one line."""
    one = json.dumps(value, ensure_ascii=False)
    if used + len(one) <= width or not isinstance(value, dict | list) or not value:
        return one
    inner = " " * (indent + 2)
    if isinstance(value, dict):
        lines = []
        for key, item in value.items():
            prefix = json.dumps(key, ensure_ascii=False) + ": "
            used_here = indent + 2 + len(prefix) + 1  # the comma after it
            lines.append(inner + prefix + compact_json(item, width, indent + 2, used_here))
        return "{\n" + ",\n".join(lines) + "\n" + " " * indent + "}"
    # The items of an array are laid out alike: all on a line each, or all folded.
    flat = [json.dumps(item, ensure_ascii=False) for item in value]
    if all(indent + 3 + len(text) <= width for text in flat):
        lines = [inner + text for text in flat]
    else:
        lines = [inner + compact_json(item, width, indent + 2, width) for item in value]
    return "[\n" + ",\n".join(lines) + "\n" + " " * indent + "]"


def rounded(value: Any, digits: int = 6) -> Any:
    """``value`` with every float rounded (examples read better; a file may hold either)."""
    if isinstance(value, float):
        return round(value, digits) + 0.0  # no -0.0
    if isinstance(value, dict):
        return {k: rounded(v, digits) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [rounded(v, digits) for v in value]
    return value


def mebibytes(size: int) -> str:
    if size >= 1024**3:
        return f"{size / 1024**3:g} GiB"
    return f"{size / 1024**2:g} MiB"


def number(value: float) -> str:
    return str(int(value)) if float(value).is_integer() else repr(float(value))


# ------------------------------------------------------------------- schema field tables


@dataclass(frozen=True)
class FieldTable:
    """One schema's fields as a table under a heading; ``meaning`` per field."""

    heading: str
    schema: type[BaseModel]
    meaning: Mapping[str, str]
    noun: str = ""
    """What a value of the schema is called where another table refers to it."""

    @property
    def name(self) -> str:
        return self.noun or self.heading.lower()


POSE_FIELDS = {
    "position": "`[x, y]` or `[x, y, z]`: the resting point; a missing z is 0",
    "yaw": "turn about z (degrees, or radians with `units.angle`)",
    "rpy": "`[roll, pitch, yaw]`: turns about the fixed x, then y, then z axes",
    "quat": "unit quaternion `[x, y, z, w]`: its length within 0.1 of 1 (normalised when read)",
}
UNITS = FieldTable(
    "Units",
    UnitsSchema,
    {
        "length": "unit of every length in the file: positions, sizes, free space, gripper",
        "angle": "unit of `yaw`, `rpy` and grasp axes",
    },
)
POSE = FieldTable("Poses", PoseSchema, POSE_FIELDS, noun="pose")
DEMONSTRATION = FieldTable(
    "Demonstration fields",
    DemonstrationSchema,
    {
        "format": "`demoplan/demonstration-1` (optional inside a collection)",
        "name": "the demonstration's name (default: the file name without extension)",
        "description": "free text",
        "units": "units of this demonstration",
        "objects": "geometry of the objects; when given, it names every object a step moves",
        "landmarks": "static things placements may be relative to (a tray, a board); "
        "never moved by a step",
        "initial": "where objects stood before the first step",
        "provenance": "where the demonstration came from (above); strings and numbers",
        "steps": "the steps in the order they were done (at least one)",
    },
)
STEP = FieldTable(
    "Step",
    StepSchema,
    {**POSE_FIELDS, "object": "the object moved: the pose is where it was released"},
)
MASS_FIELDS = {
    "mass": "kg; or `density`, not both; default: solid wood "
    f"({WOOD_DENSITY:g} kg/m³). The mean density over the shape's volume must lie "
    f"between {MIN_DENSITY:g} (air) and {MAX_DENSITY:g} kg/m³ (osmium)",
    "density": "kg/m³; the mass is the density times the shape's volume (a box, a "
    "cylinder, a sphere of the largest extent)",
}
GEOMETRY = FieldTable(
    "Object geometry",
    ObjectSchema,
    {
        "shape": "`mesh`: a shape known only by its extents (no symmetry is assumed)",
        "size": "extents `[x, y, z]` in the object's frame; a cylinder's x and y are its diameter",
        **MASS_FIELDS,
        "type": "the kind of object it is (`plate`), where several interchangeable instances "
        "are of one kind; default: its name, an object of its own kind. Instances of a type "
        "have one shape and size; their names need not match between demonstrations "
        "([learning.md](learning.md#identical-objects))",
        "colour": f"{COLOUR_FORMS}: the colour every figure of the demonstration and of the "
        "model learned from it draws it in (`learn --plot`, `show`, the studio), and of a "
        "scene that names none for it (`plan --plot`, `run --frames`, MuJoCo, the arm); the "
        "studio's Teach view writes the colours a user chose. Default: the figures' palette. "
        "A demonstration giving a thing none draws it in the colour another of the task's "
        "gives (`show`'s panels, as `plan` and `run`). Two demonstrations giving one thing "
        "different colours are learned with a warning line: each demonstration's figure "
        "draws its own, a scene taking the first's. An "
        "instance of a type (`plate-a`, learned as a role `plate#1`) keeps its colour in a "
        "scene naming it. Anything else is one error line naming the file and the field "
        "(`objects.cup.colour`, exit 1)",
    },
)
LANDMARK = FieldTable(
    "Landmark",
    LandmarkSchema,
    {
        **POSE_FIELDS,
        "position": "`[x, y]` or `[x, y, z]`: where it stands (bottom-face centre); its yaw "
        "is its frame as given — a landmark's shape does not make its frame symmetric",
        "shape": "its shape, with `size`",
        "size": "extents `[x, y, z]`; z is its height: objects stand on its top, and every "
        "figure draws it (may stand under `objects` instead, as `import` writes it)",
        "compartments": "its open interiors (a bin's compartments): `[x_low, y_low, z_low, "
        "x_high, y_high, z_high]` each, in its frame from its position, z from the top of its "
        "floor to its rim; learning makes placements inside one a region goal "
        "(docs/learning.md, \"Region goals\"). `import` writes them for a recording's bins "
        "(the spaces its walls and dividers enclose all round); a scene's are not used",
        "colour": f"{COLOUR_FORMS}: the colour every renderer draws it in, as an object's "
        "(default: the figures' sandy landmark colour; a scene's landmark without one takes "
        "the demonstrations'). In a demonstration it may stand under `objects` where the "
        "landmark's size does, not in both places; anything else is one error line naming "
        "the file and the field (`landmarks.caddy.colour`, exit 1)",
    },
    noun="landmark",
)
COLLECTION = FieldTable(
    "Collection fields",
    DemonstrationsSchema,
    {
        "format": "`demoplan/demonstrations-1`",
        "description": "free text",
        "units": "units of every demonstration that gives none of its own",
        "demonstrations": "demonstration documents (the fields above; `format` optional)",
    },
)
OBJECTS_FILE = FieldTable(
    "Object geometry file fields",
    ObjectsFileSchema,
    {
        "format": "optional; not checked",
        "description": "free text",
        "units": "units of the sizes",
        "objects": "geometry per object of the stream (at least one)",
    },
)
SCENE = FieldTable(
    "Scene fields",
    _SceneSchema,
    {
        "format": "`demoplan/scene-1`",
        "name": "the scene's name",
        "description": "free text",
        "units": "units of this scene",
        "objects": "the movable objects and where they stand (at least one)",
        "landmarks": "static references; one that moved between the demonstrations must be "
        "given ([scenes.md](scenes.md#landmarks)); one that stood still defaults to that pose",
        "freespace": "spots `[x, y]` or `[x, y, z]` (z = 0) where objects may be parked; "
        "default: generated on the table",
        "gripper": "the parallel-jaw gripper",
        "table": "where free space may be generated (default: the demonstrations' "
        "workspace grown by 10 cm, the table the studio draws; where that has no room, "
        "inferred around the objects, targets, landmarks and that workspace; docs/scenes.md)",
        "robot": "where the arm of `run --sim arm` stands (default: placed where it "
        "reaches every object and target)",
    },
)
SCENE_OBJECT = FieldTable(
    "Scene object",
    _ObjectSchema,
    {
        **POSE_FIELDS,
        "size": "extents `[x, y, z]`; may be left out when the demonstrations give it",
        "shape": "the object's shape",
        "grasps": "finger axes in the object's frame, in degrees; default `[0, 90]`: "
        "two side grasps at right angles",
        **MASS_FIELDS,
        "type": "the kind of object it is (`plate`); any instance of a type may fill the "
        "model's roles of that type, the planner chooses which "
        "([planning.md](planning.md#identical-objects)); default: its name",
        "colour": f"{COLOUR_FORMS}, e.g. `\"#d62728\"` or `[0.84, 0.15, 0.16]`: the colour "
        "every renderer draws it in — `run --frames` (the kinematic top views, MuJoCo's and "
        "the arm's pictures), `--video`, the storyboard, `plan --plot`, the studio. Default: "
        "the demonstrations' colour for it, else the colour demoplan gives its name (`red` is "
        "red, another name a colour of a palette of 20, distinct within the task). Anything "
        "else is one error line naming the file and the field (`objects.cup.colour`, exit 1)",
    },
)
GRIPPER = FieldTable(
    "Gripper",
    _GripperSchema,
    {
        "finger_radius": f"each finger is a disc of this radius (at most {MAX_GRIPPER:g} m)",
        "clearance": f"extra gap between finger and object (at most {MAX_GRIPPER:g} m)",
    },
)
TABLE = FieldTable(
    "Table",
    _TableSchema,
    {"min": "`[x, y]` of one corner", "max": "`[x, y]` of the opposite corner, above and right"},
)
ROBOT = FieldTable(
    "Robot",
    _RobotSchema,
    {
        "base": "`[x, y]` of the arm's base on the table (`run --sim arm`)",
        "yaw": "the base's turn about the vertical, in degrees (default 0: facing +x)",
    },
)
MODEL = FieldTable(
    "Model fields",
    _ModelSchema,
    {
        "format": "`demoplan/model-1`",
        "states": "the learned states",
        "sequences": "per demonstration, the visits of its steps in order: state ids, a "
        "second visit of a state in one demonstration labelled `C#2`",
        "constraints": "pairs `[X, Y]`: X comes before Y (seen before it in some "
        "demonstration, after it in none)",
        "support": "optional, per constraint: the number of demonstrations that show it (X "
        "visited before Y; docs/learning.md). Written by `learn`; recomputed from "
        "`sequences` when read",
        "goals": "per demonstration, the visits it ends in",
        "teacher_constraints": "pairs `[X, Y]` required by the teacher (`learn --require`), "
        "kept whatever the demonstrations show",
        "violations": "demonstrations that contradict a teacher constraint",
        "settings": "the learning settings (below); left out: the defaults",
        "precision": "the placement precision decisions were measured against",
        "roles": "the roles of types with declared instances (below); left out where every "
        "object is of its own type",
        "demonstrations": "the demonstrations learned from (demonstration documents), "
        "for `learn --update`; their instances renamed to the roles they filled",
    },
)
ROLE = FieldTable(
    "Role",
    _RoleSchema,
    {
        "name": "the role, as states and demonstrations name it: `plate#1`, `plate#2` (the "
        "type's own name where it has one role)",
        "type": "the type of the instances that fill it",
        "instances": "per demonstration, the instance that filled the role (null: that "
        "demonstration had fewer instances of the type)",
    },
)
STATE = FieldTable(
    "State",
    _StateSchema,
    {
        "id": "`A`, `B`, …, `Z`, `AA`, … in order of first appearance (demonstrations in "
        "the order given, steps in order)",
        "object": "the object placed",
        "position": "where",
        "orientation": "how it is turned",
        "members": "the placements that make the state: `[demonstration, step]`, from 0",
        "margins": "per decision (`position reference`, `position clusters`, …) how far it "
        "was from going the other way, in units of the precision",
        "notes": "decisions taken at an edge of learning's rules, in words (`turns with "
        "lunchbox: never seen turned`; docs/learning.md, \"Notes\"); for people, not read back "
        "into decisions",
    },
)
STATE_POSITION = FieldTable(
    "State position",
    _PositionSchema,
    {
        "reference": "the object or landmark the position is relative to; null: absolute",
        "value": "`[x, y, z]` in metres: the position, or the offset from the reference",
        "spread": "trace of the sample covariance of the members' values (m²)",
        "frame": "`reference`: the offset is in the reference's frame (turns with it); "
        "`world`: in world axes",
        "anywhere": "`true`: placed anywhere on its support (an absolute state scattered far "
        "beyond the precision, docs/learning.md); `value` is the mean, for information",
        "region": "a region goal: placed anywhere inside this compartment of the landmark "
        "`reference`, `[x_low, y_low, z_low, x_high, y_high, z_high]` in metres, its frame "
        "(docs/learning.md, \"Region goals\"); `value` is the mean of the placements",
    },
)
STATE_ORIENTATION = FieldTable(
    "State orientation",
    _OrientationSchema,
    {
        "reference": "the object or landmark the orientation is relative to; null: absolute",
        "value": "`[yaw]` or `[roll, pitch, yaw]` in degrees; null: not learned (the "
        "object keeps its orientation)",
        "quat": "the same as a quaternion `[x, y, z, w]`; read in preference to `value`",
        "spread": "spread of the members' rotations about their mean (deg²)",
    },
)
VIOLATION = FieldTable(
    "Violation",
    _ViolationSchema,
    {
        "demonstration": "the demonstration (from 0)",
        "required": "the teacher constraint `[X, Y]` it contradicts",
    },
)
PRECISION = FieldTable(
    "Precision",
    _PrecisionSchema,
    {
        "position": "RMS placement precision (m)",
        "orientation": "RMS orientation precision (degrees)",
        "estimated": "true: estimated from the demonstrations; false: given",
    },
)
SETTINGS = FieldTable(
    "Settings",
    _SettingsSchema,
    {
        "position_noise": "placement precision (m); null: estimated from the "
        "demonstrations (`learn --position-noise`)",
        "orientation_noise": "orientation precision (degrees); null: estimated "
        "(`--orientation-noise`)",
        "position_separation": "cluster means closer than this (m) reject a clustering "
        "(`--position-separation`)",
        "orientation_separation": "the same for orientations, degrees (`--orientation-separation`)",
        "n_init": "K-means restarts",
        "seed": "seed of the K-means restarts",
        "max_clusters": "cap on clusters per object and reference; 0: none (`--max-clusters`)",
        "significance": "level of the F test that adding states must pass; 0: the paper's "
        "plain comparison (`--significance`)",
        "require": "the teacher constraints as given (`A<B`, `plate<napkin`)",
        "min_support": "a learned constraint is kept when at least this many demonstrations "
        "show it; 1: the paper's rule (`--min-support`)",
        "orientation_follows_position": "an orientation whose reference is a tie within the "
        "precision takes the position's reference (a thing in a box turns with the box); "
        "false under `--paper`: the tie goes to absolute",
    },
)


def described(schema: type[BaseModel]) -> dict[str, str]:
    """Each field's meaning as its schema describes it (the camera and markers files)."""
    properties = schema.model_json_schema()["properties"]
    return {name: node["description"] for name, node in properties.items()}


MARKERS_FILE = FieldTable("Markers file fields", _MarkersSchema, described(_MarkersSchema))
CAMERA_FILE = FieldTable("Camera file fields", _CameraSchema, described(_CameraSchema))
REPROJECTION = FieldTable(
    "Reprojection error", _ErrorSchema, described(_ErrorSchema), noun="reprojection error"
)
USED_MARKERS = FieldTable(
    "Markers used", _UsedMarkersSchema, described(_UsedMarkersSchema), noun="markers used"
)
INTRINSICS = FieldTable(
    "Intrinsics", _IntrinsicsSchema, described(_IntrinsicsSchema), noun="intrinsics"
)
CAMERA_CENTRE = FieldTable(
    "Camera centre", _CentreSchema, described(_CentreSchema), noun="camera centre"
)
FIELD_TABLES = (
    MARKERS_FILE,
    CAMERA_FILE,
    REPROJECTION,
    USED_MARKERS,
    INTRINSICS,
    CAMERA_CENTRE,
    UNITS,
    POSE,
    DEMONSTRATION,
    STEP,
    GEOMETRY,
    LANDMARK,
    COLLECTION,
    OBJECTS_FILE,
    SCENE,
    SCENE_OBJECT,
    GRIPPER,
    TABLE,
    ROBOT,
    MODEL,
    STATE,
    STATE_POSITION,
    STATE_ORIENTATION,
    VIOLATION,
    PRECISION,
    ROLE,
    SETTINGS,
)
LINKED = {entry.schema.__name__: entry for entry in FIELD_TABLES}
"""Schemas by the name ``model_json_schema`` refers to them with."""


def field_table(entry: FieldTable) -> str:
    """``### heading`` and the schema's fields: name, type, required or default, meaning."""
    schema = entry.schema.model_json_schema()
    properties: dict[str, Any] = schema["properties"]
    undocumented = sorted(set(properties) - set(entry.meaning))
    stale = sorted(set(entry.meaning) - set(properties))
    if undocumented or stale:
        raise SystemExit(
            f"docs/generate.py: {entry.schema.__name__}: describe the fields {undocumented} "
            f"and remove {stale} (FieldTable {entry.heading!r})"
        )
    required = set(schema.get("required", ()))
    rows = []
    for name, node in properties.items():
        default = "required" if name in required else code(json.dumps(node.get("default")))
        rows.append((code(name), type_text(node), default, entry.meaning[name]))
    return f"### {entry.heading}\n\n" + table(("field", "type", "default", "meaning"), rows)


def type_text(node: Mapping[str, Any], plural: bool = False) -> str:
    """A JSON schema node in words: ``array of 2–3 numbers in [-10000, 10000]``."""
    if "$ref" in node:
        name = node["$ref"].rsplit("/", 1)[-1]
        if name not in LINKED:
            raise SystemExit(f"docs/generate.py: no FieldTable for the schema {name}")
        entry = LINKED[name]
        noun = "objects" if plural else "object"
        return f"[{entry.name}](#{slug(entry.heading)}) {noun}"
    if "anyOf" in node:
        options = [o for o in node["anyOf"] if o.get("type") != "null"]
        text = " or ".join(type_text(o, plural) for o in options)
        return text + (" or null" if len(options) < len(node["anyOf"]) else "")
    if "enum" in node:
        return "one of " + ", ".join(code(json.dumps(v)) for v in node["enum"])
    kind = node.get("type")
    if kind == "array":
        if "prefixItems" in node:
            kinds = "[" + ", ".join(type_text(i) for i in node["prefixItems"]) + "]"
            noun = "pair" if len(node["prefixItems"]) == 2 else "array"
            return f"{noun}s {kinds}" if plural else f"{noun} {kinds}"
        low, high = node.get("minItems"), node.get("maxItems")
        count = ""
        if low is not None and low == high:
            count = f"{low} "
        elif low is not None and high is not None:
            count = f"{low}–{high} "
        elif low:
            count = f"{low} or more "
        items = node.get("items")
        inner = type_text(items, plural=True) if items else "values"
        return ("arrays" if plural else "array") + f" of {count}{inner}"
    if kind == "object":
        extra = node.get("additionalProperties")
        noun = "objects" if plural else "object"
        if isinstance(extra, dict):
            return f"{noun}: name → {type_text(extra)}"
        return noun
    words = {"number": "number", "integer": "integer", "string": "string", "boolean": "boolean"}
    if kind not in words:
        raise SystemExit(f"docs/generate.py: cannot describe the schema node {dict(node)}")
    if kind == "string" and node.get("format") == "object-name":
        return "[object name" + ("s" if plural else "") + "](#conventions)"
    text = words[kind] + ("s" if plural else "")
    if kind == "string" and node.get("minLength") == 1:
        text = "non-empty " + text
    if "pattern" in node:
        text += f" matching {code(node['pattern'])}"
    low, high = node.get("minimum"), node.get("maximum")
    if low is not None and high is not None:
        text += f" in [{number(low)}, {number(high)}]"
    elif low is not None:
        text += f" ≥ {number(low)}"
    elif high is not None:
        text += f" ≤ {number(high)}"
    if "exclusiveMinimum" in node:
        text += f" > {number(node['exclusiveMinimum'])}"
    return text


def extra_fields(schema: type[BaseModel]) -> str:
    return "kept" if schema.model_config.get("extra") == "allow" else "refused"


# ------------------------------------------------------------------ computed examples


@dataclass(frozen=True)
class Output:
    """A JSON output's fields: type and meaning; ``optional`` ones appear only sometimes."""

    fields: Mapping[str, tuple[str, str]]
    optional: frozenset[str] = frozenset()

    def rows(self, shown: Mapping[str, Any], what: str) -> list[tuple[str, str, str]]:
        """The table rows in the order the output gives them; the output and this
        description must name the same fields."""
        unknown = sorted(set(shown) - set(self.fields))
        missing = sorted(set(self.fields) - set(shown) - self.optional)
        if unknown or missing:
            raise SystemExit(
                f"docs/generate.py: {what}: describe the fields {unknown} and remove {missing}"
            )
        order = [*shown, *(k for k in self.fields if k not in shown)]
        return [(code(k), *self.fields[k]) for k in order]


SOLVE_JSON = Output(
    {
        "actions": ("array of actions", "`[KIND, OBJECT, LOCATION, GRASP]`, in order"),
        "length": ("integer", "number of actions"),
        "optimal": ("boolean", "proved shortest"),
        "bound": ("integer", "proven lower bound on the length of any plan"),
        "search": (
            "string",
            "the phase that found it (`tight`, `greedy`, `plateau`, `parts`, "
            "`greedy+astar`, `parts+astar`, `astar`, `bfs`; docs/planning.md)",
        ),
        "expanded": ("integer", "states expanded"),
        "generated": ("integer", "states generated"),
        "seconds": ("number", "time spent searching"),
        "read_seconds": ("number", "time spent reading and checking the problem file"),
    },
)
PLAN_JSON = Output(
    {
        "actions": ("array of actions", "the chosen plan, `[KIND, OBJECT, LOCATION, GRASP]`"),
        "length": ("integer", "number of actions"),
        "optimal": ("boolean", "proved shortest over every candidate goal"),
        "bound": ("integer", "proven lower bound over every candidate goal"),
        "goal": ("integer", "the demonstration whose goal was chosen, from 0"),
        "binding": (
            "object",
            "only where the model has roles of identical objects: role → the scene's instance "
            "filling it ([planning.md](planning.md#identical-objects))",
        ),
        "candidates": ("array", "every candidate goal (below)"),
        "subgoals": ("array", "the chosen goal's subgoals (below)"),
        "precedences": ("array of pairs", "`[X, Y]`: subgoal Y only after X"),
        "locations": ("object", "every location of the chosen problem (below), by name"),
        "grasps": (
            "object",
            "every grasp by name: `object`, and `axis` in degrees in the object's frame",
        ),
        "collisions": (
            "object",
            "with `--collisions simulation` only: `simulation` and `rule` (how many "
            "collision facts each gives), `only_rule` and `only_simulation` (the facts "
            "`[a, b, grasp]` where they disagree), `unreachable` (`[location, grasp]` the "
            "arm could not check)",
        ),
    },
    optional=frozenset({"collisions", "binding"}),
)
CANDIDATE_JSON = Output(
    {
        "goal": ("integer", "the demonstration naming the candidate, from 0"),
        "demonstrations": ("array of integers", "every demonstration with this goal, from 0"),
        "length": ("integer or null", "plan length; null: no plan"),
        "optimal": ("boolean or null", "the plan is proved shortest"),
        "bound": ("integer or null", "proven lower bound; null: proved to have no plan"),
        "reason": ("string", "why there is no plan (only then)"),
        "bindings": (
            "integer",
            "only where the model has roles: the bindings of roles to instances weighed "
            "(planned, or set aside by their lower bound)",
        ),
        "expanded": ("integer or null", "states expanded"),
        "seconds": ("number or null", "time spent on this candidate"),
    },
    optional=frozenset({"reason", "bindings"}),
)
SUBGOAL_JSON = Output(
    {
        "id": ("string", "the visit label (`C`, `C#2`)"),
        "state": ("string", "the state id"),
        "object": ("string", "the object to put down"),
        "location": ("string", "where"),
    }
)
LOCATION_JSON = Output(
    {
        "position": ("array of 3 numbers", "resting point (m)"),
        "yaw": ("number", "degrees"),
        "kind": ("string", "`current`, `target`, `current+target` or `freespace`"),
        "objects": ("array of strings", "the objects it is made for"),
    }
)
RUN_JSON = Output(
    {
        "success": ("boolean", "the goal was reached"),
        "status": ("string", "`succeeded` or `failed`: whether the goal was reached, in words"),
        "exit_code": ("integer", "the exit code `run` ends with (docs/limits.md): 0 when it succeeded"),
        "replans": ("integer", "times the task was planned again"),
        "actions": ("array of actions", "the actions executed, `[KIND, OBJECT, LOCATION, GRASP]`"),
        "failures": ("array", "every difference between expectation and observation (below)"),
        "injected": ("array", "every fault the simulation injected, as it happened (below)"),
        "collisions": (
            "array",
            "`--sim arm`: every contact of the arm with anything but its load, as a "
            "sentence with the simulated time (empty: none)",
        ),
        "motions_refused": (
            "array",
            "`--sim arm`: motions not made because a check found them impossible "
            "(no inverse kinematics, a collision), each with its reason",
        ),
        "final_scene": ("scene", "the world at the end, as a scene document"),
        "goal": ("integer or null", "the demonstration whose goal was pursued, from 0"),
        "reason": ("string", "how the run ended"),
        "world": ("string", "`kinematic`, `mujoco`, `arm` or `robosuite:ENV`"),
        "first_plan_actions": ("integer", "length of the first plan"),
        "extra_actions": ("integer", "actions beyond the first plan's"),
        "reached": ("array of strings", "subgoals reached"),
        "pose_errors": ("object", "per goal object, its distance from its target at the end (m)"),
        "turn_errors_deg": (
            "object",
            "per goal object whose target's orientation was learned, its turn from the"
            " target's yaw at the end (deg, given its symmetry; none for a cylinder)",
        ),
        "steps": ("array", "each executed action with the pose it used (below)"),
        "seconds": ("number", "time the run took"),
        "frames": ("array of strings", "images written with `--frames`"),
        "env_success": (
            "boolean",
            "`--sim robosuite:ENV` only: robosuite's `_check_success()` after the run; "
            "`success` is true only with it",
        ),
        "demoplan_success": (
            "boolean",
            "`--sim robosuite:ENV` only: demoplan's executor reached a demonstrated goal",
        ),
        "control_steps": (
            "integer",
            "`--sim robosuite:ENV` only: the environment's control steps (20 per second)",
        ),
    },
    optional=frozenset({"env_success", "demoplan_success", "control_steps"}),
)
FAILURE_JSON = Output(
    {
        "step": ("integer", "the action after which it was seen, from 1 (0: before any)"),
        "kind": ("string", "what went wrong (below)"),
        "detail": ("string", "in words"),
    }
)
INJECTED_JSON = Output(
    {
        "kind": ("string", "the `--faults` kind"),
        "action": ("integer", "the world's action it came with, from 1 (grasps and put-downs)"),
        "object": ("string", "the object it happened to (a `block`: the new obstacle)"),
        "position": ("array of 3 numbers or null", "where the object ended up (null: it stayed)"),
        "detail": ("string", "in words"),
    }
)
STEP_JSON = Output(
    {
        "step": ("integer", "from 1"),
        "action": ("action", "`[KIND, OBJECT, LOCATION, GRASP]`"),
        "position": ("array of 3 numbers", "the location's resting point (m)"),
        "yaw": ("number", "the location's yaw (degrees)"),
        "plan": ("integer", "which plan it came from: 0 the first, 1 after the first replan, …"),
        "ok": ("boolean", "the observation matched the expectation"),
    }
)
IMPORT_JSON = Output(
    {
        "source": ("string", "the recording"),
        "output": ("string", "the folder written"),
        "demonstrations": ("array", "per demonstration of the recording (below)"),
    }
)
IMPORTED_JSON = Output(
    {
        "key": ("string", "its group in `data` (`demo_1`)"),
        "name": ("string or null", "the demonstration's name; null: not written"),
        "file": ("string or null", "the file written; null: none"),
        "samples": ("integer", "simulator states read"),
        "objects": ("array of strings", "the free-jointed bodies followed"),
        "landmarks": ("array of strings", "the static bodies kept as landmarks"),
        "steps": (
            "array",
            "the steps found: `object`, `start` and `end` (s), `position` and, when "
            "oriented, `quat`",
        ),
        "provenance": ("object", "what the recording says about itself"),
        "problem": ("string", "why no demonstration was written (only then)"),
    },
    optional=frozenset({"problem"}),
)
EXECUTION = ExecutionSettings()
"""The tolerances ``run`` compares observations with."""
FAILURE_KINDS = {
    "grasp": "after GRASP the object is not in the hand",
    "release": "after PUT_DOWN the object is still in the hand",
    "dropped": "after PUT_DOWN the object is nowhere to be seen, or 6 cm or more from its target",
    "misplaced": "after PUT_DOWN the object stands within 6 cm of its target but farther "
    f"than {EXECUTION.position_tolerance * 100:g} cm, or is turned more than "
    f"{EXECUTION.yaw_tolerance:g}° from a learned orientation",
    "moved": "another object is gone from where it stood, or stands more than "
    f"{EXECUTION.position_tolerance * 100:g} cm from it",
    "new_object": "an object that was not there before appeared",
    "goal": "the plan is done but the goal does not hold",
}
BLOCKS = "examples/blocks/demonstrations.json"
PYRAMID = "examples/scenes/pyramid-fig4.json"
PAPER_PROBLEM = "examples/planning/paper-example.xml"
RUN_FAULTS = Faults(drop=0.3, displace=0.2)
RUN_SEED = 3


TIMINGS = frozenset({"seconds", "read_seconds"})
"""Fields that differ from run to run: checked against the descriptions, left out
of the examples."""


@dataclass(frozen=True)
class Computed:
    """What the library gives on the shipped examples (JSON outputs in full)."""

    model: dict[str, Any]
    solve_text: str
    solve_note: str
    solve_json: dict[str, Any]
    plan_json: dict[str, Any]
    run_json: dict[str, Any]
    tree_xml: str


def compute() -> Computed:
    """Learn the blocks (Table IV, the paper's reading), plan the pyramid scene,
    run it with faults, solve the paper's example problem. No time limits, so
    that the results do not depend on the machine."""
    model = learn(load_demonstrations([ROOT / BLOCKS]), settings=PAPER_SETTINGS)
    scene = load_scene(ROOT / PYRAMID)
    plan = solve(load_problem(ROOT / PAPER_PROBLEM), "astar", Budget())
    report = run_task(
        model,
        prepare(model, scene),
        faults=RUN_FAULTS,
        seed=RUN_SEED,
        settings=ExecutionSettings(budget=Budget(timeout=math.inf)),
    )
    return Computed(
        model={k: v for k, v in model_to_dict(model).items() if k != "demonstrations"},
        solve_text=format_plan(plan),
        solve_note=f"demoplan: {optimality_line(plan)}",
        solve_json=plan_to_json(plan, read_seconds=0.0),
        plan_json=plan_in_scene(model, prepare(model, scene), clock=Clock(Budget())).to_json(),
        run_json=report.to_json(),
        tree_xml=task_tree(plan_in_scene(model, prepare(model, scene), clock=Clock(Budget()))),
    )


def untimed(value: Any) -> Any:
    """``value`` without its timings, floats rounded: an example that reads the same
    on every machine."""
    if isinstance(value, dict):
        return {k: untimed(v) for k, v in value.items() if k not in TIMINGS}
    if isinstance(value, list):
        return [untimed(v) for v in value]
    return rounded(value)


def first(items: Sequence[Any], what: str) -> Any:
    if not items:
        raise SystemExit(f"docs/generate.py: the example gives no {what} to describe")
    return items[0]


def example_file(relative: str) -> Any:
    return json.loads((ROOT / relative).read_text(encoding="utf-8"))


def first_lines(relative: str, count: int) -> str:
    lines = (ROOT / relative).read_text(encoding="utf-8").splitlines()
    return "\n".join(lines[:count])


# ------------------------------------------------------------------------- formats.md

TITLES = {
    "demonstration": "Demonstration (`demoplan/demonstration-1`)",
    "stream": "Pose stream (CSV, ROS 2 bag)",
    "recording": "Recording (robosuite / robomimic HDF5)",
    "objects": "Object geometry file",
    "requirements": "Teacher constraints file",
    "scene": "Scene (`demoplan/scene-1`)",
    "studio_objects": "Objects file (`demoplan/objects-1`)",
    "markers": "Markers file (`demoplan/markers-1`)",
    "camera": "Camera file (`demoplan/camera-1`)",
    "palette": "Palette file",
    "model": "Task model (`demoplan/model-1`)",
    "problem": "Planning problem (XML)",
    "plan": "Plan",
    "run": "Run report",
    "bt": "Behaviour tree (BehaviorTree.CPP v4 XML)",
    "other": "Other files",
}


def link(key: str, text: str | None = None, page: str = "") -> str:
    return f"[{text or TITLES[key]}]({page}#{slug(TITLES[key])})"


def formats_page() -> str:
    computed = compute()
    sections = [
        "# File formats",
        "Every file demoplan reads or writes, field by field. Demonstrations, scenes, "
        "task models and object geometry are JSON documents checked against schemas when "
        "they are read; the field tables below are made from those schemas, and the "
        "examples are shipped examples or what the library gives on them. " + GENERATED,
        overview(),
        conventions(),
        demonstration_section(),
        stream_section(),
        recording_section(),
        objects_section(),
        requirements_section(),
        scene_section(),
        studio_objects_section(),
        markers_section(),
        camera_section(),
        palette_section(),
        model_section(computed),
        problem_section(),
        plan_section(computed),
        run_section(computed),
        tree_section(computed),
        other_section(),
    ]
    return blocks(sections) + "\n"


FORMS = {
    "demonstration": "JSON / YAML: `demoplan/demonstration-1`, `demoplan/demonstrations-1`",
    "stream": "CSV; ROS 2 bag (sqlite3, mcap)",
    "recording": "HDF5 (robosuite 0.3 / 1.x, robomimic)",
    "objects": "JSON / YAML",
    "requirements": "text",
    "scene": "JSON / YAML: `demoplan/scene-1`",
    "studio_objects": "JSON: `demoplan/objects-1` (the studio's **Save objects**)",
    "markers": "JSON / YAML",
    "camera": "JSON / YAML: `demoplan/camera-1`",
    "palette": "JSON / YAML",
    "model": "JSON / YAML: `demoplan/model-1`",
    "problem": "XML",
    "plan": "text; JSON",
    "run": "JSON",
    "bt": 'XML (`BTCPP_format="4"`)',
    "other": "images, PDDL, reports",
}
SHORT_TITLES = {
    "demonstration": "Demonstration",
    "stream": "Pose stream",
    "recording": "Recording",
    "objects": "Object geometry",
    "requirements": "Teacher constraints",
    "scene": "Scene",
    "studio_objects": "Objects file",
    "markers": "Markers",
    "camera": "Camera",
    "palette": "Palette",
    "model": "Task model",
    "problem": "Planning problem",
    "bt": "Behaviour tree",
}


def users(key: str, which: int) -> list[str]:
    """The commands that read (``which`` 0) or write (1) the file ``key`` of
    :data:`TITLES`, each with the option that asks for it (:data:`COMMAND_FILES`)."""
    found = []
    for command, files in COMMAND_FILES.items():
        for entry in files[which]:
            name, _, option = entry.partition(" ")
            if name == key:
                found.append(code(f"{command} {option}".strip()))
    return found


def overview() -> str:
    """Each file, what it is and which commands read and write it."""
    rows = [
        (
            link(key, SHORT_TITLES.get(key)),
            FORMS[key],
            ", ".join(users(key, 0)) or "—",
            ", ".join(users(key, 1)) or "—",
        )
        for key in TITLES
    ]
    return table(("file", "form", "read by", "written by"), rows)


def listed(words: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return ", ".join(words[:-1]) + (" and " if len(words) > 1 else "") + words[-1]


def conventions() -> str:
    documents = (DemonstrationSchema, _SceneSchema, ObjectsFileSchema, _ModelSchema)
    names = {
        DemonstrationSchema: "demonstrations",
        _SceneSchema: "scenes",
        ObjectsFileSchema: "object geometry files",
        _ModelSchema: "task models",
    }
    refused = [names[s] for s in documents if extra_fields(s) == "refused"]
    kept = [names[s] for s in documents if extra_fields(s) == "kept"]
    unknown = ", and ".join(
        text
        for text in (
            f"refused in {listed(refused)}" if refused else "",
            f"kept (unread) in {listed(kept)}" if kept else "",
        )
        if text
    )

    limits = table(
        ("file", "largest size"),
        [
            (
                "demonstration, scene, task model, object geometry, teacher constraints",
                mebibytes(MAX_FILE_BYTES),
            ),
            ("planning problem (XML)", mebibytes(MAX_XML_BYTES)),
            ("pose stream (CSV)", mebibytes(MAX_STREAM_BYTES)),
            (
                "camera image",
                f"{mebibytes(MAX_IMAGE_BYTES)}, {MAX_PIXELS:,} pixels, {MAX_SIDE:,} on a side",
            ),
        ],
    )
    return blocks(
        [
            "## Conventions",
            "**Documents.** Demonstrations, scenes, task models and object geometry files "
            "are JSON, or YAML when the file name ends in `.yaml` or `.yml`; the top level "
            "is an object. A document names its kind and version in `format`, "
            '`"demoplan/<kind>-<version>"` (a minor version, `-1.1`, is accepted). An '
            f"unknown kind, or a version newer than {FORMAT_VERSION}, is refused. A key given "
            "twice in one object, NaN and ±Infinity, and YAML aliases are refused too. "
            f"Fields a schema does not name are {unknown}. Every problem is one line on "
            "stderr naming the "
            "file, the field and what was expected (exit code 1).",
            "**Object names.** An object's or a landmark's name is a word of a plan "
            "(`GRASP cup loc3 grasp5`): 1 to "
            f"{MAX_NAME_LENGTH} printable characters, no space, tab or line break, no "
            "control character (an escape sequence, a bidirectional override), and not "
            "`loc`, `freespace` or `grasp` followed by digits (the names demoplan gives "
            "locations and grasps). One rule (`demoplan.documents.names`) for "
            "demonstrations, scenes, object geometry files, task models and the objects "
            "of a pose stream or a recording: a name that breaks it is refused where it "
            "is read, in one line naming the file and the field, the name escaped "
            "(`objects['cup\\n']: 'cup\\n' holds a space, a tab or a line break; …`).",
            "**Writing.** Files are written whole or not at all: to a temporary file beside "
            "the target, then renamed over it. JSON is written indented, in UTF-8, in "
            "metres and degrees, with orientations as `quat`.",
            "**Units.** Lengths are metres and angles degrees unless a document's `units` "
            'says otherwise: `"units": {"length": "cm"}` reads every length of that file '
            "in centimetres. Task models, pose streams and problems have no `units`.",
            field_table(UNITS),
            "**World frame.** z points up, against gravity, and the table top is z = 0. A "
            "position is an object's resting point, the centre of its bottom face: an "
            "object standing on the table has z = 0, one standing on a 4 cm block z = 0.04.",
            "**Poses.** A pose is a `position` and at most one orientation; no orientation "
            "means unknown or irrelevant (a plate's turn does not matter). `rpy` angles are "
            "extrinsic x-y-z; `quat` is written `[x, y, z, w]`.",
            field_table(POSE),
            '**Numbers and limits.** Numbers are JSON numbers: `"0.5"` as text and `true` '
            f"are refused. A coordinate as written lies within ±{MAX_COORDINATE:g} (in the "
            "file's unit); "
            "after conversion to metres, a position farther than "
            f"{MAX_DISTANCE_M:g} m from the origin on any axis and an extent outside "
            f"{MIN_SIZE_M * 1000:g} mm – {MAX_SIZE_M:g} m are refused: they are unit "
            "mistakes. Files larger than these are refused before they are read "
            "(docs/limits.md has every limit):",
            limits,
            "**Does the file fit its units?** A file in millimetres without `units` is read "
            "in metres, a 30 cm table as 300 m. A demonstration or scene is therefore "
            "looked at as a whole, after its unit, and refused in one line naming `units` "
            f"when its positions spread more than {MAX_SPREAD_M:g} m along an axis (a "
            f"tabletop is smaller), an object it moves (not a landmark) is larger than "
            f"{MAX_CARRIED_M:g} m, or its positions spread more than "
            f"{MAX_SPREAD_PER_OBJECT:g} times the largest object it moves (sizes and "
            "positions in different units). The line says which unit would fit: "
            "`demoplan: error: mm.json: units: lengths read in metres (the default: it "
            'gives no "units"), its positions spread 524 m along x (…); a tabletop spans '
            "less than 10 m: in mm, the positions spread 0.524 m: give the unit, "
            '"units": {"length": "mm"}`. A millimetre file read as metres is caught '
            "whenever two of its positions lie 1.5 cm or more apart; a centimetre file "
            "whenever its positions spread more than 10 cm along an axis or an object it "
            "moves is larger than 2 cm (a file of smaller things, closer together, is not "
            "seen). A scene's `table` is a region, not a position, and does not count.",
            "**Angles that look like radians.** Where angles are read in degrees (the "
            "default), a file whose `yaw`, `rpy` and `grasps` values all lie within ±2π, "
            "not all whole numbers, and at least two of them π/4 or more (two objects "
            "turned 45° or more, were they radians), gets one warning naming the file and "
            "the field of the largest: "
            "`demoplan: WARNING: scene.json: objects.knife.yaw: every angle of the file "
            "lies within ±2π (this one 1.5708) and they are read in degrees; if they are "
            'radians, give "units": {"angle": "rad"}`. A warning, not an error: every '
            "object within 6° of the axes is possible. Placements within a degree of the "
            "axes (at most one angle of 0.79 or more), and whole numbers (2° is a likelier "
            "reading than 2 rad), are not warned about.",
            "**Numbering demonstrations.** JSON counts demonstrations from 0, in the order "
            "they were given to `learn`: a model's `members` and `violations`, the `goal` "
            "and `candidates` of `plan --json`, the `goal` of `run --json`. Everything "
            "written for a person counts from 1: the tables of `learn` and `show`, the "
            "candidate goals of `plan`, messages, and `problem --goal`. "
            '`"goal": 1` in JSON is demonstration 2.',
        ]
    )


def demonstration_section() -> str:
    single = example_file("examples/set_table/demonstration-1.json")
    collection = example_file(BLOCKS)
    return blocks(
        [
            f"## {TITLES['demonstration']}",
            "One demonstration of the task, segmented: the pose of an object after each "
            "pick-and-place step. `segment` and `import` write them; `learn` reads files, "
            "and folders of them (every `*.json`, `*.yaml` and `*.yml` file in name "
            "order; hidden files are skipped; a file that is a link leading out of the "
            "folder is refused, naming it: a folder's files are read, not what its links "
            "lead to — name such a file on the command line to read it).",
            "A step is one object picked up and released; its pose is where the object "
            "was released. An object may be moved more than once. `landmarks` do not move "
            "but placements may be relative to them. `initial` says where objects stood "
            "before the first step: learning takes the pose of a reference the "
            "demonstration never moves from it. An object has "
            "one geometry in all the demonstrations learned together (to "
            f"{GEOMETRY_TOLERANCE * 1000:g} mm).",
            "A step released where nothing holds the object up gets one warning when the "
            "file is read: more than 1 cm above the table (its lowest corner, for a "
            "tilted object) and not resting on, or inside, an object standing there at "
            "that moment or a landmark — `demoplan: WARNING: dinner.json: "
            "demonstrations[1]: demonstration 'd2' step 4: bowl released 2 cm above the "
            "table with nothing under it (the plate arrives at step 5)`. Learning would "
            "take the pose as given and, since a position is learned relative to objects "
            "already placed, lose the bowl's relation to the plate. Support is judged as "
            "in scenes (footprints; an upper one rests on a lower one covering 5% of it), "
            "with the sizes of `objects`; an object or landmark of unknown size less than "
            "10 cm away beneath may be the support. Steps numbered from 1. A step "
            "followed by a step of the same object is a point it was carried through "
            "(the cucumber example's knife going down and up), not a release.",
            "`provenance` says where a demonstration came from. `segment` writes the "
            "stream (`source`), the pushes and nudges it left out (`pushes`, `nudges`) and "
            "every threshold it used (`segment.min_lift`, …); `import` also writes the "
            "recording's `source`, the `demonstration` key, the number of `samples`, the "
            "`env`, the `robosuite_version`, the `model` and `table_top_z` (the simulator "
            "height that became z = 0).",
            "`examples/set_table/demonstration-1.json` (Experiment 1, demonstration 1):",
            fenced("json", compact_json(single)),
            field_table(DEMONSTRATION),
            field_table(STEP),
            field_table(GEOMETRY),
            "A landmark is a pose, and optionally the thing's `shape` and `size` "
            "(in demonstrations and scenes alike: [scenes.md](scenes.md#landmarks)):",
            fenced(
                "json",
                '{"landmarks": {"tray": {"position": [0.45, 0.10, 0], "yaw": 30, '
                '"shape": "box", "size": [0.40, 0.30, 0.02]}}}',
            ),
            field_table(LANDMARK),
            "### A file of several demonstrations (`demoplan/demonstrations-1`)",
            "A file may hold several demonstrations in `demonstrations`, each a document as "
            "above. One without a `name` is called after the file and its place in it, "
            "counted from 1 (`demos-2`). `examples/blocks/demonstrations.json` "
            "(Experiment 2):",
            fenced("json", compact_json(collection)),
            field_table(COLLECTION),
        ]
    )


def stream_section() -> str:
    return blocks(
        [
            f"## {TITLES['stream']}",
            "Object poses over time, as a tracker or motion capture records them; "
            "`segment` turns one into a demonstration, and `learn` segments the streams it "
            "is given on the way (docs/segmentation.md). `segment` reads a path as a ROS 2 "
            "bag when it is a folder, a `.db3` or `.mcap` file or a bag's `metadata.yaml`, "
            "and as CSV otherwise; `learn` takes a `.csv`, `.db3` or `.mcap` file, a "
            "`metadata.yaml` or a folder holding one for a pose stream, and anything else "
            "for demonstrations.",
            "### CSV",
            "A header, then one row per object per sample. The header names the columns "
            "`t,object,x,y,z` — time in seconds, the object's name, its resting point in "
            "metres — plus optionally an orientation: `yaw`, or `roll,pitch,yaw` (degrees, "
            "extrinsic x-y-z), or `qx,qy,qz,qw`. Columns and rows may come in any order; "
            "blank lines and lines starting with `#` are skipped. An object without an "
            "orientation leaves the orientation cells of all its rows empty. Objects are "
            "sampled independently: each has its own times, and one object may not have "
            "two samples at the same time. The first rows of "
            "`examples/streams/set-table-1.csv` (Experiment 1's first demonstration as a "
            "tracker records it, 30 Hz):",
            fenced("csv", first_lines("examples/streams/set-table-1.csv", 8)),
            "**Units.** Positions are metres unless the stream says otherwise: a comment "
            "line `# units: mm` (or `cm`, `m`) above the header, or `--units mm` on "
            "`segment` and `learn`. Positions are converted to metres on reading. When "
            "both are given they must agree (a file that says mm read with `--units cm` "
            "is refused: one of the two is wrong, and a guess would be silent). A stream "
            f"without either whose positions reach beyond {PLAUSIBLE_METRES:g} m — a "
            "millimetre stream's hundreds and thousands — is refused in one line naming "
            "`units`, rather than segmented into no step of at least 2 cm; declare `# "
            "units: m` (or `--units m`) for a stream that truly spans more than a room.",
            fenced(
                "csv",
                "# units: mm\nt,object,x,y,z,yaw\n0.0,plate,148.9,201.2,0.7,0\n"
                "0.0,knife,97.3,350.9,-0.7,90",
            ),
            "A tracked frame that is a landmark (a tray the objects are put into, a box) "
            "is named with `--landmarks tray` (names or glob patterns, comma-separated, on "
            "`segment` and `learn`): it is no object; its first rest pose is written as "
            "the demonstration's landmark, and it must not be moved (a step of it is "
            "refused).",
            "### ROS 2 bag",
            "A bag in sqlite3 or mcap storage — its folder, its `.db3` or `.mcap` file, or "
            "its `metadata.yaml` — read with the `rosbags` library (no ROS installation "
            "needed), from its own folder: a file there that is a link leading out of the "
            "folder is refused, naming it. Two kinds of topic are read, others are ignored:",
            "- `tf2_msgs/msg/TFMessage` (`/tf`, and `/tf_static` — any topic of the type; "
            "one whose name ends in `tf_static` holds static transforms): a tree of "
            "frames, each posed in its parent. Each object's pose is composed to the world "
            "frame, by default the tree's root (`--frame` chooses another). The objects "
            "are by default the tree's leaves: frames other than the world frame with no "
            "children.\n"
            "- `geometry_msgs/msg/PoseStamped`, one topic per object, named by the topic's "
            "last part, or the one before it when the last is `pose` or `pose_stamped` "
            "(`/mocap/plate/pose` and `/plate` both name `plate`).",
            "A sample's time is its header stamp, or the time the bag received it when the "
            "stamp is zero. `--objects` keeps some objects, for CSV and bags alike: names "
            "or glob patterns, comma-separated (`'cup,plate'`, `'obj_*'`).",
        ]
    )


def recording_section() -> str:
    layout = "\n".join(
        [
            "demo.hdf5",
            "└── data                 attributes: env, repository_version (robosuite);",
            "    │                                env_args (robomimic, JSON with env_name)",
            "    ├── demo_1           attribute model_file: the MuJoCo model, as XML text",
            "    │   │                or as the name of a file in models/ beside the recording",
            "    │   └── states       one row per sample: time, qpos…, qvel… (, act…)",
            "    └── demo_2 …",
        ]
    )
    return blocks(
        [
            f"## {TITLES['recording']}",
            "An HDF5 file as robosuite (0.3 and 1.x) and robomimic record teleoperated "
            "demonstrations; `import` reads it and writes one demonstration file per "
            "demonstration in it, named `<name>-<key>.json`: the name is `--name-prefix`, "
            "or the file's stem, or the environment when the stem says nothing (`demo`, "
            "`low_dim`), reduced to a safe file name (no `/`, `..` or control character: "
            '[limits.md](limits.md), "Recordings"). A recording must be self-contained: '
            "external links, external storage and virtual datasets are refused.",
            fenced("text", layout),
            "The model is read as XML, not compiled (recordings ship without their "
            "meshes). The objects are its free-jointed bodies, named without robosuite's "
            "instance suffix (`Milk0` → `Milk`); their poses over time come from the "
            "states and are segmented like a pose stream. The table top becomes z = 0. "
            "Static bodies that collide (bins, pegs) become landmarks. A `states` table "
            "whose width does not match the model is refused; samples whose time does not "
            "increase are dropped. docs/segmentation.md says how each of these is found.",
            "### `import --json`",
            "A summary on stdout:",
            table(
                ("field", "type", "meaning"), [(code(k), *v) for k, v in IMPORT_JSON.fields.items()]
            ),
            "Each entry of `demonstrations`:",
            table(
                ("field", "type", "meaning"),
                [(code(k), *v) for k, v in IMPORTED_JSON.fields.items()],
            ),
        ]
    )


def objects_section() -> str:
    geometry = {"objects": example_file("examples/set_table/demonstration-1.json")["objects"]}
    return blocks(
        [
            f"## {TITLES['objects']}",
            "The geometry of a stream's objects, for `segment --objects-file`, `learn "
            "--objects-file` (the pose streams it segments) and `import --objects-file`: a "
            "demonstration's `objects` (and `units`) alone. Every name must be an object "
            "(or a tracked landmark) of the streams — for `import`, an object or landmark "
            "of the recording — and every object that moves must have a geometry; it is "
            "written into the demonstration, so that learning knows a plate is round (a "
            "cylinder's yaw is taken modulo any turn, docs/learning.md). `import` adds it "
            "to the recording's own geometry, replacing it where both name an object. "
            "`learn` refuses it without a pose stream among its inputs: demonstration "
            "files carry their own `objects`. An entry's `type` declares identical objects "
            "(two tracked plates of type `plate`): it is written into the demonstration "
            "too ([learning.md](learning.md#identical-objects)), and so is an entry's "
            "`colour` (an object's or a tracked landmark's). JSON or YAML. The geometry of "
            "`examples/set_table/demonstration-1.json`:",
            fenced("json", compact_json(geometry)),
            field_table(OBJECTS_FILE),
        ]
    )


def requirements_section() -> str:
    return blocks(
        [
            f"## {TITLES['requirements']}",
            "Teacher constraints for `learn --require-file`, as `--require` takes them: one "
            "`X<Y` per line, X to come before Y, each a state id, a visit label (`C#2`) or "
            "an object name. A `#` at the start of a line or after a space starts a comment "
            "(`C#2` is a label); blank lines are skipped. UTF-8 text.",
            fenced(
                "text",
                "# the plate goes down before anything is put on it\n"
                "plate<napkin\nplate<food  # the food too",
            ),
        ]
    )


def scene_section() -> str:
    return blocks(
        [
            f"## {TITLES['scene']}",
            f"The world at run time, read by {listed(users('scene', 0))}; `perceive` writes "
            "one, and `run --json` reports the world at the end as one. Object names "
            "appear in plans, so they have no spaces and are not `loc`, `freespace` or "
            "`grasp` followed by digits (the names demoplan gives locations and grasps). "
            "An object with z > 0 stands on what is under it; no object lies under the "
            "table top (z below −5 mm) nor inside another object or a landmark's body "
            "(a landmark with a size is solid, unless things stood inside it in the "
            "demonstrations: a bin), and free-space spots lie on the table. The model's "
            "objects must all be in the scene, and its landmarks under `landmarks`; "
            "objects the model never saw are refused "
            "unless planning is told to move them out of the way (`--clutter`). "
            "docs/scenes.md says how a scene becomes a planning problem.",
            f"`{PYRAMID}` (Experiment 2 at run time: red stands on green and wood):",
            fenced("json", (ROOT / PYRAMID).read_text(encoding="utf-8")),
            field_table(SCENE),
            field_table(SCENE_OBJECT),
            field_table(GRIPPER),
            field_table(TABLE),
            field_table(ROBOT),
        ]
    )


STUDIO_OBJECTS_EXAMPLE = """{
  "format": "demoplan/objects-1",
  "objects": {
    "sandwich": {"shape": "box", "size": [0.1, 0.1, 0.03], "position": [0.08, 0.08, 0.0],
                 "yaw": 0.0, "colour": "#d9a441", "mass": 0.15},
    "cookie": {"shape": "cylinder", "size": [0.05, 0.05, 0.01], "position": [0.5, 0.055, 0.0],
               "yaw": 0.0, "colour": "#7f5539", "type": "biscuit"}
  },
  "landmarks": {
    "lunchbox": {"shape": "box", "size": [0.26, 0.18, 0.02], "position": [0.45, 0.4, 0.0],
                 "yaw": 0.0, "colour": "#2e86c1"}
  }
}"""
"""An objects file as the studio writes it (the lunch box of
tests/studio/test_studio_own_objects_browser.py, shortened); tests/studio/test_studio_objects.py
reads it from formats.md with the objects file's reader."""


def studio_objects_section() -> str:
    return blocks(
        [
            f"## {TITLES['studio_objects']}",
            "The things of a task of your own, as the studio's **Save objects** writes "
            'them and its Teach view starts from (docs/studio.md, "Your own objects"): '
            f"a {link('scene', 'scene')} — every object with its `shape`, `size`, `colour`, "
            "`mass` or `density`, `type` and where it stands at the start; every landmark "
            "with its `shape`, `size`, `colour` and pose (the colours chosen in the page). It "
            "is read by the scene reader, so every field means and is checked as in a scene "
            "(a colour too), and every object must give its `size`. Every command "
            "that reads a scene (`show`, `plan`, `problem`, `export`, `run`, `evaluate`) "
            "reads an objects file as the scene it starts from, in its colours; the "
            "studio's **Save scene** writes a scene, with the start as its Plan view shows "
            "it and every thing's colour. A lunch box "
            "(tests/studio/test_studio_own_objects_browser.py), shortened:",
            fenced("json", STUDIO_OBJECTS_EXAMPLE),
        ]
    )


def markers_section() -> str:
    return blocks(
        [
            f"## {TITLES['markers']}",
            "ArUco or AprilTag markers lying flat on the table, for `calibrate --markers` "
            "and `perceive --markers`: the OpenCV dictionary they come from, the side of "
            f"their black square (m, at most {number(MAX_MARKER_SIDE)}) and where each id "
            "lies on the table — its centre `[x, y]` in the scene's coordinates (m), or "
            "`[x, y, yaw]` with the marker turned yaw degrees (0: the top of the marker's "
            "pattern faces +y). Markers found in the image whose ids the file does not "
            "list are ignored; at least one listed marker (four corners) must be seen, "
            "and more give a better fit. JSON or YAML; `format` may be left out. "
            "`examples/perception/markers.json`:",
            fenced("json", (ROOT / "examples/perception/markers.json").read_text().strip()),
            field_table(MARKERS_FILE),
        ]
    )


def palette_section() -> str:
    from demoplan.perception.palette import MAX_PALETTE_COLOURS, PALETTE

    built_in = ", ".join(f"`{name}`" for name in PALETTE)
    return blocks(
        [
            f"## {TITLES['palette']}",
            "Colours for `perceive --colours` to name blocks by, besides the built-in "
            f"ones ({built_in}): a JSON object — YAML with a `.yaml` / `.yml` name — "
            "mapping a name to the block's colour as the camera sees its top face, "
            "`[R, G, B]` in 0–255 (measure it on a picture: the mean of the top face, "
            "not of a highlight or a shadow). Only the hue counts: the colour is kept "
            "as RGB divided by its largest channel, so a block in shade is still named; "
            "a block is named by the nearest colour of the palette, and a block farther "
            "than 0.3 from every one is `block1`, `block2`… A built-in name moves that "
            'colour (`"wood": [200, 140, 90]` for a darker wood). '
            "`examples/perception/colours.json`:",
            fenced("json", (ROOT / "examples/perception/colours.json").read_text().strip()),
            table(
                ("field", "type", "meaning"),
                [
                    (
                        "a name",
                        "letters, digits and `_`, not starting with a digit or `block`",
                        "The blocks' name (`pink`, then `pink2`…) and type.",
                    ),
                    (
                        "its value",
                        "3 numbers in 0–255, not all 0",
                        "The top face's colour, `[R, G, B]`.",
                    ),
                ],
            ),
            f"At most {MAX_PALETTE_COLOURS} colours. Anything else is one error line "
            "naming the file and the colour (exit 1, docs/limits.md); so are NaN, a "
            "name given twice and a file that is not JSON.",
        ]
    )


def camera_section() -> str:
    return blocks(
        [
            f"## {TITLES['camera']}",
            "What `calibrate` writes and `perceive --camera` reads: the homography from "
            "the image's pixels to the table, the size of the images it is for (another "
            "size is refused), how well it fits the markers, and, when known, the "
            "camera's intrinsics and centre. The camera centre is recomputed from the "
            "homography (and the intrinsics) when the file is read. A camera file may "
            "also be written by hand from another calibration: the homography alone is "
            "enough, without a camera centre nothing is corrected for the blocks' "
            "height (docs/perception.md). `--intrinsics` (for `calibrate`) reads the "
            "intrinsics fields below from a JSON or YAML file of their own.",
            field_table(CAMERA_FILE),
            field_table(REPROJECTION),
            field_table(USED_MARKERS),
            field_table(INTRINSICS),
            field_table(CAMERA_CENTRE),
        ]
    )


def model_section(computed: Computed) -> str:
    return blocks(
        [
            f"## {TITLES['model']}",
            "What `learn` writes; `show`, `plan`, `problem`, `run` and `learn --update` "
            "read it. A state is an object at a place: its position and its orientation, "
            "each absolute or relative to a reference (another object, or a landmark), "
            "the two chosen independently. A state visited again in one demonstration "
            "gets a visit label (`C#2`) in `sequences` and `goals`. Every id in "
            "`sequences`, `constraints`, `goals`, `teacher_constraints` and `violations` "
            "must be a state; every reference must be an object or landmark of the "
            "demonstrations; there is one goal per sequence, and, when `demonstrations` "
            "is given, one demonstration per sequence. docs/learning.md says how each "
            "value is computed.",
            f"The model `learn {BLOCKS} --paper` writes (the paper's Table IV), without its "
            "`demonstrations`, numbers rounded to 6 decimals:",
            fenced("json", compact_json(rounded(computed.model))),
            field_table(MODEL),
            field_table(STATE),
            field_table(STATE_POSITION),
            field_table(STATE_ORIENTATION),
            field_table(VIOLATION),
            field_table(PRECISION),
            field_table(ROLE),
            field_table(SETTINGS),
        ]
    )


def problem_section() -> str:
    elements = [
        (
            '`<problem name="…">`',
            "the root; `name` is optional (default: the file name without extension)",
        ),
        (
            '`<object name="N" type="T"/>`',
            "declares a name: `T` is `Object`, `Location` or `Grasp` (any case). Names "
            'have no spaces and are declared once. A `Location` may say `freespace="true"` '
            'or `"false"`; without it, a location whose name starts with `freespace` is '
            "free space",
        ),
        ("`<state>`", 'exactly one: the facts at the start, one `<arg name="…"/>` each'),
        ("`<goal>`", "at most one: the facts that must hold at the end"),
    ]
    facts = [
        (
            "`OBJ LOC`",
            "state",
            "OBJ stands at LOC; every object at one location, one object per location",
        ),
        ("`OBJ GRASP`", "state", "GRASP may be used on OBJ"),
        (
            "`LOCA LOCB GRASP`",
            "state",
            "GRASP cannot be used at LOCA while another object stands at LOCB (a collision fact)",
        ),
        ("`hand-empty`", "state", "required: the hand starts empty"),
        (
            "`support UPPER LOWER`",
            "state",
            "UPPER holds an object only while LOWER is "
            "occupied, and the object at LOWER cannot be grasped while UPPER is",
        ),
        ("`exclusive LA LB`", "state", "overlapping places: not both occupied"),
        ("`accepts LOC OBJ`", "state", "LOC holds only the objects named with it"),
        ("`reached ID`", "state", "subgoal ID was reached before (replanning)"),
        ("`OBJ LOC`", "goal", "OBJ must end at LOC"),
        ("`subgoal ID OBJ LOC`", "goal", "OBJ must be put down at LOC"),
        ("`before ID1 ID2`", "goal", "subgoal ID2 only after subgoal ID1"),
    ]
    return blocks(
        [
            f"## {TITLES['problem']}",
            "The paper's problem format (§IV.C): `problem` writes one for a candidate goal "
            "of a task model in a scene; `solve` and `pddl` read it. It is read with "
            "`defusedxml`: DTDs, entity declarations and external references are refused. "
            "The facts are given by the names they relate; the kinds of those names tell "
            "the facts apart. A file in the paper's form needs none of the extensions "
            "(`support` to `before`); `problem` writes them where the scene needs them. "
            "docs/planning.md has what a plan must satisfy.",
            table(("element", "content"), elements),
            table(("arg", "in", "meaning"), facts),
            f"`{PAPER_PROBLEM}`, the paper's example with the declarations its “…” stands for:",
            fenced("xml", (ROOT / PAPER_PROBLEM).read_text(encoding="utf-8")),
        ]
    )


def plan_section(computed: Computed) -> str:
    plan = computed.plan_json
    candidate = first(plan["candidates"], "candidate")
    subgoal = first(plan["subgoals"], "subgoal")
    location = first(list(plan["locations"].values()), "location")
    return blocks(
        [
            f"## {TITLES['plan']}",
            "### Text",
            "`solve` prints a plan in the paper's notation, one action per line: "
            "`GRASP OBJECT LOCATION GRASP` takes the object from the location with that "
            "grasp, `PUT_DOWN OBJECT LOCATION GRASP` puts it down there. stderr says "
            "whether the plan is proved shortest. For "
            f"`{PAPER_PROBLEM}`:",
            fenced("text", computed.solve_text),
            f"and on stderr `{computed.solve_note}`. `plan` prints the same lines between "
            "two tables for reading (the candidate goals, the locations used); a program "
            "reads `--json`.",
            "### `solve --json`",
            table(
                ("field", "type", "meaning"), SOLVE_JSON.rows(computed.solve_json, "solve --json")
            ),
            f"For `{PAPER_PROBLEM}`, without the timings:",
            fenced("json", compact_json(untimed(computed.solve_json))),
            "### `plan --json`",
            "The chosen plan, as `solve --json` gives it, with every candidate goal and "
            "what the names of the chosen problem stand for. `goal` counts demonstrations "
            "from 0; `plan` without `--json` numbers them from 1.",
            table(("field", "type", "meaning"), PLAN_JSON.rows(plan, "plan --json")),
            "Each entry of `candidates`:",
            table(
                ("field", "type", "meaning"),
                CANDIDATE_JSON.rows(candidate, "plan --json candidates"),
            ),
            "Each entry of `subgoals`:",
            table(("field", "type", "meaning"), SUBGOAL_JSON.rows(subgoal, "plan --json subgoals")),
            "Each value of `locations`:",
            table(
                ("field", "type", "meaning"),
                LOCATION_JSON.rows(location, "plan --json locations"),
            ),
            f"`plan` of the model above in `{PYRAMID}`, without the timings (the goal of "
            'demonstration 2, `"goal": 1`, takes 4 moves, that of demonstration 1 five):',
            fenced("json", compact_json(untimed(plan))),
        ]
    )


def run_section(computed: Computed) -> str:
    report = computed.run_json
    faults = ",".join(
        f"{kind}={getattr(RUN_FAULTS, kind):g}" for kind in FAULT_KINDS if getattr(RUN_FAULTS, kind)
    )
    return blocks(
        [
            f"## {TITLES['run']}",
            "`run --json` prints what happened when the task was carried out in "
            "simulation (docs/execution.md). `run` exits 0 when the goal was reached, 3 "
            "when no plan exists from the observed world and 4 when it gave up (a limit).",
            table(("field", "type", "meaning"), RUN_JSON.rows(report, "run --json")),
            "Each entry of `failures`:",
            table(
                ("field", "type", "meaning"),
                FAILURE_JSON.rows(first(report["failures"], "failure"), "run --json failures"),
            ),
            "Each entry of `injected` (what the simulation did; the failures are what "
            "the executor saw — a fault that changes nothing the executor checks, such as "
            "a drop that lands on the target, is injected but not a failure):",
            table(
                ("field", "type", "meaning"),
                INJECTED_JSON.rows(
                    first(report["injected"], "injected fault"), "run --json injected"
                ),
            ),
            "The kinds of failure:",
            table(("kind", "seen when"), [(code(k), v) for k, v in FAILURE_KINDS.items()]),
            "Each entry of `steps`:",
            table(
                ("field", "type", "meaning"),
                STEP_JSON.rows(first(report["steps"], "step"), "run --json steps"),
            ),
            "`--faults` injects failures: `KIND=PROBABILITY,…` with the kinds "
            + ", ".join(code(k) for k in FAULT_KINDS)
            + ". The report of `run` with the model above in "
            f"`{PYRAMID}`, `--faults {faults} --seed {RUN_SEED}`, without its timing, "
            "numbers rounded to 6 decimals:",
            fenced("json", compact_json(untimed(report))),
        ]
    )


def tree_section(computed: Computed) -> str:
    lines = computed.tree_xml.splitlines()
    closing = " " * 6 + "</Fallback>"  # the end of the first subgoal
    end = next(i for i, line in enumerate(lines) if line.startswith(closing))
    excerpt = "\n".join([*lines[: end + 1], "      …"])
    vocabulary = [
        (
            code(node.id),
            f"{code(node.leaf)} ({node.leaf_kind.lower()})",
            escape(node.description),
            ", ".join(
                code(p.name) + (" (out)" if p.kind == "output_port" else "") for p in node.ports
            ),
        )
        for node in NODES
    ]
    ports = {p.name: p for node in NODES for p in node.ports}
    return blocks(
        [
            f"## {TITLES['bt']}",
            "`export bt MODEL SCENE -o TASK.xml` writes the plan chosen in the scene as a "
            "[BehaviorTree.CPP](https://www.behaviortree.dev/) v4 tree: the main tree `Task` "
            "is a `Sequence` with, per subgoal in the plan's order (which honours the learned "
            "constraints), a `Fallback` whose first child checks the object is already at its "
            "target (`IsAt`) and whose second carries it there (`MoveToFree` for each object "
            "the plan parks first, unless an `IsAt` finds it still parked, then `Grasp` and "
            "`PutDown`), inside a "
            f'`RetryUntilSuccessful num_attempts="{ATTEMPTS}"`; when the attempts are spent '
            "a `Script` names the subgoal on the blackboard and the tree fails. A last "
            "`Sequence`, `the goal holds`, checks every goal object and puts back one a person "
            "moved. `--plan-only` writes the plan's flat `Sequence` of `Grasp` and `PutDown`. "
            'docs/execution.md, "Behaviour trees".',
            "The vocabulary is four `SubTree` models, declared with their ports in "
            "`TreeNodesModel`; each holds one leaf, declared there too, that reads its ports "
            "from its subtree's blackboard (a robot's runtime registers the four leaves; "
            "`run --bt` binds them to the simulation):",
            table(("node", "leaf", "does", "ports"), vocabulary),
            "The ports (values are text, numbers in metres and degrees, world frame):",
            table(
                ("port", "type", "meaning"),
                [(code(name), code(p.type), escape(p.description)) for name, p in ports.items()],
            ),
            "Every node remaps `failure` and `failure_detail` to the main tree's blackboard; "
            "when the tree fails, `failure` is one of the run report's failure kinds "
            f"([above](#{slug(TITLES['run'])})), `failure_detail` what was seen and "
            "`failed_subgoal` the subgoal given up. The first subgoal of the tree that "
            f"`export bt` writes for the model above in `{PYRAMID}`:",
            fenced("xml", excerpt),
            "`run --bt` reads a tree file of its own making as strictly as a scene file "
            "(src/demoplan/execution/tree_checks.py) before the engine sees it, and refuses in "
            "one line (exit 1): anything under the root but `BehaviorTree` and "
            "`TreeNodesModel` (`include` is never followed); a `SubTree` naming a tree the file "
            "does not define, or trees that reach themselves through `SubTree` references; "
            "node types other than "
            + ", ".join(code(name) for name in sorted(NODE_TYPES))
            + "; `Script` code other than `name:='text'` and the engine's scripted attributes "
            f"(`_skipIf`, `_onSuccess`, …); retry and repeat counts outside 1 … {MAX_ATTEMPTS}; "
            "on the vocabulary's nodes, unknown ports, input values in braces (the engine "
            "would read them as blackboard entries), positions farther than "
            f"{MAX_DISTANCE_M:g} m, angles beyond {MAX_ANGLE:g}°, tolerances not above 0 or "
            f"above {MAX_TOLERANCE_M:g} m / 180°. A run stops after {MAX_TICKS:,} ticks "
            "(exit 4) or its run's limit of actions.",
        ]
    )


def _figure(command: str) -> bool:
    """Is this a matplotlib figure (not a PNG drawn on a camera image)?"""
    return "--plot" in command and not command.strip("`").startswith(("calibrate", "perceive"))


def other_section() -> str:
    figures = ", ".join(f"`.{suffix}`" for suffix in sorted(FIGURE_FORMATS))
    return blocks(
        [
            f"## {TITLES['other']}",
            "- **Camera image** (`perceive IMAGE`, `calibrate IMAGE`): a colour image of "
            "the table (PNG, or any image Pillow reads). A top-down orthographic one with "
            "`--px-per-m` pixels per metre and `--origin X Y` the world x and y of its "
            "bottom-left corner, image right = world x, image up = world y; or any view "
            "with `--camera` or `--markers` (above). `calibrate --plot` draws the markers "
            "found and a 5 cm grid of the table on it, `perceive --plot` the blocks found "
            'and the regions rejected, and why (docs/perception.md, "Overlays"); both '
            "write a PNG whatever the name's extension. `perceive` names each block by "
            "its colour (`red`; a second red block `red2`; a colour without a name `block1`, "
            "`block2`…) and writes two or more blocks of one named colour as instances "
            'of one type, `"type": "red"` (docs/perception.md).\n'
            "- **Camera frames** (`perceive --sequence FRAME…`): the frames of one "
            "demonstration filmed from above — image files in the order given, or one video "
            f"file ({', '.join(sorted(VIDEO_SUFFIXES))}; read with imageio-ffmpeg, the `sim` "
            "extra), each frame the size of the first; `-o` writes the demonstration file "
            '(docs/perception.md, "Demonstrations from a camera").\n'
            f"- **Figures** ({', '.join(c for c in users('other', 1) if _figure(c))}): "
            "the extension chooses the "
            f"format: {figures}.\n"
            "- **Frames** (`run --frames DIR`): `frame-0000.png`, `frame-0001.png`, … (the "
            "world from above after each action), `storyboard.png` and the manifest; an "
            "earlier run's folder is replaced whole.\n"
            "- **Manifest** (`.demoplan-manifest.json` in a `run --frames` or "
            "`experiments --out` folder): `format` `demoplan/manifest-1`, `written_by` "
            "(the command), `files` (each file's path in the folder: its SHA-256) and "
            "`folders`. It is what lets a later run replace the folder: a folder holding "
            "anything it does not list, or a listed file changed, is refused, never "
            'removed (docs/limits.md, "Outputs").\n'
            "- **PDDL** (`pddl PROBLEM.xml -o DIR`: `DIR/domain.pddl` and "
            "`DIR/problem.pddl`; `problem --pddl -o FILE`: `FILE` and "
            "`FILE-domain.pddl`, the extension of FILE replaced): the problem for any "
            "PDDL planner, lifted, or grounded STRIPS with `--grounded`; with identical "
            "objects, the planner binds the roles (below). docs/planning.md.\n"
            "- **Report** (`experiments --out DIR`): `report.md`, `report.html` (one "
            "self-contained page) and `summary.json`, with the figures and models the "
            "report shows, and the manifest; an earlier report's folder is replaced whole.",
            *pddl_roles_excerpt(),
        ]
    )


def pddl_roles_excerpt() -> list[str]:
    """What ``problem --pddl`` writes where the model has roles of identical objects,
    from the export itself (two cups into a tray's two slots), and a plan of it
    checked by demoplan's rules."""
    from demoplan.planning.pddl import Roles, plan_from_pddl, problem_to_pddl
    from demoplan.planning.problem import Problem, Subgoal
    from demoplan.planning.strips import validate

    problem = Problem.create(
        objects=["cup-a", "cup-b", "tray"],
        locations=["loc1", "loc2", "loc3", "loc4", "loc5"],
        grasps=["grasp1", "grasp2", "grasp3"],
        allowed=[("cup-a", "grasp1"), ("cup-b", "grasp2"), ("tray", "grasp3")],
        initial=[("cup-a", "loc1"), ("cup-b", "loc2"), ("tray", "loc3")],
        goal=[("cup-a", "loc4"), ("cup-b", "loc5")],
        supports=[("loc4", "loc3"), ("loc5", "loc3")],
        subgoals=[Subgoal("A", "cup-a", "loc4"), Subgoal("B", "cup-b", "loc5")],
        name="goal-1",
    )
    roles = Roles({"cup-a": "cup", "cup-b": "cup"}, {"cup-a": "cup#1", "cup-b": "cup#2"})
    domain, text = problem_to_pddl(problem, roles=roles)
    types = re.search(r"  \(:types.*?\)\n", domain, re.S)
    bind = re.search(r"  \(:action bind\n.*?\n    \)\)\n", domain, re.S)
    objects = re.search(r"  \(:objects\n.*?\n  \)\n", text, re.S)
    goal = re.search(r"  \(:goal.*?\)\)\n", text, re.S)
    assert types and bind and objects and goal, "the PDDL export changed: update the excerpt"
    plan = [
        "(bind cup-a cup-2 loc1 cup-b)",
        "(bind cup-b cup-1 loc2 cup-b)",
        "(grasp cup-b loc2 grasp2 cup-1)",
        "(put-down-reaching cup-b loc4 grasp2 cup-1 a)",
        "(grasp cup-a loc1 grasp1 cup-2)",
        "(put-down-reaching cup-a loc5 grasp1 cup-2 b)",
    ]
    actions, binding = plan_from_pddl(problem, plan, roles)
    validate(roles.rebind(problem, binding), actions)  # the plan shown is one
    return [
        "**PDDL with identical objects.** Where the model has roles (`cup#1`, "
        "`cup#2`: docs/planning.md) and the scene more than one way to fill them, "
        "`problem --pddl` does not fix which instance goes where: each type is a PDDL "
        "type under `item` holding its instances and its roles, subgoals and the goal "
        "name roles, and a plan starts with one `bind INSTANCE ROLE LOCATION NEXT` per "
        "instance (in turn; an instance may bind to itself and stand spare), then moves "
        "roles by the instances playing them: `(grasp INSTANCE LOCATION GRASP ROLE)`. "
        "So an optimal plan has one bind per instance and as many moves as `plan` "
        "finds over every binding. `--grounded` writes the same binds and moves out per "
        "instance and role (`bind__cup-a__cup-2`, `grasp__cup-b__loc2__grasp2__cup-1`). "
        "A goal whose targets depend on the binding (a state placed anywhere, where its "
        "instance stands) is refused (exit 2). Two cups into a tray's slots — the "
        "domain's types and "
        "`bind`, the problem's objects and goal:",
        fenced("lisp", types.group() + bind.group() + objects.group() + goal.group()),
        "and an optimal plan (`demoplan.planning.pddl.plan_from_pddl` reads it back: "
        "the moves, and the binding cup#1=cup-b, cup#2=cup-a):",
        fenced("lisp", "\n".join(plan)),
    ]


# ----------------------------------------------------------------------------- cli.md

COMMAND_FILES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "learn": (
        (
            "demonstration",
            "stream",
            "objects --objects-file",
            "requirements --require-file",
            "model --update",
        ),
        ("model",),
    ),
    "show": (("model", "scene", "studio_objects"), ("other --plot",)),
    "solve": (("problem",), ("plan",)),
    "pddl": (("problem",), ("other",)),
    "plan": (("model", "scene", "studio_objects"), ("plan", "other --plot")),
    "problem": (("model", "scene", "studio_objects"), ("problem", "other --pddl")),
    "export": (("model", "scene", "studio_objects"), ("bt",)),
    "run": (("model", "scene", "studio_objects", "bt --bt"), ("run --json", "other --frames")),
    "evaluate": (("model", "scene", "studio_objects"), ("scene --out", "other --out")),
    "calibrate": (
        ("other", "markers --markers", "camera --intrinsics"),
        ("camera -o", "other --plot"),
    ),
    "perceive": (
        ("other", "camera --camera", "markers --markers", "palette --colours"),
        ("scene", "other --plot", "demonstration --sequence"),
    ),
    "segment": (("stream", "objects --objects-file"), ("demonstration", "other --plot")),
    "import": (("recording", "objects --objects-file"), ("demonstration",)),
    "experiments": ((), ("other",)),
}
"""Per command, what it reads and what it writes: the formats.md sections (keys of
:data:`TITLES`), each with the option that asks for it where one does."""

EXIT_CODES: tuple[tuple[int, str, str], ...] = (
    (
        0,
        'success; a plan found but not proved shortest is a success (`"optimal": false` '
        "and its lower bound in `--json`)",
        "—",
    ),
    (
        InputError.exit_code,
        "bad input: a file, a field or a value is not what was expected; "
        "one line on stderr names the file, the field and what was expected",
        "`InputError`",
    ),
    (
        UsageError.exit_code,
        "usage error: an unknown command or option, a missing argument, a "
        "value of the wrong type or out of range",
        "`UsageError`; the parser's own",
    ),
    (
        NoPlanError.exit_code,
        "no plan exists, with the reason (which goal objects cannot be reached, and why)",
        "`NoPlanError`",
    ),
    (
        LimitReachedError.exit_code,
        "a search or time limit was reached without a plan (with "
        "`--optimal`: without a proof); `run`: it gave up after `--max-replans` replans or too "
        "many actions",
        "`LimitReachedError`",
    ),
    (
        INTERRUPTED_EXIT,
        "stopped by Ctrl-C (SIGINT), within a second, leaving no partial output file",
        "—",
    ),
    (TERMINATED_EXIT, "stopped by SIGTERM, the same way", "—"),
)


def cli_page() -> str:
    root = typer.main.get_command(app)
    if not isinstance(root, typer.core.TyperGroup):
        raise SystemExit("docs/generate.py: demoplan.cli.app is not a group of commands")
    context = root.context_class(root, info_name="demoplan")
    commands = [(name, root.get_command(context, name)) for name in root.list_commands(context)]
    summary = [
        (f"[`{name}`](#{slug(f'demoplan {name}')})", escape(command.get_short_help_str(10_000)))
        for name, command in commands
        if command is not None and not command.hidden
    ]
    usage_errors = typer.BadParameter.exit_code
    if usage_errors != UsageError.exit_code:
        raise SystemExit("docs/generate.py: typer's usage errors no longer exit 2")
    sections = [
        "# Command line",
        paragraphs(root.help or ""),
        "`demoplan COMMAND …`, or `python -m demoplan COMMAND …`. `--json` output goes to "
        "stdout and nothing else does; a file that is not what was expected ends the "
        "command with one line on stderr and the exit code below. File formats: "
        "[formats.md](formats.md). " + GENERATED,
        table(("command", "does"), summary),
        "## Global options",
        "Given before the command (`demoplan -v learn …`); every command also takes "
        + ", ".join(code(name) for name in context.help_option_names)
        + ", which prints its help.",
        options_table(root.params),
    ]
    for name, command in commands:
        if command is None or command.hidden:
            continue
        sections.append(command_section(name, command, context))
    sections += [
        "## Exit codes",
        table(
            ("code", "meaning", "raised as"),
            [(str(c), meaning, raised) for c, meaning, raised in sorted(EXIT_CODES)],
        ),
    ]
    return blocks(sections) + "\n"


def paragraphs(text: str) -> str:
    """A help text's paragraphs as markdown (lines within one joined)."""
    blocks = [" ".join(block.split()) for block in re.split(r"\n\s*\n", text.strip())]
    return "\n\n".join(escape(block) for block in blocks if block)


def command_section(name: str, command: Any, parent: Any) -> str:
    context = command.context_class(command, info_name=name, parent=parent)
    params = [p for p in command.get_params(context) if not getattr(p, "hidden", False)]
    arguments = [p for p in params if p.param_type_name == "argument"]
    options = [p for p in params if p.param_type_name == "option" and not p.is_eager]
    parts = [
        f"## `demoplan {name}`",
        paragraphs(command.help or ""),
        fenced("text", usage(name, arguments, options)),
    ]
    reads, writes = COMMAND_FILES.get(name, ((), ()))

    def listed(entries: Sequence[str]) -> str:
        words = []
        for entry in entries:
            key, _, option = entry.partition(" ")
            shown = link(key, SHORT_TITLES.get(key), page="formats.md")
            words.append(shown + (f" ({code(option)})" if option else ""))
        return ", ".join(words) + "."

    files = []
    if reads:
        files.append("Reads: " + listed(reads))
    if writes:
        files.append("Writes: " + listed(writes))
    if files:
        parts.append(" ".join(files))
    if arguments:
        rows = [
            (
                code(argument_name(p)),
                value_type(p) + ("" if p.required else ", optional"),
                escape(p.help or ""),
            )
            for p in arguments
        ]
        parts.append(table(("argument", "type", "meaning"), rows))
    if options:
        parts.append(options_table(options))
    return blocks(parts)


def options_table(params: Sequence[Any]) -> str:
    rows = [
        (option_names(p), value_type(p), default_text(p), escape(p.help or ""))
        for p in params
        if not getattr(p, "hidden", False)
    ]
    return table(("option", "type", "default", "meaning"), rows)


def argument_name(param: Any) -> str:
    name = str(param.metavar or param.name.upper())
    return name + "..." if param.nargs == -1 else name


def option_names(param: Any) -> str:
    """``-o``, ``--output``: short names first, as ``--help`` shows them."""
    names = sorted(param.opts, key=lambda opt: opt.startswith("--"))
    text = ", ".join(code(opt) for opt in names)
    if param.secondary_opts:
        text += " / " + ", ".join(code(opt) for opt in param.secondary_opts)
    return text


def value_words(param: Any) -> list[str]:
    """The kind of each value a parameter takes: ``["number", "number"]`` for ``--origin``."""
    descriptor = getattr(param, "type_descriptor", None)
    if descriptor is not None:
        return annotation_words(descriptor.annotation)
    # a click ParamType: typer before it carried type descriptors of its own
    kind = param.type
    choices = getattr(kind, "choices", None)
    if choices:
        return [" or ".join(code(str(choice)) for choice in choices)]
    return [str(kind.name)] * max(param.nargs, 1)


def annotation_words(annotation: Any) -> list[str]:
    origin, args = get_origin(annotation), get_args(annotation)
    if origin is list and len(args) == 1:
        return annotation_words(args[0])
    if origin is tuple:
        return [word for arg in args for word in annotation_words(arg)]
    if isinstance(annotation, type) and issubclass(annotation, Enum):
        return [" or ".join(code(str(member.value)) for member in annotation)]
    words: dict[Any, str] = {Path: "path", int: "integer", float: "number", str: "text"}
    if annotation not in words:
        raise SystemExit(f"docs/generate.py: cannot describe the option type {annotation!r}")
    return [words[annotation]]


def value_type(param: Any) -> str:
    """The value a parameter takes, in words, with its range."""
    if getattr(param, "is_flag", False):
        return "flag"
    text = " ".join(value_words(param))
    if param.metavar and param.param_type_name == "option":
        text = f"{code(param.metavar)}: {text}"
    kind = getattr(param, "type", None)
    low = getattr(param, "min", getattr(kind, "min", None))
    high = getattr(param, "max", getattr(kind, "max", None))
    if low is not None and high is not None:
        text += f", {number(low)} to {number(high)}"
    elif low is not None:
        text += f" ≥ {number(low)}"
    elif high is not None:
        text += f" ≤ {number(high)}"
    if param.nargs == -1:
        text += ", one or more"
    if param.multiple:
        text += ", repeatable"
    return text


def default_text(param: Any) -> str:
    if param.required:
        return "required"
    default = param.default
    if getattr(param, "is_flag", False):
        if param.secondary_opts:
            return code(param.opts[0] if default else param.secondary_opts[0])
        return "on" if default else "off"
    if default is None or default == [] or default == ():
        return "—"
    if isinstance(default, Enum):
        default = default.value
    if isinstance(default, float):
        return code(f"{default:g}")
    if isinstance(default, list | tuple):
        return code(" ".join(map(str, default)))
    return code(str(default))


def usage(name: str, arguments: Sequence[Any], options: Sequence[Any]) -> str:
    """``demoplan NAME ARGUMENTS REQUIRED-OPTIONS [OPTIONS]``."""
    words = ["demoplan", name]
    for param in arguments:
        shown = argument_name(param)
        words.append(shown if param.required else f"[{shown}]")
    for param in options:
        if param.required:
            values = [param.metavar] if param.metavar else value_words(param)
            words += [min(param.opts, key=len), *(v.upper() for v in values)]
    if any(not param.required for param in options):
        words.append("[OPTIONS]")
    return " ".join(words)


# ------------------------------------------------------------------------------- main

PAGES: dict[str, Callable[[], str]] = {"formats.md": formats_page, "cli.md": cli_page}


def pages() -> dict[str, str]:
    """Each generated page's name in docs/ and its text."""
    return {name: render() for name, render in PAGES.items()}


def stale(folder: Path, texts: Mapping[str, str]) -> list[str]:
    """The pages in ``folder`` that differ from ``texts`` (or are missing)."""
    out = []
    for name, text in texts.items():
        path = folder / name
        if not path.is_file() or path.read_bytes() != text.encode("utf-8"):
            out.append(name)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Write docs/formats.md and docs/cli.md.")
    parser.add_argument(
        "--check", action="store_true", help="write nothing; exit 1 if a page is out of date"
    )
    options = parser.parse_args(argv)
    texts = pages()
    if options.check:
        outdated = stale(DOCS, texts)
        for name in outdated:
            print(f"docs/{name} is out of date; run python docs/generate.py", file=sys.stderr)
        return 1 if outdated else 0
    for name, text in texts.items():
        (DOCS / name).write_bytes(text.encode("utf-8"))
        print(f"wrote docs/{name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
