"""``demoplan studio``: a local web application to teach, learn, plan and run a
task in the browser (the paper's virtual environment of Experiment 1, §V.A).

The server (:mod:`demoplan.studio.app`, served by :mod:`demoplan.studio.server`)
calls the command layer (:mod:`demoplan.commands`) as the command line does and
turns what it returns into JSON (:mod:`demoplan.studio.views`); the page lives in
``static/``. docs/studio-api.md describes the HTTP API.
"""

from __future__ import annotations

__all__: list[str] = []
