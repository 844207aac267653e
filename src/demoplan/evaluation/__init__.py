"""Monte-Carlo evaluation of a task model (``demoplan evaluate``, docs/execution.md
"Evaluation"): seeded scenes (:mod:`.scenes`), one run → one row (:mod:`.runs`),
the runs carried out here or on Ray (:mod:`.engine`), the rows written,
resumed and summed up (:mod:`.results`)."""
