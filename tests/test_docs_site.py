"""The documentation site builds strictly (every warning an error) and has what it promises: an index, an API page
naming every public name, the CLI reference generated from the Typer app, and tutorials executed at build time with
embedded PNG figures.  Slow (about 1-2 minutes: the seven tutorials run); needs the `docs` extra."""

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")
    pytest.importorskip("numpydoc")
    pytest.importorskip("pydata_sphinx_theme")
    out = tmp_path_factory.mktemp("site")
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(ROOT / "docs"), str(out)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    yield out
    shutil.rmtree(out, ignore_errors=True)


def test_index_and_pages(site):
    index = (site / "index.html").read_text(encoding="utf-8")
    assert "arXiv:math-ph/0503002" in index
    for page in (
        "foundation",
        "backlund",
        "canonical",
        "closed_forms",
        "errata",
        "performance",
        "reliability",
        "site/getting-started",
        "site/_generated/architecture",
        "site/citing",
    ):
        assert (site / f"{page}.html").is_file(), page


def test_api_page_names_every_public_name(site):
    import jetgaudin as jg

    api = (site / "site" / "_generated" / "api.html").read_text(encoding="utf-8")
    for name in jg.__all__:
        if name != "__version__":
            assert f'id="jetgaudin.{name}"' in api, name
    assert "TwoPointBacklund" in api


def test_api_lists_methods_and_the_public_modules(site):
    api = (site / "site" / "_generated" / "api.html").read_text(encoding="utf-8")
    # classes come with their methods and properties (autodoc members), e.g. the maps' driver methods
    for method in ("TwoPointBacklund.iterate", "TwoPointBacklund.advance", "TwoPointBacklund.prepare_kernels",
                   "ExactFlow.iterate", "GaudinModel.integrals"):
        assert f'id="jetgaudin.{method}"' in api, method
    # the chains' old names are the same classes (issue 33): an entry each, pointing to the one class
    for old, new in (("ChainTwoPointBacklund", "TwoPointBacklund"), ("ChainExactFlow", "ExactFlow")):
        entry = api[api.index(f'id="jetgaudin.{old}"'):][:3000]
        assert "The same class as" in entry and f"#jetgaudin.{new}" in entry, old
    for module in ("jetgaudin.run", "jetgaudin.ensemble", "jetgaudin.ensemble_recording", "jetgaudin.recording",
                   "jetgaudin.plotting"):
        page = (site / "site" / "_generated" / f"{module}.html").read_text(encoding="utf-8")
        assert f'id="module-{module}"' in page, module
    ens = (site / "site" / "_generated" / "jetgaudin.ensemble.html").read_text(encoding="utf-8")
    assert 'id="jetgaudin.ensemble.EnsembleResult.drift_quantiles"' in ens
    assert ">&gt;&gt;&gt;" in (site / "site" / "api.html").read_text(encoding="utf-8")  # the examples


def test_no_page_loads_a_remote_script_and_math_is_served_locally(site):
    """Offline reading: no <script src> and no stylesheet from another host; MathJax from _static/mathjax."""
    remote = re.compile(r'<(?:script|link)\b[^>]*(?:src|href)="(?:https?:)?//[^"]*"', re.IGNORECASE)
    pages = list(site.rglob("*.html"))
    assert len(pages) > 20
    for page in pages:
        html = page.read_text(encoding="utf-8")
        bad = [m for m in remote.findall(html) if "stylesheet" in m or "<script" in m.lower()]
        assert not bad, (page, bad[:3])
    assert (site / "_static" / "mathjax" / "tex-chtml.js").is_file()
    assert (site / "_static" / "mathjax" / "output" / "chtml" / "fonts" / "woff-v2").is_dir()
    for page in ("foundation", "backlund", "tutorials/map-as-flow"):  # typeset math, served from the site
        html = (site / f"{page}.html").read_text(encoding="utf-8")
        assert 'class="math' in html and "_static/mathjax/tex-chtml.js" in html, page


def test_cli_reference_is_generated_from_the_app(site):
    import typer.main

    from jetgaudin.cli import app

    ref = (site / "site" / "cli-reference.html").read_text(encoding="utf-8")
    for name in typer.main.get_command(app).commands:
        assert f"jetgaudin {name}" in ref, name
    assert "--max-points" in ref and "--frames" in ref


@pytest.mark.parametrize(
    "tutorial",
    ["appendix2", "map-as-flow", "branch-rule", "ensembles", "long-runs", "euler-angles", "chains", "xxz", "xyz",
     "physical_tops"],
)
def test_tutorials_are_executed_with_figures(site, tutorial):
    html = (site / "tutorials" / f"{tutorial}.html").read_text(encoding="utf-8")
    images = re.findall(r'<img[^>]+src="([^"]+\.png)"', html)
    assert images, f"{tutorial}: no embedded figure"
    for src in images:
        assert (site / "tutorials" / src).resolve().is_file(), src
    assert "Traceback" not in html
