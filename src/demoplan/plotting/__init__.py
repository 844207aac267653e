"""Every figure demoplan draws, with matplotlib (imported lazily): the
demonstrations and their states, scenes and plans from above and from the
side (:mod:`~demoplan.plotting.figures`), the labels placed so that none
covers another (:mod:`~demoplan.plotting.labels`), one colour per object in
every figure and simulator (:mod:`~demoplan.plotting.colours`), and a
segmentation's speeds and heights (:mod:`~demoplan.plotting.segmentation`)."""
