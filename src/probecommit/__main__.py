"""``python -m probecommit``: the command line."""

from probecommit.cli.app import main

main()
