"""``python -m jetgaudin`` runs the command line (same as the ``jetgaudin`` script)."""

from jetgaudin.cli import entry

if __name__ == "__main__":
    entry()
