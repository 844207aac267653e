"""What demoplan's files say, checked as they are read: the pose and geometry
schemas that demonstrations, scenes and streams share
(:mod:`~demoplan.documents.poses`), whether their numbers are plausible for
the declared units (:mod:`~demoplan.documents.units`), an object's mass
(:mod:`~demoplan.documents.masses`), and the demonstrations document with its
checks (:mod:`~demoplan.documents.demonstrations`, releases nothing holds up:
:mod:`~demoplan.documents.releases`), which learning and segmentation both
read."""
