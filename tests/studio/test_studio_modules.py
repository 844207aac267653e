"""The studio page's ES modules import each other without a circle: the shared
stage (stage.js) asks the views it draws for through a registry
(``registerView``), and the views import the stage, never the reverse — so a
view loads alone, and no top-level use depends on the order of imports."""

from __future__ import annotations

import re
from pathlib import Path

import networkx as nx

STATIC = Path(__file__).resolve().parents[2] / "src" / "demoplan" / "studio" / "static"
VIEWS = ("teach.js", "learn.js", "plan.js", "run.js", "objects.js")

# `import {...} from "./x.js"` (over several lines too), `export {...} from "./x.js"`,
# `import "./x.js"` and `import("./x.js")`.
_IMPORT = re.compile(
    r"""(?:\b(?:import|export)\b[^;'"]*?\bfrom\s*|\bimport\s*\(?\s*)["']\./([\w.-]+\.js)["']"""
)


def module_imports(folder: Path) -> dict[str, set[str]]:
    """Each module of ``folder`` and the modules of ``folder`` it imports."""
    return {
        path.name: set(_IMPORT.findall(path.read_text(encoding="utf-8")))
        for path in sorted(folder.glob("*.js"))
    }


def circles(imports: dict[str, set[str]]) -> list[list[str]]:
    graph = nx.DiGraph((a, b) for a, targets in imports.items() for b in targets)
    graph.add_nodes_from(imports)
    return [sorted(c) for c in nx.simple_cycles(graph)]


def test_the_page_modules_import_no_circle() -> None:
    imports = module_imports(STATIC)
    assert {"stage.js", "studio.js", *VIEWS} <= set(imports)  # the page was found
    assert "stage.js" in imports["plan.js"]  # the imports were read
    assert not circles(imports), circles(imports)


def test_the_stage_imports_no_view() -> None:
    imports = module_imports(STATIC)
    assert not imports["stage.js"] & set(VIEWS), imports["stage.js"]
    for view in VIEWS:
        assert "stage.js" in nx.descendants(
            nx.DiGraph((a, b) for a, targets in imports.items() for b in targets), view
        ), f"{view} does not reach the stage"


def test_the_check_reads_every_form_of_import_and_finds_a_circle(tmp_path: Path) -> None:
    (tmp_path / "a.js").write_text(
        'import {\n  one,\n  two,\n} from "./b.js";\nexport { three } from "./c.js";\n',
        encoding="utf-8",
    )
    (tmp_path / "b.js").write_text('import "./d.js";\nconst m = import("./e.js");\n')
    (tmp_path / "c.js").write_text('import { a } from "./a.js";\n', encoding="utf-8")
    imports = module_imports(tmp_path)
    assert imports == {
        "a.js": {"b.js", "c.js"},
        "b.js": {"d.js", "e.js"},
        "c.js": {"a.js"},
    }
    assert circles(imports) == [["a.js", "c.js"]]
