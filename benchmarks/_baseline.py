"""The source of a baseline commit for benchmarks that compare two trees side by side (stdlib only)."""

from __future__ import annotations

import subprocess
from pathlib import Path


def extract_src(root: Path, rev: str, tmp: Path) -> Path:
    """``git archive`` of ``rev``'s ``src`` under ``tmp/base``; returns that ``src`` (for a ``PYTHONPATH``)."""
    base = Path(tmp) / "base"
    base.mkdir()
    archive = subprocess.run(["git", "-C", str(root), "archive", rev, "src"], check=True, capture_output=True).stdout
    subprocess.run(["tar", "x", "-C", str(base)], input=archive, check=True)
    return base / "src"
