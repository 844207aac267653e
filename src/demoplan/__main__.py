"""``python -m demoplan``: the same as the ``demoplan`` command."""

from demoplan.cli.launcher import main

main()
