"""The hostile-input suite (issue 14): every command, fed malformed and hostile
files, special files, absurd numbers and options, must answer with one line on
stderr and an exit code of docs/cli.md, quickly, leaving its inputs untouched and
its outputs either as they were or complete."""
