"""Screenshots of the built site in headless Chromium; exit 1 on an empty page.

Usage (after ``sphinx-build -W --keep-going -b html docs docs/_build/html``)::

    python docs/screenshot.py [--site docs/_build/html] [--out docs/screenshots]

Takes ``index.png``, ``tutorial.png`` (the Appendix 2 tutorial) and ``math.png`` (the foundation page, typeset
formulas) with Debian's ``chromium`` (``apt-get install -y chromium``), offline (no network is used: MathJax is
served by the site itself), giving the page's scripts 10 s of virtual time so that MathJax has typeset before the
shot, and checks each: the HTML page has text and, for the tutorial, embedded PNG figures, for the math page
MathJax from ``_static``; the screenshot is a real image that is not one flat colour (an empty or failed page
renders blank).
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
from pathlib import Path

PAGES = {"index": "index.html", "tutorial": "tutorials/appendix2.html", "math": "foundation.html"}
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--no-first-run",
    "--hide-scrollbars",
    "--window-size=1280,1600",
    "--virtual-time-budget=10000",  # let deferred scripts (MathJax) finish before the screenshot
]


def check_html(path: Path, want_images: bool, want_math: bool = False) -> list[str]:
    """Problems of a built page: missing, almost no text, (for a tutorial) no embedded PNG figure, (for a math
    page) no formula or MathJax not served from the site."""
    if not path.is_file():
        return [f"{path} does not exist (build the site first)"]
    html = path.read_text(encoding="utf-8")
    problems = []
    if len(html) < 2000 or "<h1" not in html:
        problems.append(f"{path} looks empty ({len(html)} bytes, no <h1>)")
    if want_images and ".png" not in html:
        problems.append(f"{path} embeds no PNG figure")
    if want_math and ('class="math' not in html or "_static/mathjax/tex-chtml.js" not in html):
        problems.append(f"{path} has no formula typeset by the site's own MathJax")
    return problems


def check_png(path: Path) -> list[str]:
    """Problems of a screenshot: missing, not a PNG, or a single flat colour (a blank page)."""
    if not path.is_file() or path.read_bytes()[:8] != b"\x89PNG\r\n\x1a\n":
        return [f"{path}: no PNG screenshot was written"]
    from PIL import Image

    with Image.open(path) as im:
        lo_hi = im.convert("L").getextrema()
        colours = len(im.convert("RGB").getcolors(maxcolors=1 << 16) or range(1 << 16))
    if lo_hi[0] == lo_hi[1] or colours < 16:
        return [f"{path}: the page rendered blank ({colours} colours)"]
    return []


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--site", default=str(Path(__file__).resolve().parent / "_build" / "html"))
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "screenshots"))
    ap.add_argument("--chromium", default=shutil.which("chromium") or shutil.which("chromium-browser") or "chromium")
    args = ap.parse_args(argv)
    site, out = Path(args.site).resolve(), Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    problems = []
    for name, page in PAGES.items():
        html = site / page
        problems += check_html(html, want_images=name == "tutorial", want_math=name == "math")
        png = out / f"{name}.png"
        png.unlink(missing_ok=True)
        try:
            subprocess.run(
                [args.chromium, *FLAGS, f"--screenshot={png}", html.as_uri()],
                check=False,
                capture_output=True,
                timeout=120,
            )
        except (OSError, subprocess.TimeoutExpired) as exc:
            problems.append(f"chromium failed: {exc}")
            continue
        problems += check_png(png)
        print(f"{png}")
    for p in problems:
        print(f"screenshot: error: {p}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
