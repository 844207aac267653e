"""Planning a learned task in a new scene (paper §IV.C, §V.B; docs/scenes.md).

- :mod:`~demoplan.scenes.scene`: the scene file (``demoplan/scene-1``);
- :mod:`~demoplan.scenes.targets`: each demonstrated goal as subtasks with target poses;
- :mod:`~demoplan.scenes.geometry`: footprints, grasps, collision facts, support, free space;
- :mod:`~demoplan.scenes.problems`: a candidate goal in a scene → a planning problem;
- :mod:`~demoplan.scenes.plan`: plan every candidate and choose the shortest.
"""
