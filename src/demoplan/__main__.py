"""``python -m demoplan``: the same as the ``demoplan`` command."""

from demoplan.launcher import main

main()
