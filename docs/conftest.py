"""pytest collects the Markdown pages of docs/ as doctests; the site's build machinery (Sphinx configuration, the
CLI-reference extension, the screenshot script) is not library code and needs the ``docs`` extra, which the test
environment does not install: it is built and checked by ``tests/test_docs_site.py`` instead."""

collect_ignore = ["conf.py", "screenshot.py", "_ext"]
