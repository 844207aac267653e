"""The studio's HTTP API, one :class:`~fastapi.APIRouter` per resource
(docs/studio-api.md): the templates, files and the Teach view's source
(:mod:`.files`); what happens on the table (:mod:`.table`); learning and
planning (:mod:`.learning`); runs, their media and the last run
(:mod:`.runs`). Each handler takes its request body and the work folder or the
runs as typed dependencies (:mod:`.depends`) and calls the command layer or
the studio's own layouts."""

from __future__ import annotations

from fastapi import APIRouter

from demoplan.studio.routes import files, learning, runs, table

ROUTERS: tuple[APIRouter, ...] = (files.router, table.router, learning.router, runs.router)
"""Every router of the API, in the order the application includes them."""

__all__ = ["ROUTERS"]
