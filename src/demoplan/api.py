"""The whole loop in three calls: ``learn``, ``plan``, ``run``.

>>> import demoplan
>>> model = demoplan.learn(["examples/blocks"], settings=demoplan.PAPER_SETTINGS)
>>> result = demoplan.plan(model, "examples/scenes/pyramid-fig4.json")
>>> [len(c.plan) if c.plan else None for c in result.candidates]  # 5 and 4 moves
[10, 8]
>>> report = demoplan.run(model, "examples/scenes/pyramid-fig4.json")
>>> report.success
True

Each takes paths or the objects they name; ``run`` drives a simulated world,
or — with ``world=`` — any object with the :class:`~demoplan.execution.world.World`
protocol: that is where a real robot plugs in (observe, grasp, put down).
They are the command layer's functions (:mod:`demoplan.commands`), which the
shell twins ``demoplan learn``, ``demoplan plan`` and ``demoplan run`` call too.
"""

from __future__ import annotations

from demoplan.commands.execution import run
from demoplan.commands.learning import learn_model as learn
from demoplan.commands.planning import plan

__all__ = ["learn", "plan", "run"]
