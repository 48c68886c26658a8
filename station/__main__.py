"""``python -m station`` runs the ``calstation`` command."""

from station.cli.main import main

main()
