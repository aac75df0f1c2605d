"""``python -m jetgaudin`` runs the command line (same as the ``jetgaudin`` script)."""

from jetgaudin.cli import main

if __name__ == "__main__":
    main()
