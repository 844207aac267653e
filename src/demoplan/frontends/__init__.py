"""What the front ends share (docs/architecture.md, floor 7): the command line
(:mod:`demoplan.cli`) and the studio (:mod:`demoplan.studio`) stop on Ctrl-C
and SIGTERM the same way (:mod:`~demoplan.frontends.interrupts`), and neither
imports the other for it."""
