"""Execution with failure detection and replanning (the paper's execution block).

- :mod:`~demoplan.execution.world`: what an executor needs of a world (a simulator);
- :mod:`~demoplan.execution.faults`: faults to inject (``--faults drop=0.2,...``);
- :mod:`~demoplan.execution.kinematic`: an exact, deterministic world;
- :mod:`~demoplan.execution.physics`: MuJoCo physics with a parallel-jaw gripper;
- :mod:`~demoplan.execution.executor`: plan, act, observe, replan;
- :mod:`~demoplan.execution.report`: the run's report, failures and events.
"""
